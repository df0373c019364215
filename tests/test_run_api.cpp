// The run API (api/api.hpp) that the command line, the service and Python share: run_job writes
// the files `ftctune run` writes, byte for byte; a given directory holding a run is refused
// unless forced; the iteration callback may stop a run, which then writes nothing; the study
// refuses lists it cannot run.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/api/api.hpp"
#include "short_job.hpp"

using nlohmann::json;
using namespace ftc;
using namespace ftc::testing;

namespace {

// Every regular file under `dir`, by path relative to it.
std::map<std::string, std::string> files_under(const std::filesystem::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
    if (e.is_regular_file())
      files[std::filesystem::relative(e.path(), dir).string()] = slurp(e.path());
  return files;
}

}  // namespace

TEST(RunApi, RunJobWritesTheBytesOfTheCommandLine) {
  const std::filesystem::path dir = fresh_dir("run-api-bytes");
  const std::filesystem::path job_file = dir / "job.json";
  tune::write_file_atomic(job_file, tiny_job().dump(2));
  const CliResult cli = run_cli("run -q --threads 2 --baseline '" + job_file.string() +
                                    "' --out '" + (dir / "cli").string() + "'",
                                dir);
  ASSERT_EQ(cli.exit_code, 0) << cli.err;

  tune::RunJobOptions o;
  o.job_file = job_file.string();
  o.out = dir / "api";
  o.threads = 1;  // the thread count changes no byte (run.json records it)
  o.baseline = true;
  std::vector<std::string> log;
  o.log = [&](tune::LogLevel, const std::string& m) { log.push_back(m); };
  int iterations = 0;
  o.on_iteration = [&](const tune::IterationReport& it) {
    ++iterations;
    EXPECT_EQ(it.total_evaluations, 4);  // 2 bats, the initial population and 1 iteration
    return true;
  };
  const tune::RunJobResult r = tune::run_job(tune::load_job(job_file), o);
  EXPECT_FALSE(r.stopped);
  EXPECT_FALSE(r.diverged());
  EXPECT_EQ(r.out, dir / "api");
  EXPECT_EQ(iterations, 2);
  ASSERT_FALSE(log.empty());
  EXPECT_EQ(log.front().rfind("tuning Kp, Ki of job tiny: 4 evaluations of 1 scenario", 0), 0u)
      << log.front();

  const auto a = files_under(dir / "api"), c = files_under(dir / "cli");
  ASSERT_EQ(a.size(), c.size());
  for (const auto& [name, content] : c) {
    ASSERT_TRUE(a.count(name)) << name;
    if (name == "run.json") continue;  // when, where, how long and on how many threads
    EXPECT_EQ(a.at(name), content) << name;
  }
  json ra = json::parse(a.at("run.json")), rc = json::parse(c.at("run.json"));
  EXPECT_EQ(ra["files"], rc["files"]);
  EXPECT_EQ(ra["simulations"], rc["simulations"]);
  EXPECT_EQ(json::parse(r.run_json), ra);
  std::vector<std::string> listed = r.files;
  EXPECT_EQ(json(listed), ra["files"]);
}

TEST(RunApi, ARunComputedWithoutADirectoryIsWrittenLaterWithTheSameBytes) {
  const std::filesystem::path dir = fresh_dir("run-api-later");
  const tune::Job job = tune::parse_job(tiny_job(), "tiny");
  tune::SerialEvaluator serial;
  tune::RunJobOptions o;
  o.out = dir / "now";
  o.evaluator = &serial;
  o.baseline = true;
  const tune::RunJobResult now = tune::run_job(job, o);
  o.out = dir / "never";
  o.write = false;
  const tune::RunJobResult later = tune::run_job(job, o);
  EXPECT_TRUE(later.out.empty());
  EXPECT_FALSE(std::filesystem::exists(dir / "never"));  // no lock, checkpoint or file
  EXPECT_EQ(tune::write_run(later, dir / "later"), dir / "later");
  const auto a = files_under(dir / "now"), b = files_under(dir / "later");
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [name, content] : a)
    if (name != "run.json") {
      EXPECT_EQ(b.at(name), content) << name;
    }
  EXPECT_EQ(b.at("run.json"), later.run_json);
  // Like run_job, it never writes over a run unless forced.
  try {
    tune::write_run(later, dir / "now");
    ADD_FAILURE() << "write_run wrote over a run";
  } catch (const InputError& e) {
    EXPECT_EQ(e.source(), "--out");
  }
  EXPECT_EQ(slurp(dir / "now" / "run.json"), now.run_json);
  tune::write_run(later, dir / "now", true);
  EXPECT_EQ(slurp(dir / "now" / "run.json"), later.run_json);
  // A run stopped early has no files to write; nor may a run without a directory resume.
  tune::RunJobOptions stop = o;
  stop.on_iteration = [](const tune::IterationReport&) { return false; };
  EXPECT_THROW(tune::write_run(tune::run_job(job, stop), dir / "stopped"), InputError);
  EXPECT_FALSE(std::filesystem::exists(dir / "stopped"));
  EXPECT_THROW(tune::resume_job(job, o), InputError);
}

TEST(RunApi, AGivenDirectoryHoldingARunIsRefusedUnlessForced) {
  const std::filesystem::path dir = fresh_dir("run-api-refuse");
  const tune::Job job = tune::parse_job(tiny_job(), "tiny");
  tune::SerialEvaluator serial;
  tune::RunJobOptions o;
  o.out = dir / "out";
  o.evaluator = &serial;
  tune::run_job(job, o);
  const std::string gains = slurp(dir / "out" / "gains.json");
  try {
    tune::run_job(job, o);
    ADD_FAILURE() << "a second run into the directory was not refused";
  } catch (const InputError& e) {
    EXPECT_EQ(e.source(), "--out");
    EXPECT_NE(std::string(e.what()).find("already holds a run"), std::string::npos) << e.what();
  }
  // Forced with another seed: the new run's files replace the earlier run's.
  o.force = true;
  o.seed = 99;
  const tune::RunJobResult r = tune::run_job(job, o);
  EXPECT_EQ(json::parse(slurp(dir / "out" / "gains.json"))["optimizer"]["seed"], 99);
  EXPECT_NE(slurp(dir / "out" / "gains.json"), gains);
  EXPECT_EQ(r.outcome.seed, 99u);
  // A finished run has nothing to resume.
  o.force = false;
  EXPECT_THROW(tune::resume_job(job, o), InputError);
}

TEST(RunApi, AStoppedRunWritesNothingButItsCheckpoint) {
  const std::filesystem::path dir = fresh_dir("run-api-stop");
  const tune::Job job = tune::parse_job(short_table1_job(), "short");
  tune::SerialEvaluator serial;
  tune::RunJobOptions o;
  o.out = dir / "out";
  o.evaluator = &serial;
  o.checkpoint = tune::CheckpointPolicy::every_iteration;
  o.on_iteration = [](const tune::IterationReport& it) { return it.row.iteration < 1; };
  const tune::RunJobResult stopped = tune::run_job(job, o);
  EXPECT_TRUE(stopped.stopped);
  EXPECT_FALSE(stopped.outcome.completed());
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "gains.json"));
  ASSERT_TRUE(std::filesystem::exists(dir / "out" / "checkpoint.json"));
  // Resumed, it ends with the gains of a run never stopped.
  o.on_iteration = nullptr;
  const tune::RunJobResult resumed = tune::resume_job(job, o);
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "checkpoint.json"));
  tune::RunJobOptions whole;
  whole.out = dir / "whole";
  whole.evaluator = &serial;
  tune::run_job(job, whole);
  EXPECT_EQ(slurp(dir / "out" / "gains.json"), slurp(dir / "whole" / "gains.json"));
  EXPECT_EQ(slurp(dir / "out" / "trials.csv"), slurp(dir / "whole" / "trials.csv"));
}

namespace {

// A run's storage in memory: what the seam hands a storage other than the output directory (the
// service's job store is one).
struct MemoryStorage final : tune::RunStorage {
  std::string checkpoint_name() const override { return "memory"; }
  std::optional<tune::Checkpoint> load_checkpoint(const std::string& sha,
                                                  std::uint64_t seed) override {
    if (state.is_null()) return std::nullopt;
    EXPECT_EQ(sha, job_sha);
    EXPECT_EQ(seed, job_seed);
    return tune::Checkpoint{iteration, state};
  }
  bool save_checkpoint(const std::string& sha, std::uint64_t seed, const tune::HistoryRow& h,
                       const tune::Optimizer& optimizer,
                       const std::vector<tune::Trial>& trials) override {
    job_sha = sha;
    job_seed = seed;
    iteration = h.iteration;
    state = tune::run_checkpoint(optimizer, trials);
    ++saved;
    return h.iteration < stop_after;
  }
  void describe(json& run) const override { run["where"] = "memory"; }
  void put(const tune::RunJobResult&, const std::map<std::string, std::string>& f) override {
    files = f;
  }
  std::string job_sha;
  std::uint64_t job_seed = 0;
  int iteration = -1, saved = 0, stop_after = 1 << 30;
  json state;
  std::map<std::string, std::string> files;
};

}  // namespace

// The storage seam: given a storage, run_job checkpoints into it after every iteration, resumes
// from what it holds, keeps a stopped run's files partial when asked, and hands it the files it
// would write into a directory, byte for byte; no directory is made.
TEST(RunApi, AStorageTakesTheCheckpointsAndFilesADirectoryWouldHold) {
  const std::filesystem::path dir = fresh_dir("run-api-storage");
  const tune::Job job = tune::parse_job(short_table1_job(), "short");
  tune::SerialEvaluator serial;
  MemoryStorage memory;
  memory.stop_after = 0;  // the storage itself stops the run after the first iteration
  tune::RunJobOptions o;
  o.out = dir / "unused";
  o.evaluator = &serial;
  o.storage = &memory;
  o.checkpoint = tune::CheckpointPolicy::every_iteration;
  bool asked = false;
  o.keep_partial = [&] { return asked = true; };
  const tune::RunJobResult stopped = tune::run_job(job, o);
  EXPECT_TRUE(asked);
  EXPECT_TRUE(stopped.stopped);
  EXPECT_TRUE(stopped.partial);
  EXPECT_EQ(memory.saved, 1);
  EXPECT_EQ(memory.iteration, 0);
  ASSERT_TRUE(memory.files.count("gains.json"));
  EXPECT_EQ(json::parse(memory.files.at("gains.json"))["optimizer"]["completed"], false);
  const json partial_run = json::parse(memory.files.at("run.json"));
  EXPECT_EQ(partial_run["completed"], false);
  EXPECT_EQ(partial_run["where"], "memory");
  EXPECT_EQ(memory.files.at("run.json"), stopped.run_json);

  // Resumed from the storage's checkpoint, it ends with the bytes of a run never stopped.
  memory.stop_after = 1 << 30;
  memory.files.clear();
  o.keep_partial = nullptr;
  const tune::RunJobResult resumed = tune::run_job(job, o);
  EXPECT_FALSE(resumed.stopped);
  EXPECT_FALSE(resumed.partial);
  EXPECT_EQ(memory.saved, 3);  // iterations 1 and 2 after the resume
  EXPECT_FALSE(std::filesystem::exists(dir / "unused"));
  tune::RunJobOptions whole;
  whole.out = dir / "whole";
  whole.evaluator = &serial;
  tune::run_job(job, whole);
  const auto w = files_under(dir / "whole");
  ASSERT_EQ(memory.files.size(), w.size());
  for (const auto& [name, content] : w) {
    ASSERT_TRUE(memory.files.count(name)) << name;
    if (name != "run.json") {
      EXPECT_EQ(memory.files.at(name), content) << name;
    }
  }
  const json rm = json::parse(memory.files.at("run.json")), rw = json::parse(w.at("run.json"));
  EXPECT_EQ(rm["files"], rw["files"]);
  EXPECT_EQ(rm["where"], "memory");
  EXPECT_FALSE(rm.contains("completed"));
  EXPECT_EQ(json::parse(resumed.run_json), rm);
}

TEST(RunApi, StudyRefusesListsItCannotRun) {
  const tune::Job job = tune::parse_job(tiny_job(), "tiny");
  EXPECT_EQ(tune::parse_seed_list("1-3,7"), (std::vector<std::uint64_t>{1, 2, 3, 7}));
  EXPECT_THROW(tune::parse_seed_list("3-1"), InputError);
  EXPECT_EQ(tune::parse_algorithm_list("bat,random"), (std::vector<std::string>{"bat", "random"}));
  EXPECT_THROW(tune::parse_algorithm_list("bat,bat"), InputError);
  tune::StudyOptions o;
  o.budget = 4;
  o.out = fresh_dir("run-api-study");
  o.algorithms = {"bat", "bat"};
  o.seeds = {1};
  EXPECT_THROW(tune::run_study(job, o), InputError);
  o.algorithms = {"bat"};
  o.seeds = {1, 1};
  EXPECT_THROW(tune::run_study(job, o), InputError);
  o.seeds = {};
  EXPECT_THROW(tune::run_study(job, o), InputError);
  o.seeds = {1};
  o.budget = 0;
  EXPECT_THROW(tune::run_study(job, o), InputError);
}
