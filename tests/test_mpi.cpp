// The MPI evaluator end to end: `mpirun -np N ftctune ...` against a plain run, a worker rank
// that hangs or dies, and the service under mpirun. mpirun refuses to start as root unless told;
// the tests tell it in the command they run, never in the environment of the user.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli_runner.hpp"
#include "goal_job.hpp"
#include "short_job.hpp"

extern char** environ;

namespace {

namespace fs = std::filesystem;
using ftc::testing::fresh_dir;
using ftc::testing::run_cli;
using ftc::testing::slurp;
using nlohmann::json;
using namespace std::chrono_literals;

#ifndef FTC_WITH_MPI
#define REQUIRE_MPI() GTEST_SKIP() << "ftctune was built without MPI"
#else
#define REQUIRE_MPI() (void)0
#endif

const std::string kAsRoot = "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 ";

// Under `tools/test --sanitize`, the ranks run without LeakSanitizer: Open MPI leaves its
// components' allocations behind at MPI_Finalize, in libraries it has already unloaded, so
// the reports cannot even be attributed, let alone suppressed. The same code paths are checked
// for leaks by the tests that run without mpirun. Empty outside a sanitizer run.
std::string no_leak_check() {
  const char* asan = std::getenv("ASAN_OPTIONS");
  return asan ? std::string("ASAN_OPTIONS=") + asan + ":detect_leaks=0" : std::string();
}

// `mpirun -np N ftctune ARGS`, from the source directory; --oversubscribe lets 3 ranks share 2
// cores, --bind-to none lets each rank's threads use every core.
ftc::testing::CliResult mpirun_cli(int ranks, const std::string& args, const fs::path& scratch,
                                   const std::string& env = "") {
  const auto out = scratch / "stdout.txt", err = scratch / "stderr.txt";
  const std::string cmd = "cd '" FTC_SOURCE_DIR "' && " + kAsRoot + no_leak_check() + " " + env +
                          " mpirun -np " + std::to_string(ranks) +
                          " --oversubscribe --bind-to none '" FTC_CLI "' " + args + " >'" +
                          out.string() + "' 2>'" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  ftc::testing::CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

fs::path write_job(const fs::path& dir, const json& j) {
  const fs::path p = dir / "job.json";
  std::ofstream(p) << j.dump(2);
  return p;
}

// The run files that must not depend on how the simulations were spread.
void expect_same_run(const fs::path& a, const fs::path& b) {
  for (const char* f : {"gains.json", "trials.csv", "history.csv", "comparison.json"}) {
    ASSERT_TRUE(fs::exists(a / f)) << a / f;
    ASSERT_TRUE(fs::exists(b / f)) << b / f;
    EXPECT_EQ(slurp(a / f), slurp(b / f)) << f;
  }
}

// Runs `job` (with the options `args`) in one process and on 3 ranks of `threads` threads each,
// into dir/plain and dir/three, and expects the same run files.
void expect_three_ranks_run_as_one_process(const fs::path& dir, const fs::path& job, int threads,
                                           const std::string& args = "") {
  const auto plain = run_cli(
      "run '" + job.string() + "' -q " + args + " --out '" + (dir / "plain").string() + "'", dir);
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  const auto three =
      mpirun_cli(3,
                 "run '" + job.string() + "' -q " + args + " --threads " + std::to_string(threads) +
                     " --out '" + (dir / "three").string() + "'",
                 dir);
  ASSERT_EQ(three.exit_code, 0) << three.err;
  expect_same_run(dir / "plain", dir / "three");
}

TEST(Mpi, GainsAreByteIdenticalForOneProcessOneRankAndThreeRanks) {
  REQUIRE_MPI();
  const fs::path dir = fresh_dir("mpi-same");
  const auto plain =
      run_cli("run jobs/table1.json -q --threads 2 --out '" + (dir / "plain").string() + "'", dir);
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  const auto one = mpirun_cli(
      1, "run jobs/table1.json -q --threads 1 --out '" + (dir / "one").string() + "'", dir);
  ASSERT_EQ(one.exit_code, 0) << one.err;
  const auto three = mpirun_cli(
      3, "run jobs/table1.json -q --threads 1 --out '" + (dir / "three").string() + "'", dir);
  ASSERT_EQ(three.exit_code, 0) << three.err;
  expect_same_run(dir / "plain", dir / "one");
  expect_same_run(dir / "plain", dir / "three");
  // run.json says how it ran.
  const json run = json::parse(slurp(dir / "three" / "run.json"));
  EXPECT_EQ(run["evaluator"], "mpi");
  EXPECT_EQ(run["ranks"], 3);
  EXPECT_EQ(run["threads_per_rank"], json::array({1, 1, 1}));
  EXPECT_EQ(run["threads"], 3);
}

// The scenario's actuator model travels with the scenarios rank 0 sends (their JSON): three
// ranks give the files of a plain run, which differ from those of the job without the model.
TEST(Mpi, ActuatorModelReachesEveryRank) {
  REQUIRE_MPI();
  const fs::path dir = fresh_dir("mpi-actuator");
  const auto plain = run_cli(
      "run jobs/post-fault-actuator.json -q --threads 2 --out '" + (dir / "plain").string() + "'",
      dir);
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  const auto three = mpirun_cli(
      3,
      "run jobs/post-fault-actuator.json -q --threads 1 --out '" + (dir / "three").string() + "'",
      dir);
  ASSERT_EQ(three.exit_code, 0) << three.err;
  expect_same_run(dir / "plain", dir / "three");
  const auto ideal = run_cli(
      "run jobs/post-fault.json -q --threads 2 --out '" + (dir / "ideal").string() + "'", dir);
  ASSERT_EQ(ideal.exit_code, 0) << ideal.err;
  EXPECT_NE(slurp(dir / "ideal" / "history.csv"), slurp(dir / "three" / "history.csv"));
}

// Sensor noise (SPEC §18) is each scenario's own stream, resolved from the job (the seed and the
// scenario's index, which its JSON does not carry): every rank draws what rank 0 would, for a
// second listed scenario as for the first and for ensemble members.
TEST(Mpi, SensorNoiseIsTheSameOnEveryRank) {
  REQUIRE_MPI();
  const fs::path dir = fresh_dir("mpi-sensors");
  json j = ftc::testing::short_ensemble_job();
  j["scenarios"][0]["sensors"] = {{"rate", {{"noise", 1e-3}, {"bias_walk", 1e-4}}},
                                  {"delay", 1},
                                  {"acceleration", {{"source", "differentiated"}}}};
  json second = j["scenarios"][0];
  second["name"] = "second";
  j["scenarios"].push_back(second);
  j["ensemble"]["sensors"] = {{"angle_noise", {{"uniform", {0, 2e-4}}}}};
  ASSERT_NO_FATAL_FAILURE(expect_three_ranks_run_as_one_process(dir, write_job(dir, j), 1));
  EXPECT_NE(slurp(dir / "three" / "gains.json").find("sensor_seeds"), std::string::npos);
}

// A plugin plant (examples/plant-plugin): every rank loads it from its plant search path, and
// a rank whose library is not rank 0's (another build of the same name) ends the job with a
// message instead of simulating another plant.
TEST(Mpi, PluginPlantRunsAsOneProcessAndEveryRankChecksItsLibrary) {
  REQUIRE_MPI();
  const fs::path dir = fresh_dir("mpi-plugin");
  const fs::path job = fs::path(FTC_SOURCE_DIR) / "examples/plant-plugin/job.json";
  ASSERT_NO_FATAL_FAILURE(
      expect_three_ranks_run_as_one_process(dir, job, 1, "--plant-path '" FTC_PLUGIN_DIR "'"));
  // Ranks 1 and 2 find a copy with one byte more at its end: it loads, but it is not the same.
  const std::string lib = "ftctune_plant_reaction_wheel_pendulum.so";
  fs::create_directories(dir / "other");
  fs::copy_file(fs::path(FTC_PLUGIN_DIR) / lib, dir / "other" / lib);
  std::ofstream(dir / "other" / lib, std::ios::app | std::ios::binary) << '\0';
  const std::string cmd =
      "cd '" FTC_SOURCE_DIR "' && " + kAsRoot + no_leak_check() +
      " mpirun -np 3 --oversubscribe --bind-to none sh -c 'if [ \"$OMPI_COMM_WORLD_RANK\" = 0 ]; "
      "then d=" FTC_PLUGIN_DIR "; else d=" +
      (dir / "other").string() + "; fi; exec " FTC_CLI " run " + job.string() +
      " -q --threads 1 --plant-path $d --out " + (dir / "mixed").string() + "' >'" +
      (dir / "out.txt").string() + "' 2>'" + (dir / "err.txt").string() + "'";
  const int status = std::system(cmd.c_str());
  EXPECT_NE(status, 0);
  const std::string err = slurp(dir / "err.txt");
  EXPECT_NE(err.find("plugin:reaction_wheel_pendulum here is not rank 0's"), std::string::npos)
      << err;
  EXPECT_FALSE(fs::exists(dir / "mixed" / "gains.json"));
}

TEST(Mpi, FrontIsByteIdenticalForAPlainRunAndThreeRanks) {
  REQUIRE_MPI();
  // Two soft goals (the Pareto Bat algorithm), 4 bats x 2 iterations on the short Table 1 job.
  const fs::path dir = fresh_dir("mpi-front");
  json j = ftc::testing::short_table1_job();
  j["name"] = "front-mpi";
  j.erase("objective");
  j["goals"] = {{{"metric", "ise"}, {"window", {0, 5}}, {"minimize", true}},
                {{"metric", "control_tv"}, {"minimize", true}}};
  j["tuning"]["algorithm"]["population"] = 4;
  const fs::path job = write_job(dir, j);
  const auto plain = run_cli(
      "run '" + job.string() + "' -q --threads 2 --out '" + (dir / "plain").string() + "'", dir);
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  const auto three = mpirun_cli(
      3, "run '" + job.string() + "' -q --threads 1 --out '" + (dir / "three").string() + "'",
      dir);
  ASSERT_EQ(three.exit_code, 0) << three.err;
  expect_same_run(dir / "plain", dir / "three");
  for (const char* f : {"front.json", "front.csv"}) {
    ASSERT_TRUE(fs::exists(dir / "plain" / f)) << f;
    EXPECT_EQ(slurp(dir / "plain" / f), slurp(dir / "three" / f)) << f;
  }
}

// The job j run in dir/plain, with --no-capping in dir/off and on three ranks in dir/three; plain
// and three hold the same files. False when a run failed.
bool run_plain_uncapped_and_on_three_ranks(const fs::path& dir, const json& j) {
  const std::string job = "run '" + write_job(dir, j).string() + "' -q ";
  const auto out = [&](const char* name) { return "--out '" + (dir / name).string() + "'"; };
  for (const std::string& args : {job + out("plain"), job + "--no-capping " + out("off")}) {
    const auto r = run_cli(args, dir);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    if (r.exit_code != 0) return false;
  }
  const auto three = mpirun_cli(3, job + "--threads 1 " + out("three"), dir);
  EXPECT_EQ(three.exit_code, 0) << three.err;
  if (three.exit_code != 0) return false;
  expect_same_run(dir / "plain", dir / "three");
  return true;
}

// Capping with goals (issue 27): a job of one soft goal and hard goals on the short ensemble,
// capped plain and under three ranks, writes the same files, trials.csv (where each candidate
// stopped, the bounds of its goals) included; with --no-capping the same gains and history.
TEST(Mpi, CappedGoalJobIsByteIdenticalToAPlainRun) {
  REQUIRE_MPI();
  const fs::path dir = fresh_dir("mpi-goals");
  json j = ftc::testing::goal_ensemble_job(1000, 30, false);
  j["tuning"]["algorithm"]["population"] = 4;
  j["tuning"]["algorithm"]["iterations"] = 3;
  ASSERT_TRUE(run_plain_uncapped_and_on_three_ranks(dir, j));
  for (const char* f : {"gains.json", "history.csv"})
    EXPECT_EQ(slurp(dir / "plain" / f), slurp(dir / "off" / f)) << f;
  // A capped row stopped on its limits: capped 1, under 12 members, cached 0, feasible 0.
  EXPECT_TRUE(std::regex_search(slurp(dir / "three" / "trials.csv"),
                                std::regex(",1,([0-9]|1[01]),0,[^,\n]+,[^,\n]+,[^,\n]+,[^,\n]+,0\n")))
      << "no trial capped on its limits: the comparison proves less";
}

// Capping a front (issue 42): the Pareto Bat's candidates stop on the same rounds under three
// ranks, and front.json, front.csv and every other file are the plain run's, and without
// capping the same gains, history and front.
TEST(Mpi, CappedFrontJobIsByteIdenticalToAPlainRun) {
  REQUIRE_MPI();
  const fs::path dir = fresh_dir("mpi-front");
  json j = ftc::testing::front_ensemble_job();
  j["tuning"]["algorithm"] = {{"type", "bat"}, {"population", 6}, {"iterations", 3}};
  ASSERT_TRUE(run_plain_uncapped_and_on_three_ranks(dir, j));
  for (const char* f : {"gains.json", "history.csv", "front.json", "front.csv"}) {
    EXPECT_EQ(slurp(dir / "plain" / f), slurp(dir / "three" / f)) << f;
    EXPECT_EQ(slurp(dir / "plain" / f), slurp(dir / "off" / f)) << f;
  }
  // A capped row, read by its columns: capped 1, under 12 members simulated, not cached.
  std::istringstream csv(slurp(dir / "three" / "trials.csv"));
  std::string line;
  std::getline(csv, line);
  const auto cells = [](const std::string& l) {
    std::vector<std::string> c;
    std::istringstream in(l);
    for (std::string x; std::getline(in, x, ',');) c.push_back(x);
    return c;
  };
  const std::vector<std::string> head = cells(line);
  const auto column = [&](const char* name) {
    return static_cast<std::size_t>(std::find(head.begin(), head.end(), name) - head.begin());
  };
  const std::size_t capped = column("capped"), simulated = column("simulated"),
                    cached = column("cached");
  ASSERT_LT(cached, head.size()) << line;
  int stopped = 0;
  while (std::getline(csv, line)) {
    const std::vector<std::string> c = cells(line);
    if (c.size() > cached && c[capped] == "1" && c[cached] == "0" && std::stoi(c[simulated]) < 12)
      ++stopped;
  }
  EXPECT_GT(stopped, 0) << "no trial capped: the comparison proves less";
}

TEST(Mpi, EnsembleGainsAreByteIdenticalToAPlainRun) {
  REQUIRE_MPI();
  const fs::path dir = fresh_dir("mpi-ensemble");
  // With the job's metric settings, which the ranks get in each scenario's options: the
  // settling times and steady-state errors in comparison.json and evaluation.csv must agree.
  json j = ftc::testing::short_ensemble_job();
  j["metrics"] = {{"settling_threshold", 0.01}, {"steady_state_tail", 1.0}};
  // Enough members and iterations for capping (issue 27) to stop candidates: the coordinator
  // decides from results by task index, so trials.csv (where each one stopped) is the same.
  j["ensemble"]["count"] = 11;
  j["tuning"]["algorithm"]["population"] = 4;
  j["tuning"]["algorithm"]["iterations"] = 3;
  const fs::path job = write_job(dir, j);
  ASSERT_NO_FATAL_FAILURE(expect_three_ranks_run_as_one_process(dir, job, 2));
  // A capped row: accepted 0, capped 1, fewer than the 12 scenarios simulated, cached 0.
  EXPECT_TRUE(
      std::regex_search(slurp(dir / "three" / "trials.csv"), std::regex(",0,1,([0-9]|1[01]),0\n")))
      << "no capped trial: the comparison proves less";
  // Out-of-sample evaluation spreads its slices over the ranks as well.
  const auto e_plain = run_cli("evaluate '" + job.string() + "' -q --gains '" +
                                   (dir / "plain" / "gains.json").string() +
                                   "' --no-figure --out '" + (dir / "eval-plain").string() + "'",
                               dir);
  ASSERT_EQ(e_plain.exit_code, 0) << e_plain.err;
  const auto e_three = mpirun_cli(3,
                                  "evaluate '" + job.string() + "' -q --gains '" +
                                      (dir / "plain" / "gains.json").string() +
                                      "' --no-figure --out '" + (dir / "eval-three").string() + "'",
                                  dir);
  ASSERT_EQ(e_three.exit_code, 0) << e_three.err;
  const std::string csv = slurp(dir / "eval-plain" / "evaluation.csv");
  EXPECT_EQ(csv, slurp(dir / "eval-three" / "evaluation.csv"));
  // The settings took effect on the ranks: members have settling times and steady-state errors
  // (without them both are NaN, written as null).
  const json ev = json::parse(slurp(dir / "eval-three" / "evaluation.json"));
  int settled = 0, tails = 0;
  for (const json& c : ev["controllers"])
    for (const json& m : c["members"]) {
      settled += m["settling_time"].is_number() ? 1 : 0;
      tails += m["steady_state_error"].is_number() ? 1 : 0;
    }
  EXPECT_GT(settled, 0);
  EXPECT_GT(tails, 0);
}

// mpirun with a long run in the background; finds the process of a given rank by its
// environment.
class MpiRun {
 public:
  MpiRun(int ranks, const std::vector<std::string>& args, const fs::path& log,
         const std::vector<std::string>& env = {}) {
    std::vector<std::string> a = {"mpirun",          "-np",       std::to_string(ranks),
                                  "--oversubscribe", "--bind-to", "none"};
    for (const std::string& e : env) {
      a.push_back("-x");
      a.push_back(e);
    }
    a.push_back(FTC_CLI);
    a.insert(a.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& s : a) argv.push_back(s.data());
    argv.push_back(nullptr);
    std::vector<std::string> envs = {"OMPI_ALLOW_RUN_AS_ROOT=1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1",
                                     marker_ + "=1"};
    if (const std::string n = no_leak_check(); !n.empty()) envs.push_back(n);
    for (const std::string& e : env) envs.push_back(e);
    for (char** e = environ; *e; ++e) envs.emplace_back(*e);
    std::vector<char*> envp;
    for (std::string& s : envs) envp.push_back(s.data());
    envp.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT, 0644);
    posix_spawn_file_actions_adddup2(&fa, STDOUT_FILENO, STDERR_FILENO);
    if (posix_spawnp(&pid_, "mpirun", &fa, nullptr, argv.data(), envp.data()) != 0)
      throw std::runtime_error("cannot start mpirun");
    posix_spawn_file_actions_destroy(&fa);
  }
  ~MpiRun() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  // The pid of rank `r` of this run (0 while it has not started).
  pid_t rank_pid(int r) const {
    const std::string want = "OMPI_COMM_WORLD_RANK=" + std::to_string(r);
    for (const auto& e : fs::directory_iterator("/proc")) {
      const std::string name = e.path().filename();
      if (name.find_first_not_of("0123456789") != std::string::npos) continue;
      std::ifstream in(e.path() / "environ", std::ios::binary);
      std::string env((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      bool rank = false, ours = false;
      for (std::size_t i = 0; i < env.size();) {
        const std::size_t end = env.find('\0', i);
        const std::string v = env.substr(i, end - i);
        rank |= v == want;
        ours |= v == marker_ + "=1";
        i = end == std::string::npos ? env.size() : end + 1;
      }
      if (rank && ours) return std::stoi(name);
    }
    return 0;
  }
  // The exit status (or -signal) once it has ended, or nullopt after `limit`.
  std::optional<int> wait_for(std::chrono::seconds limit) {
    const auto end = std::chrono::steady_clock::now() + limit;
    while (std::chrono::steady_clock::now() < end) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
      }
      std::this_thread::sleep_for(20ms);
    }
    return std::nullopt;
  }
  pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  std::string marker_ = "FTC_TEST_MPI_RUN_" + std::to_string(::getpid());
};

// Waits until `file` holds `text` (or the time is up).
bool wait_for_text(const fs::path& file, const std::string& text, std::chrono::seconds limit) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < end) {
    if (slurp(file).find(text) != std::string::npos) return true;
    std::this_thread::sleep_for(20ms);
  }
  return false;
}

// Table 1 for long enough to be stopped in the middle.
fs::path long_job(const fs::path& dir) {
  json j = json::parse(slurp(fs::path(FTC_SOURCE_DIR) / "jobs" / "table1.json"));
  j["name"] = "table1-long";
  j["tuning"]["algorithm"]["iterations"] = 400;
  return write_job(dir, j);
}

// A worker that stops answering (SIGSTOP: alive, silent) ends the run within the rank timeout
// (6 s: long enough that a busy CI host does not starve a healthy rank that long):
// exit 1, the rank named, no gains file.
TEST(Mpi, WorkerRankThatHangsStopsTheRunNamingIt) {
  REQUIRE_MPI();
  const fs::path dir = fresh_dir("mpi-hang");
  const fs::path job = long_job(dir);
  MpiRun run(3, {"run", job.string(), "--threads", "1", "--out", (dir / "out").string()},
             dir / "log.txt", {"FTCTUNE_RANK_TIMEOUT=6"});
  ASSERT_TRUE(wait_for_text(dir / "log.txt", "iteration 2/", 60s)) << slurp(dir / "log.txt");
  const pid_t worker = run.rank_pid(2);
  ASSERT_GT(worker, 0);
  ::kill(worker, SIGSTOP);
  const auto t0 = std::chrono::steady_clock::now();
  const std::optional<int> status = run.wait_for(30s);
  ASSERT_TRUE(status) << "still running 30 s after a rank hung";
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(*status, 1);
  EXPECT_LT(took, 30.0);
  const std::string log = slurp(dir / "log.txt");
  EXPECT_NE(log.find("rank 2 (on "), std::string::npos) << log;
  EXPECT_NE(log.find("has not answered for 6 s"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(dir / "out" / "gains.json"));
}

// A worker that dies is noticed by mpirun, which ends the job at once and names the rank; its
// exit status is mpirun's (128 + the signal), not ftctune's.
TEST(Mpi, WorkerRankThatDiesStopsTheRunNamingIt) {
  REQUIRE_MPI();
  const fs::path dir = fresh_dir("mpi-kill");
  const fs::path job = long_job(dir);
  MpiRun run(3, {"run", job.string(), "--threads", "1", "--out", (dir / "out").string()},
             dir / "log.txt");
  ASSERT_TRUE(wait_for_text(dir / "log.txt", "iteration 2/", 60s)) << slurp(dir / "log.txt");
  const pid_t worker = run.rank_pid(1);
  ASSERT_GT(worker, 0);
  ::kill(worker, SIGKILL);
  const std::optional<int> status = run.wait_for(30s);
  ASSERT_TRUE(status) << "still running 30 s after a rank died";
  EXPECT_NE(*status, 0);
  const std::string log = slurp(dir / "log.txt");
  EXPECT_NE(log.find("rank 1"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(dir / "out" / "gains.json"));
}

// Rank 0 serves HTTP and runs each job on every rank; the workers leave when the service stops.
TEST(Mpi, ServeUnderMpirunRunsJobsOnEveryRankAndStopsCleanly) {
  REQUIRE_MPI();
  const fs::path dir = fresh_dir("mpi-serve");
  const auto plain =
      run_cli("run jobs/table1.json -q --out '" + (dir / "plain").string() + "'", dir);
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  const int port = 20000 + static_cast<int>(::getpid() % 20000);
  MpiRun serve(2,
               {"serve", "--port", std::to_string(port), "--store", (dir / "store").string(),
                "--threads", "1"},
               dir / "log.txt");
  ASSERT_TRUE(wait_for_text(dir / "log.txt", "listening on", 60s)) << slurp(dir / "log.txt");
  EXPECT_NE(slurp(dir / "log.txt").find("serving with 2 MPI ranks"), std::string::npos);
  const std::string server = " --server http://127.0.0.1:" + std::to_string(port);
  const auto submit = run_cli("submit jobs/table1.json --wait -q" + server + " -o '" +
                                  (dir / "fetched.json").string() + "'",
                              dir);
  ASSERT_EQ(submit.exit_code, 0) << submit.err << slurp(dir / "log.txt");
  EXPECT_EQ(slurp(dir / "fetched.json"), slurp(dir / "plain" / "gains.json"));
  // SIGTERM to rank 0: it stops in order and releases the worker; every process ends.
  const pid_t leader = serve.rank_pid(0), worker = serve.rank_pid(1);
  ASSERT_GT(leader, 0);
  ASSERT_GT(worker, 0);
  ::kill(leader, SIGTERM);
  const std::optional<int> status = serve.wait_for(30s);
  ASSERT_TRUE(status) << slurp(dir / "log.txt");
  EXPECT_EQ(*status, 0) << slurp(dir / "log.txt");
  EXPECT_NE(::kill(worker, 0), 0) << "the worker rank outlived the service";
}

}  // namespace
