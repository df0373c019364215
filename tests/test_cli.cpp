#include <arpa/inet.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>

#include "../tools/eta.hpp"
#include "cli_runner.hpp"
#include "ftc/sim/isa.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/io/sha256.hpp"
#include "ftc/tune/run/checkpoint.hpp"
#include "short_job.hpp"

using nlohmann::json;
using namespace ftc::testing;

TEST(Cli, SimulateWritesMetricsAndTrajectory) {
  const auto dir = fresh_dir("simulate");
  const CliResult r = run_cli("simulate jobs/table1.json --out '" + dir.string() + "'", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("fitness J ="), std::string::npos) << r.out;

  const json m = json::parse(slurp(dir / "metrics.json"));
  for (const char* key : {"controller", "objective", "fitness", "scenarios"})
    EXPECT_TRUE(m.contains(key)) << key;
  EXPECT_EQ(m["controller"]["type"], "pi_fosmc");
  EXPECT_EQ(m["controller"]["Kp"], 20.0);
  ASSERT_EQ(m["scenarios"].size(), 1u);
  const json& s = m["scenarios"][0];
  for (const char* key : {"name", "ise", "iae", "itae", "max_abs_u", "control_tv",
                          "peak_error_after_fault", "diverged"})
    EXPECT_TRUE(s.contains(key)) << key;
  EXPECT_EQ(s["name"], "paper");
  EXPECT_EQ(s["peak_error_after_fault"].size(), 2u);
  EXPECT_FALSE(s["diverged"].get<bool>());
  EXPECT_GT(s["ise"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(m["fitness"].get<double>(), 1.0 / m["objective"].get<double>());

  std::istringstream csv(slurp(dir / "trajectory.csv"));
  std::string header, line;
  std::getline(csv, header);
  EXPECT_EQ(header, "time,x1,x2,x3,x4,x5,x6,ud1,ud2,ud3,ud4,u1,u2,u3,u4");
  int rows = 0;
  while (std::getline(csv, line)) ++rows;
  EXPECT_EQ(rows, 3000);  // 30 s every 10 ms
}

TEST(Cli, SimulateOtherControllerWithOverrides) {
  const auto dir = fresh_dir("simulate-nftsmc");
  const CliResult r = run_cli(
      "simulate jobs/table1.json --controller nftsmc --set sigma1=12 --set "
      "theta=500 --record-every 0.1 --out '" +
          dir.string() + "'",
      dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json m = json::parse(slurp(dir / "metrics.json"));
  EXPECT_EQ(m["controller"]["type"], "nftsmc");
  EXPECT_EQ(m["controller"]["sigma1"], 12.0);
  EXPECT_EQ(m["controller"]["theta"], 500.0);
  EXPECT_EQ(m["controller"]["sigma2"], 5.0);  // Table 1 default
}

// A recording interval longer than the run keeps its first sample only: 1e16 s / 1 ms
// overflowed llround, and every one of the 30 000 samples was written. Not a finite number of
// seconds: exit 2.
TEST(Cli, SimulateWithARecordingIntervalLongerThanTheRunRecordsOneSample) {
  const auto dir = fresh_dir("simulate-record-every");
  const CliResult r = run_cli(
      "simulate jobs/table1.json --record-every 1e16 --out '" + dir.string() + "'", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string csv = slurp(dir / "trajectory.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 2) << csv.substr(0, 400);  // header, t = 0
  const CliResult inf = run_cli("simulate jobs/table1.json --record-every inf --out '" +
                                    (dir / "inf").string() + "'",
                                dir);
  EXPECT_EQ(inf.exit_code, 2) << inf.err;
  EXPECT_NE(inf.err.find("--record-every: must be a finite number of seconds > 0"),
            std::string::npos)
      << inf.err;
}

TEST(Cli, InvalidJobExitsTwoNamingFileAndPath) {
  const auto dir = fresh_dir("invalid");
  {
    std::ofstream bad(dir / "bad.json");
    bad << R"({"schema": "ftctune.job/1", "name": "bad", "scenarios": [{"name": "s", "duration": 1,
              "sample_time": -1}], "controller": {"type": "fosmc"}})";
  }
  const CliResult r = run_cli("simulate '" + (dir / "bad.json").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("bad.json: /scenarios/0/sample_time: must be > 0"), std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

TEST(Cli, BadOverrideExitsTwo) {
  const auto dir = fresh_dir("badset");
  CliResult r = run_cli("simulate jobs/table1.json --set Kq=3 --out '" + dir.string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--set: Kq: is not a parameter of controller pi_fosmc"), std::string::npos)
      << r.err;
  r = run_cli("simulate jobs/table1.json --set Kp=-1 --out '" + dir.string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("Kp: must be > 0"), std::string::npos) << r.err;
}

TEST(Cli, MissingFileAndUsageErrorsExitTwo) {
  const auto dir = fresh_dir("usage");
  CliResult r = run_cli("simulate no-such-job.json", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("no-such-job.json: cannot open"), std::string::npos) << r.err;
  r = run_cli("frobnicate", dir);
  EXPECT_EQ(r.exit_code, 2);
}

TEST(Cli, QuietFlagAfterSubcommand) {
  const auto dir = fresh_dir("quiet");
  const CliResult r = run_cli("simulate jobs/table1.json -q --out '" + dir.string() + "'", dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "");
  EXPECT_TRUE(std::filesystem::exists(dir / "metrics.json"));
}

TEST(Cli, VersionAndHelp) {
  const auto dir = fresh_dir("version");
  CliResult r = run_cli("--version", dir);
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("ftctune "), std::string::npos);
  r = run_cli("--help", dir);
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("simulate"), std::string::npos);
}

TEST(Cli, RepeatedOptionsMayComeBeforeTheJobPath) {
  const auto dir = fresh_dir("options-first");
  const CliResult r = run_cli(
      "simulate --set Kp=12 --set Ki=3 jobs/table1.json -q --out '" + dir.string() + "'", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json m = json::parse(slurp(dir / "metrics.json"));
  EXPECT_EQ(m["controller"]["Kp"], 12.0);
  EXPECT_EQ(m["controller"]["Ki"], 3.0);
}

TEST(Cli, NearMissNamesGetASuggestion) {
  const auto dir = fresh_dir("did-you-mean");
  CliResult r = run_cli("simulate jobs/table1.json --set kp=3 --out '" + dir.string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("did you mean \"Kp\"?"), std::string::npos) << r.err;
  json j = json::parse(slurp(std::filesystem::path(FTC_SOURCE_DIR) / "jobs" / "table1.json"));
  j["controller"]["swiching_gain"] = 3;
  j["objective"]["metrc"] = "ise";
  std::ofstream(dir / "job.json") << j.dump();
  r = run_cli("validate '" + (dir / "job.json").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("/controller/swiching_gain: unknown key"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("did you mean \"switching_gain\"?"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("did you mean \"metric\"?"), std::string::npos) << r.err;
  // Two equally near names (alpha3: alpha1 or alpha2?) get no guess.
  r = run_cli("simulate jobs/table1.json --set alpha3=0.5 --out '" + dir.string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err.find("did you mean"), std::string::npos) << r.err;
}

TEST(Cli, HelpNamesTheCommandAndEndsWithExamples) {
  const auto dir = fresh_dir("help");
  CliResult r = run_cli("--help", dir);
  EXPECT_NE(r.out.find("Usage: ftctune "), std::string::npos) << r.out;
  for (const char* c :
       {"run", "simulate", "validate", "schema", "report", "landscape", "study", "ensemble",
        "evaluate", "serve", "submit", "status", "fetch", "cancel", "jobs"}) {
    r = run_cli(std::string(c) + " --help", dir);
    EXPECT_NE(r.out.find("Usage: ftctune " + std::string(c)), std::string::npos) << c;
    EXPECT_NE(r.out.find("Examples:\n  ftctune " + std::string(c)), std::string::npos) << c;
    EXPECT_EQ(run_cli(std::string("help ") + c, dir).out, r.out) << c;
  }
  r = run_cli("simulate", dir);  // a usage error points to the command's own help
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("(see ftctune simulate --help)"), std::string::npos) << r.err;
  EXPECT_EQ(run_cli("help nope", dir).exit_code, 2);
}

TEST(Cli, NegativeThreadCountsAreRefusedEverywhere) {
  const auto dir = fresh_dir("threads");
  for (const char* c :
       {"run jobs/table1.json", "landscape jobs/table1.json", "evaluate jobs/robust-faults.json",
        "serve", "study jobs/table1.json --algorithms bat --seeds 1 --budget 20"}) {
    const CliResult r = run_cli(std::string(c) + " --threads -1", dir);
    EXPECT_EQ(r.exit_code, 2) << c;
    EXPECT_NE(r.err.find("--threads: Value -1 not in range 0 to 4096"), std::string::npos)
        << c << ": " << r.err;
  }
}

// Memory by design: a run that would not fit the memory budget (FTCTUNE_MEMORY_MIB here) is
// refused before any work, exit 2, saying how much it would need. Members are generated as they
// are simulated, so it takes 10^6 of them (192 bytes each for 3 bats, the incumbent and 4
// compared controllers) to pass 100 MiB.
TEST(Cli, RunAboveTheMemoryBudgetIsRefusedBeforeTheWork) {
  const auto dir = fresh_dir("memory-budget");
  json j = short_table1_job();
  j["ensemble"] = {{"count", 1000000}, {"seed", 1}};
  ftc::tune::write_file_atomic(dir / "job.json", j.dump());
  ::setenv("FTCTUNE_MEMORY_MIB", "100", 1);
  const CliResult r =
      run_cli("run -q '" + (dir / "job.json").string() + "' --out '" + (dir / "out").string() + "'",
              dir);
  ::unsetenv("FTCTUNE_MEMORY_MIB");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("the job would need about 260 MB of memory (1 listed scenario and its "
                       "comparison at about 1.28 MB, 1000000 ensemble members "
                       "at about 192 bytes each, 9 trials at about 1344 bytes each)"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("more than the budget of 105 MB"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "gains.json"));
  // A landscape takes the budget too: every grid point keeps its outcome (issue 44: 865 MB).
  ftc::tune::write_file_atomic(dir / "table1.json", short_table1_job().dump());
  ::setenv("FTCTUNE_MEMORY_MIB", "100", 1);
  const CliResult l = run_cli("landscape '" + (dir / "table1.json").string() +
                                  "' --grid 1000x1000 --out '" + (dir / "landscape").string() + "'",
                              dir);
  ::unsetenv("FTCTUNE_MEMORY_MIB");
  EXPECT_EQ(l.exit_code, 2) << l.err;
  EXPECT_NE(l.err.find("--grid: a landscape of 1000000 points would need about 1.6 GB of memory, "
                       "more than the budget of 105 MB"),
            std::string::npos)
      << l.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "landscape"));
  // A budget that is not a positive number is bad input, not silently the default.
  for (const char* bad : {"abc", "0", "-5", "12MB"}) {
    ::setenv("FTCTUNE_MEMORY_MIB", bad, 1);
    const CliResult b = run_cli(
        "run -q '" + (dir / "job.json").string() + "' --out '" + (dir / "out").string() + "'", dir);
    ::unsetenv("FTCTUNE_MEMORY_MIB");
    EXPECT_EQ(b.exit_code, 2) << bad << ": " << b.err;
    EXPECT_NE(b.err.find("FTCTUNE_MEMORY_MIB: must be a positive number of MiB (got \"" +
                         std::string(bad) + "\")"),
              std::string::npos)
        << b.err;
  }
}

// A directory kept from an interrupted run (.staging-PID holding a whole run, .previous-PID) is
// never reused or deleted by a later run that gets the same process id (PID 1 in every
// container): the run is exec'd by a shell that first makes both directories under its own pid.
TEST(Cli, RunNeverReusesADirectoryKeptForRecovery) {
  const auto dir = fresh_dir("kept-dirs");
  ftc::tune::write_file_atomic(dir / "job.json", short_table1_job().dump());
  const auto out = dir / "out";
  // A finished run first, so that --force has an earlier run to set aside.
  ASSERT_EQ(run_cli("run -q '" + (dir / "job.json").string() + "' --out '" + out.string() + "'",
                    dir)
                .exit_code,
            0);
  const std::string script = "cd '" + out.string() +
                             "' && mkdir .staging-$$ .previous-$$ && echo kept > .staging-$$/gains.json"
                             " && echo kept > .previous-$$/gains.json && echo $$ > '" +
                             (dir / "pid").string() + "' && exec '" FTC_CLI "' run '" +
                             (dir / "job.json").string() + "' --out '" + out.string() +
                             "' --force 2>'" + (dir / "err").string() + "'";
  const int status = std::system(("sh -c \"" + script + "\"").c_str());
  EXPECT_EQ(status, 0) << slurp(dir / "err");
  const std::string pid = slurp(dir / "pid").substr(0, slurp(dir / "pid").find('\n'));
  for (const char* prefix : {".staging-", ".previous-"}) {
    const auto kept = out / (prefix + pid);
    EXPECT_EQ(slurp(kept / "gains.json"), "kept\n") << kept;
  }
  EXPECT_NE(slurp(out / "gains.json").find("\"schema\": \"ftctune.gains/1\""), std::string::npos);
  EXPECT_NE(slurp(dir / "err").find(".staging-" + pid), std::string::npos) << slurp(dir / "err");
}

// `jobs --prune` takes a finite number of days: NaN passed CLI11's range check and pruned nothing.
TEST(Cli, PruneDaysMustBeAFiniteNumber) {
  const auto dir = fresh_dir("prune-nan");
  for (const char* days : {"nan", "inf", "-1", "1e7", "3x"}) {
    const CliResult r =
        run_cli("jobs --server http://127.0.0.1:9 --prune " + std::string(days), dir);
    EXPECT_EQ(r.exit_code, 2) << days << ": " << r.err;
    EXPECT_NE(r.err.find("--prune: days are a number in 0..1000000"), std::string::npos)
        << days << ": " << r.err;
  }
}

// An IPv6 address is printed in brackets in the server's URL (RFC 3986).
TEST(Cli, ServeOnIpv6PrintsTheAddressInBrackets) {
  const auto dir = fresh_dir("serve-ipv6");
  // Stopped (SIGTERM) once it has said where it listens, or once it has given up.
  std::string script = "cd '" FTC_SOURCE_DIR "'\n'" FTC_CLI "' serve --bind ::1 --port 0 --store '";
  script += (dir / "store").string() + "' >'" + (dir / "out").string() + "' 2>'";
  script += (dir / "err").string() + "' & pid=$!\n";
  script += "for i in $(seq 400); do grep -q listening '" + (dir / "out").string();
  script += "' && break; kill -0 $pid 2>/dev/null || break; sleep 0.05; done\n";
  script += "kill $pid 2>/dev/null; wait $pid\nexit 0\n";
  ftc::tune::write_file_atomic(dir / "serve.sh", script);
  ASSERT_EQ(std::system(("bash '" + (dir / "serve.sh").string() + "'").c_str()), 0);
  if (slurp(dir / "err").find("cannot listen") != std::string::npos)
    GTEST_SKIP() << "no IPv6 loopback here: " << slurp(dir / "err");
  EXPECT_NE(slurp(dir / "out").find("listening on http://[::1]:"), std::string::npos)
      << slurp(dir / "out") << slurp(dir / "err");
}

TEST(Cli, NumberOutOfRangeOrDuplicateKeyInAFileExitsTwo) {
  const auto dir = fresh_dir("strict-json");
  std::string job = slurp(std::filesystem::path(FTC_SOURCE_DIR) / "jobs" / "table1.json");
  const std::string name = "\"name\": \"table1\"";
  ASSERT_NE(job.find(name), std::string::npos);
  std::ofstream(dir / "twice.json")
      << std::string(job).replace(job.find(name), name.size(), name + ", \"name\": \"other\"");
  std::ofstream(dir / "gains.json") << R"({"schema": "ftctune.gains/1", "sample_time": -1e400})";
  json big = json::parse(job);
  big["controller"]["Kp"] = "HERE";
  std::string text = big.dump();
  std::ofstream(dir / "big.json") << text.replace(text.find("\"HERE\""), 6, "1e400");

  CliResult r = run_cli("validate '" + (dir / "big.json").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("/controller/Kp: invalid JSON: number 1e400 is out of the range"),
            std::string::npos)
      << r.err;
  r = run_cli("validate '" + (dir / "twice.json").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("/name: duplicate key"), std::string::npos) << r.err;
  r = run_cli("simulate jobs/table1.json --gains '" + (dir / "gains.json").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("gains.json: /sample_time: invalid JSON: number -1e400"), std::string::npos)
      << r.err;
}

TEST(Cli, SeedMustBeANonNegativeInteger) {
  const auto dir = fresh_dir("seed");
  for (const char* c : {"run jobs/table1.json", "evaluate jobs/robust-faults.json",
                        "ensemble jobs/robust-faults.json"})
    for (const char* seed : {"-1", "1.5", "18446744073709551616", "x"}) {
      const CliResult r = run_cli(std::string(c) + " --seed " + seed, dir);
      EXPECT_EQ(r.exit_code, 2) << c << " --seed " << seed << ": " << r.err;
      EXPECT_NE(r.err.find("--seed: a seed is an integer in 0..18446744073709551615"),
                std::string::npos)
          << r.err;
    }
}

TEST(Cli, SetValueOutOfRangeExitsTwo) {
  const auto dir = fresh_dir("set-range");
  const CliResult r =
      run_cli("simulate jobs/table1.json --set Kp=1e400 --out '" + dir.string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--set: Kp: value \"1e400\" is not a finite number"), std::string::npos)
      << r.err;
}

TEST(Cli, OutputThatCannotBeADirectoryExitsTwoWithTheReason) {
  const auto dir = fresh_dir("out-null");
  std::ofstream(dir / "file") << "x";
  const std::string file = (dir / "file").string();
  for (const std::string c :
       {"run jobs/table1.json --out /dev/null", "simulate jobs/table1.json --out /dev/null",
        "evaluate jobs/robust-faults.json --out /dev/null",
        "study jobs/table1.json --algorithms bat --seeds 1 --budget 20 --out /dev/null"}) {
    const CliResult r = run_cli(c, dir);
    EXPECT_EQ(r.exit_code, 2) << c << ": " << r.err;
    EXPECT_NE(r.err.find("--out: /dev/null exists and is not a directory"), std::string::npos)
        << c << ": " << r.err;
  }
  CliResult r = run_cli("simulate jobs/table1.json --out '" + file + "/sub'", dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(file + " is not a directory"), std::string::npos) << r.err;
  r = run_cli("ensemble jobs/robust-faults.json --count 2 --out '" + dir.string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("is a directory"), std::string::npos) << r.err;
}

// `ensemble --out` replaces only a regular file: a symbolic link (to /dev/full, say) or a FIFO
// is refused before any work, exit 2, and left as it was.
TEST(Cli, EnsembleOutThatIsNotARegularFileIsRefused) {
  const auto dir = fresh_dir("ensemble-out-special");
  std::ofstream(dir / "precious") << "keep";
  std::filesystem::create_symlink(dir / "precious", dir / "link.json");
  ASSERT_EQ(::mkfifo((dir / "fifo.json").c_str(), 0600), 0);
  for (const char* name : {"link.json", "fifo.json"}) {
    const CliResult r = run_cli("ensemble jobs/robust-faults.json --count 2 --out '" +
                                    (dir / name).string() + "'",
                                dir);
    EXPECT_EQ(r.exit_code, 2) << name << ": " << r.err;
    EXPECT_NE(r.err.find((dir / name).string() + " is a"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("only in place of a regular file"), std::string::npos) << r.err;
  }
  EXPECT_TRUE(std::filesystem::is_symlink(dir / "link.json"));
  EXPECT_TRUE(std::filesystem::is_fifo(dir / "fifo.json"));
  EXPECT_EQ(slurp(dir / "precious"), "keep");
}

// A figure is the earlier one or the whole new one: gnuplot failing (exit 1) or leaving a
// truncated PNG with exit 0 (as on a full disk) is exit 2 with one clear line, and the earlier
// figure stays. A stand-in gnuplot on PATH plays both.
TEST(Cli, GnuplotFailureIsAnErrorAndLeavesTheEarlierFigure) {
  const auto dir = fresh_dir("gnuplot-failure");
  const std::string out = (dir / "landscape").string();
  const std::string args = "landscape -q jobs/table1.json --grid 3x3 --out '" + out + "'";
  ASSERT_EQ(run_cli(args, dir).exit_code, 0);
  const std::string before = slurp(dir / "landscape" / "landscape.png");
  ASSERT_GT(before.size(), 100u);
  std::filesystem::create_directories(dir / "bin");
  ftc::tune::write_file_atomic(dir / "bin" / "failing", "#!/bin/sh\necho 'no font' >&2\nexit 1\n");
  ftc::tune::write_file_atomic(
      dir / "bin" / "truncating",
      "#!/bin/sh\nout=$(sed -n \"s/^set output '\\(.*\\)'$/\\1/p\" \"$1\")\n"
      "printf '\\211PNG\\r\\n\\032\\nIHDR' > \"$out\"\nexit 0\n");
  const char* path = std::getenv("PATH");
  const std::string saved = path ? path : "";
  for (const char* kind : {"failing", "truncating"}) {
    std::filesystem::create_directories(dir / kind);
    std::filesystem::copy_file(dir / "bin" / kind, dir / kind / "gnuplot");
    std::filesystem::permissions(dir / kind / "gnuplot", std::filesystem::perms::owner_all);
    ::setenv("PATH", ((dir / kind).string() + ":" + saved).c_str(), 1);
    const CliResult r = run_cli(args + " --force", dir);
    ::setenv("PATH", saved.c_str(), 1);
    EXPECT_EQ(r.exit_code, 2) << kind << ": " << r.err;
    EXPECT_NE(r.err.find(std::string(kind) == "failing" ? "gnuplot failed on" : "incomplete"),
              std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("no figure written"), std::string::npos) << r.err;
    EXPECT_EQ(slurp(dir / "landscape" / "landscape.png"), before) << kind;
    for (const auto& e : std::filesystem::directory_iterator(dir / "landscape"))
      EXPECT_EQ(e.path().string().find("partial"), std::string::npos) << e.path();
  }
}

// landscape: the grid is N1xN2 and nothing else, and --out is checked before the work: a
// directory that cannot be written, or one holding a landscape (--force replaces it).
TEST(Cli, LandscapeChecksItsGridAndOutputBeforeTheWork) {
  const auto dir = fresh_dir("landscape-checks");
  const std::string out = (dir / "l").string();
  for (const char* grid : {"3x3x3", "3x3junk", "2x3.9", "x3", "3x", "3"}) {
    const CliResult r = run_cli(
        "landscape -q jobs/table1.json --grid '" + std::string(grid) + "' --out '" + out + "'",
        dir);
    EXPECT_EQ(r.exit_code, 2) << grid << ": " << r.err;
    EXPECT_NE(r.err.find("--grid: expected N1xN2"), std::string::npos) << grid << ": " << r.err;
  }
  const std::string args = "landscape -q jobs/table1.json --grid 2x2 --out '" + out + "'";
  ASSERT_EQ(run_cli(args, dir).exit_code, 0);
  CliResult r = run_cli(args, dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(out + " already holds a landscape"), std::string::npos) << r.err;
  EXPECT_EQ(run_cli(args + " --force", dir).exit_code, 0);
  std::ofstream(dir / "file") << "x";
  r = run_cli("landscape -q jobs/table1.json --grid 2x2 --out '" + (dir / "file").string() + "'",
              dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--out: " + (dir / "file").string() + " exists and is not a directory"),
            std::string::npos)
      << r.err;
  if (::geteuid() != 0) {  // root writes anywhere
    std::filesystem::create_directory(dir / "ro");
    std::filesystem::permissions(dir / "ro", std::filesystem::perms::owner_read |
                                                 std::filesystem::perms::owner_exec);
    r = run_cli("landscape -q jobs/table1.json --grid 2x2 --out '" + (dir / "ro" / "l").string() +
                    "'",
                dir);
    std::filesystem::permissions(dir / "ro", std::filesystem::perms::owner_all);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("--out: cannot write in " + (dir / "ro").string()), std::string::npos)
        << r.err;
  }
}

// An input that is not a regular file is refused at once: a directory given as the job ("is a
// directory", not "invalid JSON"), a FIFO (which used to hang, waiting for a writer) as the job
// or the checkpoint, a link to /dev/zero (which used to be read up to 2 GB).
TEST(Cli, InputThatIsNotARegularFileIsRefusedWithoutWaiting) {
  const auto dir = fresh_dir("input-special");
  ASSERT_EQ(::mkfifo((dir / "fifo.json").c_str(), 0600), 0);
  std::filesystem::create_symlink("/dev/zero", dir / "zero.json");
  std::filesystem::create_directory(dir / "dir.json");
  const struct {
    const char* name;
    const char* kind;
  } cases[] = {{"dir.json", "is a directory"},
               {"fifo.json", "is a FIFO"},
               {"zero.json", "is a character device"}};
  for (const auto& c : cases) {
    const auto t0 = std::chrono::steady_clock::now();
    const CliResult r = run_cli("validate '" + (dir / c.name).string() + "'", dir);
    EXPECT_EQ(r.exit_code, 2) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find((dir / c.name).string()), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(std::string(c.kind) + ", not a file to read"), std::string::npos)
        << r.err;
    EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(10)) << c.name;
  }
  // A FIFO as the checkpoint of a run to resume.
  std::filesystem::create_directory(dir / "out");
  ASSERT_EQ(::mkfifo((dir / "out" / "checkpoint.json").c_str(), 0600), 0);
  const CliResult r =
      run_cli("run -q --resume jobs/table1.json --out '" + (dir / "out").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("checkpoint.json"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("is a FIFO, not a file to read"), std::string::npos) << r.err;
}

TEST(Cli, ServeOnAPortInUseExitsTwo) {
  const auto dir = fresh_dir("serve-in-use");
  // A listener that shares its port with whoever asks (SO_REUSEPORT), as earlier ftctune
  // servers did: the kernel would split connections between it and a second server.
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  ASSERT_GE(fd, 0);
  int yes = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEPORT, &yes, sizeof yes);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  ASSERT_EQ(::listen(fd, 4), 0);
  socklen_t len = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  const int port = ntohs(a.sin_port);
  // `timeout` ends a server that started anyway, which is then a failure, not a hang.
  const std::string cmd = "cd '" FTC_SOURCE_DIR "' && timeout -s KILL 20 '" FTC_CLI
                          "' serve --port " +
                          std::to_string(port) + " --store '" + (dir / "store").string() + "' >'" +
                          (dir / "out").string() + "' 2>'" + (dir / "err").string() + "'";
  const int status = std::system(cmd.c_str());
  ::close(fd);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2) << slurp(dir / "err");
  EXPECT_NE(slurp(dir / "err").find("127.0.0.1:" + std::to_string(port) + ": address in use"),
            std::string::npos)
      << slurp(dir / "err");
  EXPECT_FALSE(std::filesystem::exists(dir / "store"));  // refused before the store was made
}

// A run whose every candidate diverges writes its files for diagnosis but exits 3 (not 1, an
// internal error), also with --quiet, and its gains file is one the runtime loader refuses.
TEST(Cli, RunWhoseEveryCandidateDivergesExitsThree) {
  const auto dir = fresh_dir("cli-all-diverge");
  json j = short_table1_job();
  // c2 above about 9e4 diverges at 1 ms sampling (see TuningRun.FinishesWhenSomeCandidatesDiverge).
  j["tuning"]["parameters"] = {{"c2", {2e5, 3e5}}};
  ftc::tune::write_file_atomic(dir / "job.json", j.dump(2));
  const CliResult r = run_cli(
      "run -q --out '" + (dir / "out").string() + "' '" + (dir / "job.json").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("every candidate diverged"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("must not be deployed"), std::string::npos) << r.err;
  EXPECT_TRUE(std::filesystem::is_regular_file(dir / "out" / "gains.json"));
  const CliResult sim = run_cli("simulate --gains '" + (dir / "out" / "gains.json").string() +
                                    "' '" + (dir / "job.json").string() + "' -q",
                                dir);
  EXPECT_EQ(sim.exit_code, 2) << sim.err;
}

// A token file others can read is refused before the server starts, as ssh refuses such a key.
TEST(Cli, ServeRefusesATokenFileOthersCanRead) {
  const auto dir = fresh_dir("serve-token-mode");
  const auto token = dir / "token";
  ftc::tune::write_file_atomic(token, "s3cret\n");
  std::filesystem::permissions(
      token,
      std::filesystem::perms::owner_read | std::filesystem::perms::owner_write |
          std::filesystem::perms::group_read | std::filesystem::perms::others_read,
      std::filesystem::perm_options::replace);
  const std::string cmd = "cd '" FTC_SOURCE_DIR "' && timeout -s KILL 20 '" FTC_CLI
                          "' serve --port 0 --token-file '" +
                          token.string() + "' --store '" + (dir / "store").string() +
                          "' >/dev/null 2>'" + (dir / "err").string() + "'";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2) << slurp(dir / "err");
  EXPECT_NE(slurp(dir / "err").find("is accessible by other users (mode 0644); chmod 600"),
            std::string::npos)
      << slurp(dir / "err");
}

// Two runs into one directory would interleave their files: the second is refused while the
// first holds the directory.
TEST(Cli, RunRefusesAnOutputDirectoryAnotherRunIsWriting) {
  const auto dir = fresh_dir("run-locked");
  std::filesystem::create_directories(dir / "out");
  const int fd = ::open((dir / "out").c_str(), O_RDONLY | O_DIRECTORY);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);  // as a running `ftctune run` holds it
  const CliResult r =
      run_cli("run jobs/table1.json -q --out '" + (dir / "out").string() + "'", dir);
  ::close(fd);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("is being written by another ftctune run"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "gains.json"));
}

// A full disk in the middle of writing a run: exit 2 naming the file and the errno, and no
// gains.json, so the half-written directory is never taken for a finished run.
TEST(Cli, RunStoppedByAFullDiskLeavesNoGainsFile) {
  const auto dir = fresh_dir("run-disk-full");
  json j = short_table1_job();
  ftc::tune::write_file_atomic(dir / "job.json", j.dump(2));
  const std::string job = "'" + (dir / "job.json").string() + "'";
  // Step 3 is run.json's rename (written first); step 12 falls among the run's other files.
  for (const char* step : {"3", "12"}) {
    const auto out = dir / (std::string("out-") + step);
    ::setenv("FTCTUNE_FAIL_IO", step, 1);
    const CliResult r = run_cli("run -q " + job + " --out '" + out.string() + "'", dir);
    ::unsetenv("FTCTUNE_FAIL_IO");
    EXPECT_EQ(r.exit_code, 2) << step << ": " << r.err;
    EXPECT_NE(r.err.find("No space left on device"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(out.string()), std::string::npos) << r.err;
    // The files were staged: nothing of the run (no temporary file either) is in its directory.
    for (const auto& e : std::filesystem::recursive_directory_iterator(out))
      ADD_FAILURE() << step << ": left behind " << e.path();
    // Once there is space again, the run goes through.
    const CliResult again = run_cli("run -q " + job + " --out '" + out.string() + "'", dir);
    EXPECT_EQ(again.exit_code, 0) << again.err;
    EXPECT_TRUE(std::filesystem::exists(out / "gains.json"));
  }
}

// A --force run that a full disk stops leaves the run it was to replace whole: never the files
// of two seeds side by side.
TEST(Cli, ForcedRunStoppedByAFullDiskLeavesTheEarlierRunWhole) {
  const auto dir = fresh_dir("run-disk-full-force");
  ftc::tune::write_file_atomic(dir / "job.json", short_table1_job().dump(2));
  const std::string job = "'" + (dir / "job.json").string() + "'";
  const auto out = dir / "out";
  ASSERT_EQ(run_cli("run -q --seed 1 " + job + " --out '" + out.string() + "'", dir).exit_code, 0);
  std::map<std::string, std::string> before;
  for (const auto& e : std::filesystem::recursive_directory_iterator(out))
    if (e.is_regular_file()) before[e.path().string()] = slurp(e.path());
  ::setenv("FTCTUNE_FAIL_IO", "12", 1);
  const CliResult r =
      run_cli("run -q --force --seed 2 " + job + " --out '" + out.string() + "'", dir);
  ::unsetenv("FTCTUNE_FAIL_IO");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  std::map<std::string, std::string> after;
  for (const auto& e : std::filesystem::recursive_directory_iterator(out))
    if (e.is_regular_file()) after[e.path().string()] = slurp(e.path());
  EXPECT_EQ(after, before);
}

namespace {

std::map<std::string, std::string> entries_under(const std::filesystem::path& dir) {
  std::map<std::string, std::string> m;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
    m[e.path().lexically_relative(dir).string()] = e.is_regular_file() ? slurp(e.path()) : "";
  return m;
}

}  // namespace

// --force's move phase: an I/O failure at any of its renames (setting the earlier run aside,
// moving the new one in) undoes the moves made, so the earlier run is whole and alone again.
TEST(Cli, ForcedRunFailingInTheMovePhaseKeepsTheEarlierRun) {
  const auto dir = fresh_dir("run-move-phase");
  ftc::tune::write_file_atomic(dir / "job.json", short_table1_job().dump(2));
  const std::string job = "'" + (dir / "job.json").string() + "'";
  const auto out = dir / "out";
  ASSERT_EQ(run_cli("run -q --seed 1 " + job + " --out '" + out.string() + "'", dir).exit_code, 0);
  const auto before = entries_under(out);
  std::filesystem::copy(out, dir / "pristine", std::filesystem::copy_options::recursive);
  const auto forced = [&](int step) {
    ::setenv("FTCTUNE_FAIL_IO", std::to_string(step).c_str(), 1);
    const CliResult r =
        run_cli("run -q --force --seed 2 " + job + " --out '" + out.string() + "'", dir);
    ::unsetenv("FTCTUNE_FAIL_IO");
    return r;
  };
  // The I/O steps of the whole run: the least step that is never reached, by bisection.
  int lo = 1, hi = 256;  // forced(lo) fails, forced(hi) succeeds
  ASSERT_NE(forced(lo).exit_code, 0);
  while (hi - lo > 1) {
    const int mid = (lo + hi) / 2;
    const CliResult r = forced(mid);
    if (r.exit_code == 0) {
      hi = mid;
      // Back to the earlier run for the next try.
      std::filesystem::remove_all(out);
      std::filesystem::copy(dir / "pristine", out, std::filesystem::copy_options::recursive);
    } else {
      lo = mid;
    }
    ASSERT_EQ(entries_under(out), before) << "step " << mid << ": " << r.err;
  }
  // The last steps are the moves: each entry of the earlier run set aside, each of the new one
  // moved in.
  std::size_t entries = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(out)) ++entries;
  int moves = 0;
  for (int step = lo; step > 0 && moves < static_cast<int>(2 * entries); --step, ++moves) {
    const CliResult r = forced(step);
    EXPECT_EQ(r.exit_code, 2) << step << ": " << r.err;
    EXPECT_NE(r.err.find("cannot move into place: No space left on device"), std::string::npos)
        << step << ": " << r.err;
    EXPECT_EQ(entries_under(out), before) << "step " << step << ": " << r.err;
  }
  EXPECT_EQ(moves, static_cast<int>(2 * entries));
}

// What a run killed in its move phase leaves (the new run's whole files in a staging directory,
// the earlier run set aside) is kept and named by the next run, never deleted; a staging
// directory from a run killed while writing (no gains.json) is removed.
TEST(Cli, RunNamesAndKeepsWhatAnInterruptedMoveLeft) {
  const auto dir = fresh_dir("run-leftovers");
  ftc::tune::write_file_atomic(dir / "job.json", short_table1_job().dump(2));
  const std::string job = "'" + (dir / "job.json").string() + "'";
  const auto out = dir / "out";
  ASSERT_EQ(run_cli("run -q " + job + " --out '" + out.string() + "'", dir).exit_code, 0);
  ftc::tune::write_file_atomic(out / ".staging-999999" / "gains.json", "{}");
  ftc::tune::write_file_atomic(out / ".previous-999999" / "gains.json", "{}");
  ftc::tune::write_file_atomic(out / ".staging-999998" / "run.json", "{}");
  const CliResult r = run_cli("run --force " + job + " --out '" + out.string() + "'", dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find((out / ".staging-999999").string() + " holds the whole files of a run"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find((out / ".previous-999999").string() + " holds the earlier run"),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(std::filesystem::exists(out / ".staging-999999" / "gains.json"));
  EXPECT_TRUE(std::filesystem::exists(out / ".previous-999999" / "gains.json"));
  EXPECT_FALSE(std::filesystem::exists(out / ".staging-999998"));
}

// Standard output that cannot be written (a full disk behind it) is exit 2 with a message, not
// exit 0 with the output lost.
TEST(Cli, WriteErrorOnStandardOutputExitsTwo) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const auto dir = fresh_dir("stdout-full");
  for (const char* c : {"schema job", "ensemble jobs/robust-faults.json --count 3"}) {
    const std::string cmd = "cd '" FTC_SOURCE_DIR "' && '" FTC_CLI "' " + std::string(c) +
                            " >/dev/full 2>'" + (dir / "err").string() + "'";
    const int status = std::system(cmd.c_str());
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 2) << c << ": " << status;
    EXPECT_NE(slurp(dir / "err").find("ftctune: error: cannot write to standard output"),
              std::string::npos)
        << c << ": " << slurp(dir / "err");
  }
}

// --- run checkpoints (--checkpoint, --resume) ---

namespace {

// The short Table 1 job with more iterations, written to `dir`.
std::filesystem::path checkpoint_job(const std::filesystem::path& dir, int iterations) {
  json j = short_table1_job();
  j["tuning"]["algorithm"]["iterations"] = iterations;
  ftc::tune::write_file_atomic(dir / "job.json", j.dump(2));
  return dir / "job.json";
}

// The checkpoint a run of `job` writes after its first iteration, made in process.
std::string first_checkpoint(const std::filesystem::path& job_file, std::uint64_t seed) {
  const ftc::tune::Job job = ftc::tune::load_job(job_file);
  std::string text;
  ftc::tune::RunOptions o;
  o.observer = [&](const ftc::tune::HistoryRow& h, const ftc::tune::Optimizer& opt,
                   const std::vector<ftc::tune::Trial>& trials) {
    text = ftc::tune::checkpoint_text(ftc::tune::canonical_job_sha256(job), seed, h.iteration,
                                      ftc::tune::run_checkpoint(opt, trials));
    return false;  // stop after the first iteration
  };
  tuned(job, 2, seed, o);
  return text;
}

void expect_same_files(const std::filesystem::path& a, const std::filesystem::path& b) {
  for (const char* f : {"gains.json", "trials.csv", "history.csv", "comparison.json"})
    EXPECT_EQ(slurp(a / f), slurp(b / f)) << f;
}

}  // namespace

// SIGKILL in the middle of a checkpointed run, then --resume: the files of an uninterrupted
// run, byte for byte, and no checkpoint left once it has finished.
TEST(Cli, ResumeAfterSigkillWritesTheFilesOfAnUninterruptedRun) {
  const auto dir = fresh_dir("cli-resume-kill");
  const auto job = checkpoint_job(dir, 150);
  const std::string out = (dir / "killed").string();
  const CliResult whole = run_cli(
      "run -q --threads 2 --out '" + (dir / "whole").string() + "' '" + job.string() + "'", dir);
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  // The killed run replaces (--force) a finished run of another seed, whose files, its
  // trajectories/ folder included, are in the way when the resumed run moves its own in.
  ASSERT_EQ(run_cli("run -q --seed 5 --out '" + out + "' '" + job.string() + "'", dir).exit_code,
            0);
  // One thread, so that the run is still going when it is killed; 0.2 s after the first
  // checkpoint (stretched under an emulator) it has written a later one.
  std::string script = "'" FTC_CLI "' run -q --threads 1 --force --checkpoint --out '" + out +
                       "' '" + job.string() + "' & pid=$!\n";
  script += "while [ ! -f '" + out + "/checkpoint.json' ]; do sleep 0.02; done\n";
  script += "sleep " + std::to_string(0.2 * FTC_TEST_SLOWDOWN) + "\n";
  script += "kill -9 $pid\nwait $pid\nexit 0\n";
  ftc::tune::write_file_atomic(dir / "kill.sh", script);
  ASSERT_EQ(std::system(("bash '" + (dir / "kill.sh").string() + "'").c_str()), 0);
  // A finished run removes its checkpoint.
  ASSERT_TRUE(std::filesystem::exists(dir / "killed" / "checkpoint.json"))
      << "finished before the kill";
  const json cp = json::parse(slurp(dir / "killed" / "checkpoint.json"));
  EXPECT_EQ(cp["schema"], "ftctune.checkpoint/1");
  EXPECT_GE(cp["iteration"].get<int>(), 1);

  // Without --resume (or --force) the interrupted run is not written over.
  const CliResult again = run_cli("run -q --out '" + out + "' '" + job.string() + "'", dir);
  EXPECT_EQ(again.exit_code, 2);
  EXPECT_NE(again.err.find("holds an interrupted run (checkpoint.json); pass --resume"),
            std::string::npos)
      << again.err;

  const CliResult resumed =
      run_cli("run --threads 2 --resume --out '" + out + "' '" + job.string() + "'", dir);
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_NE(resumed.err.find("resuming from"), std::string::npos) << resumed.err;
  expect_same_files(dir / "whole", dir / "killed");
  EXPECT_FALSE(std::filesystem::exists(dir / "killed" / "checkpoint.json"));
}

// A checkpoint that is damaged, of another job or of another seed is refused with the reason
// (exit 2), never silently taken for a fresh start; a sound one resumes to the same files.
TEST(Cli, ResumeRefusesADamagedOrForeignCheckpoint) {
  const auto dir = fresh_dir("cli-resume-refuse");
  const auto job = checkpoint_job(dir, 3);
  const std::uint64_t seed = ftc::tune::load_job(job).tuning->seed;
  const std::string good = first_checkpoint(job, seed);
  const auto resume = [&](const std::string& name, const std::string& text,
                          const std::string& extra = "") {
    const auto out = dir / name;
    std::filesystem::create_directories(out);
    ftc::tune::write_file_atomic(out / "checkpoint.json", text);
    return run_cli("run -q --resume --out '" + out.string() + "' '" + job.string() + "'" + extra,
                   dir);
  };

  json tampered = json::parse(good);
  ASSERT_GE(tampered["state"]["trials"].size(), 2u);
  tampered["state"]["trials"][0] = tampered["state"]["trials"][1];
  CliResult r = resume("tampered", tampered.dump());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("the checkpoint is damaged (its state does not match its digest)"),
            std::string::npos)
      << r.err;

  r = resume("truncated", good.substr(0, good.size() / 2));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("the checkpoint is damaged (not valid JSON)"), std::string::npos) << r.err;

  r = resume("not-a-checkpoint", R"({"schema": "ftctune.gains/1"})");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("is not an ftctune checkpoint"), std::string::npos) << r.err;

  json other = json::parse(good);
  other["job_sha256"] = std::string(64, 'a');
  r = resume("other-job", other.dump());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("was written by a run of another job"), std::string::npos) << r.err;

  r = resume("other-seed", good, " --seed " + std::to_string(seed + 1));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("was written by a run with seed " + std::to_string(seed)), std::string::npos)
      << r.err;
  for (const char* d : {"tampered", "truncated", "other-job", "other-seed"})
    EXPECT_FALSE(std::filesystem::exists(dir / d / "gains.json")) << d;

  r = resume("sound", good);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CliResult whole =
      run_cli("run -q --out '" + (dir / "whole").string() + "' '" + job.string() + "'", dir);
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  expect_same_files(dir / "whole", dir / "sound");
}

// A forged checkpoint, its state_sha256 recomputed as a forger would, is refused with exit 2,
// the checkpoint file and the field's path; it used to crash (t beyond the run) or be taken
// (t = -1, evaluations 1e18, wrong-length points, a garbage engine state).
TEST(Cli, ResumeRefusesAForgedCheckpointNamingTheFileAndField) {
  const auto dir = fresh_dir("cli-resume-forged");
  const auto job = checkpoint_job(dir, 3);
  const std::uint64_t seed = ftc::tune::load_job(job).tuning->seed;
  const json good = json::parse(first_checkpoint(job, seed));
  int n = 0;
  const auto forged = [&](const std::function<void(json&)>& forge, const std::string& path) {
    json cp = good;
    forge(cp["state"]["optimizer"]);
    cp["state_sha256"] = ftc::tune::sha256_hex(cp["state"].dump());
    const auto out = dir / ("forged-" + std::to_string(n++));
    std::filesystem::create_directories(out);
    ftc::tune::write_file_atomic(out / "checkpoint.json", cp.dump());
    const CliResult r =
        run_cli("run -q --resume --out '" + out.string() + "' '" + job.string() + "'", dir);
    EXPECT_EQ(r.exit_code, 2) << path << "\n" << r.err;
    EXPECT_NE(r.err.find((out / "checkpoint.json").string()), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(path + ":"), std::string::npos) << path << "\n" << r.err;
    EXPECT_FALSE(std::filesystem::exists(out / "gains.json")) << path;
  };
  for (const json& t : {json(4), json(61), json(100), json(1e9), json(-1)})
    forged([&](json& o) { o["t"] = t; }, "/state/optimizer/t");
  forged([](json& o) { o["evaluations"] = 1e18; }, "/state/optimizer/evaluations");
  forged([](json& o) { o["bats"][0]["x"].push_back(1.0); }, "/state/optimizer/bats/0/x");
  forged([](json& o) { o["best"].erase(0); }, "/state/optimizer/best");
  forged([](json& o) { o["rng"] = "0 1 2 garbage"; }, "/state/optimizer/rng");
}

namespace {

// Runs the CLI with FTCTUNE_ISA set to `isa` (the child inherits the environment).
CliResult run_cli_with_isa(const std::string& isa, const std::string& args,
                           const std::filesystem::path& scratch) {
  ::setenv("FTCTUNE_ISA", isa.c_str(), 1);
  CliResult r = run_cli(args, scratch);
  ::unsetenv("FTCTUNE_ISA");
  return r;
}

}  // namespace

// The gains file does not depend on the instruction set the simulations ran on: every lane
// gives the scalar code's bits (tests/test_batch_kernel.cpp), so the tuning takes the same path.
// Nor on the CPU: the tuned gains and each iteration's best fitness are the ones `ftctune run`
// wrote on x86-64 and, under qemu, on aarch64 (tools/test --aarch64) on 2026-11-25.
TEST(Cli, GainsAreTheSameBytesUnderEveryInstructionSet) {
  struct Recorded {
    double Kp, Ki;
    std::vector<double> best_fitness;
  };
  const std::map<std::string, Recorded> recorded = {
      {"jobs/table1.json",
       {1.2813446875159336,
        50.0,
        {0.7503333271579694, 0.7507799421830366, 0.7507807356486825, 0.7507807356486825,
         0.7507807356486825, 0.7507807356486825, 0.7507807356486825, 0.7507807356486825,
         0.7507807356486825, 0.7507807356486825, 0.7507807356486825}}},
      {"jobs/table1-adaptive.json",
       {1.0,
        42.54125471239895,
        {0.7503280382217092, 0.7507799213756619, 0.7507807352160112, 0.7507808846985218,
         0.7507808846985218, 0.7507808846985218, 0.7507809172601402, 0.7507809172601402,
         0.7507809172601402, 0.750781061252312, 0.750781061252312}}}};
  const auto dir = fresh_dir("cli-isa");
  for (const std::string job : {"jobs/table1.json", "jobs/table1-adaptive.json"}) {
    std::string scalar;
    for (const ftc::sim::Isa isa : ftc::sim::supported_isas()) {
      const std::string name = ftc::sim::to_string(isa);
      const auto out = dir / (name + std::to_string(job.size()));
      const CliResult r =
          run_cli_with_isa(name, "run -q " + job + " --out '" + out.string() + "'", dir);
      ASSERT_EQ(r.exit_code, 0) << name << ": " << r.err;
      const std::string gains = slurp(out / "gains.json");
      ASSERT_FALSE(gains.empty());
      if (isa == ftc::sim::Isa::scalar) {
        scalar = gains;
        const nlohmann::json g = nlohmann::json::parse(gains);
        const Recorded& want = recorded.at(job);
        EXPECT_EQ(g["tuned"]["Kp"].get<double>(), want.Kp) << job;
        EXPECT_EQ(g["tuned"]["Ki"].get<double>(), want.Ki) << job;
        std::vector<double> best;
        for (const auto& h : g["history"]) best.push_back(h["best_fitness"].get<double>());
        EXPECT_EQ(best, want.best_fitness) << job;
      } else
        EXPECT_EQ(gains, scalar) << job << ": gains.json under FTCTUNE_ISA=" << name
                                 << " differs from the scalar one";
    }
  }
}

// The shipped vehicle jobs (SPEC §17: a full tensor with Euler kinematics and per-wheel limits;
// a quad_x multirotor) tune to the same gains.json under every instruction set and on 1 or 2
// threads, and their plants are what the jobs say.
TEST(Cli, VehicleJobsGiveTheSameBytesUnderEveryInstructionSetAndThreadCount) {
  const auto dir = fresh_dir("cli-vehicles");
  for (const std::string job : {"jobs/smallsat-pyramid.json", "jobs/quad-x.json"}) {
    std::string first;
    for (const ftc::sim::Isa isa : ftc::sim::supported_isas())
      for (const char* threads : {"1", "2"}) {
        const std::string name = ftc::sim::to_string(isa);
        const auto out = dir / (name + threads + std::to_string(job.size()));
        const CliResult r = run_cli_with_isa(
            name, "run -q " + job + " --threads " + threads + " --out '" + out.string() + "'", dir);
        ASSERT_EQ(r.exit_code, 0) << job << " " << name << ": " << r.err;
        const std::string gains = slurp(out / "gains.json");
        ASSERT_FALSE(gains.empty());
        if (first.empty()) {
          first = gains;
          const nlohmann::json g = nlohmann::json::parse(gains);
          EXPECT_EQ(g["plant"]["model"], job == "jobs/quad-x.json" ? "multirotor" : "rigid_body");
        } else {
          EXPECT_EQ(gains, first) << job << ": gains.json under FTCTUNE_ISA=" << name << ", "
                                  << threads << " threads";
        }
      }
  }
}

TEST(Cli, UnknownInstructionSetExitsTwoAndVersionNamesTheOneInUse) {
  const auto dir = fresh_dir("cli-isa-bad");
  const CliResult bad = run_cli_with_isa("avx1024", "validate jobs/table1.json", dir);
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("FTCTUNE_ISA"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("scalar, sse2, avx2, avx512"), std::string::npos) << bad.err;
  EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
  // Every instruction set the CPU and the build have can be chosen; one they lack is refused by
  // name (on aarch64 only scalar is built).
  const std::vector<ftc::sim::Isa> supported = ftc::sim::supported_isas();
  for (ftc::sim::Isa isa :
       {ftc::sim::Isa::scalar, ftc::sim::Isa::sse2, ftc::sim::Isa::avx2, ftc::sim::Isa::avx512}) {
    const std::string name = ftc::sim::to_string(isa);
    const CliResult v = run_cli_with_isa(name, "--version", dir);
    if (std::find(supported.begin(), supported.end(), isa) != supported.end()) {
      EXPECT_EQ(v.exit_code, 0) << name << ": " << v.err;
      EXPECT_NE(v.out.find("simulation lanes: " + name + " (" +
                           std::to_string(ftc::sim::lane_width(isa)) + " per core"),
                std::string::npos)
          << v.out;
    } else {
      EXPECT_EQ(v.exit_code, 2) << name;
      EXPECT_NE(
          v.err.find("is \"" + name + "\", which this CPU or build cannot run (it can: scalar"),
          std::string::npos)
          << v.err;
    }
  }
  const CliResult d = run_cli("--version", dir);
  EXPECT_NE(d.out.find(std::string("simulation lanes: ") +
                       ftc::sim::to_string(ftc::sim::supported_isas().back())),
            std::string::npos)
      << d.out;
}

// `simulate --gains` runs the tuned controller alone, in scalar code; the tuning ran it in SIMD
// lanes beside other candidates. The objective is the same double.
TEST(Cli, SimulateWithTheGainsReproducesTheTunedObjectiveExactly) {
  const auto dir = fresh_dir("cli-replay");
  for (const std::string job : {"jobs/table1.json", "jobs/table1-adaptive.json"}) {
    const auto out = dir / ("run" + std::to_string(job.size()));
    ASSERT_EQ(run_cli("run -q " + job + " --out '" + out.string() + "'", dir).exit_code, 0);
    const json gains = json::parse(slurp(out / "gains.json"));
    const auto sim = dir / ("sim" + std::to_string(job.size()));
    const CliResult r =
        run_cli("simulate -q " + job + " --gains '" + (out / "gains.json").string() + "' --out '" +
                    sim.string() + "'",
                dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const json metrics = json::parse(slurp(sim / "metrics.json"));
    EXPECT_EQ(metrics["objective"].get<double>(), gains["objective"]["value"].get<double>()) << job;
    EXPECT_EQ(metrics["fitness"].get<double>(), gains["fitness"].get<double>()) << job;
  }
}

// `status` shows a running job's ETA from the server's own times, at the rate so far.
TEST(Cli, StatusShowsTheEtaOfARunningJob) {
  json j = {{"status", "running"},
            {"started_at", "2026-11-23T14:00:00.000Z"},
            {"updated_at", "2026-11-23T14:00:30.500Z"},
            {"progress", {{"evaluations", 25}, {"total_evaluations", 100}}}};
  EXPECT_EQ(ftc::cli::eta_text(j), "  ETA 1.5 min");  // 30.5 s for 25: 91.5 s for 75
  j["progress"]["evaluations"] = 50;
  EXPECT_EQ(ftc::cli::eta_text(j), "  ETA 30 s");
  j["started_at"] = "2026-11-23T10:00:00.000Z";
  EXPECT_EQ(ftc::cli::eta_text(j), "  ETA 4.0 h");
  j["progress"]["evaluations"] = 0;  // no rate yet
  EXPECT_EQ(ftc::cli::eta_text(j), "");
  j["progress"]["evaluations"] = 50;
  j["status"] = "succeeded";
  EXPECT_EQ(ftc::cli::eta_text(j), "");
  j["status"] = "running";
  j["started_at"] = nullptr;  // queued only
  EXPECT_EQ(ftc::cli::eta_text(j), "");
  // Past its last iteration: what it is doing, not an ETA of 0.
  j["progress"]["phase"] = "finishing";
  EXPECT_EQ(ftc::cli::eta_text(j), "  comparing controllers and measuring the noise floor");
}
