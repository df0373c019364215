// The run API (api/api.hpp): run, resume, evaluate and landscape, as the command line runs them.
#include "ftc/tune/api/api.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <map>
#include <nlohmann/json.hpp>

#include "ftc/runtime/json_reader.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/optimizers/random_search.hpp"
#include "ftc/tune/report/evaluation.hpp"
#include "ftc/tune/run/checkpoint.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/memory_budget.hpp"
#include "ftc/tune/problem/problem.hpp"
#include "ftc/version.hpp"

namespace ftc::tune {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

using clock_type = std::chrono::steady_clock;

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::string hostname() {
  char buf[256] = {};
  if (::gethostname(buf, sizeof buf - 1) != 0) return "unknown";
  return buf;
}

std::string g6(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// The evaluator a call runs on: the caller's, or one made for it.
struct EvaluatorFor {
  std::unique_ptr<BatchEvaluator> owned;
  BatchEvaluator* use = nullptr;
  EvaluatorFor(BatchEvaluator* given, int threads) {
    if (given) {
      use = given;
    } else {
      owned = make_evaluator(threads);
      use = owned.get();
    }
  }
};

// The files of a finished run into `out` (locked by the caller): first into a staging directory
// inside it, each synced, so that a full disk or a kill on the way leaves `out` as it was, an
// earlier run included; only then does the new run take its place, entry by entry by rename
// (which needs no space) with gains.json last. `replace`: what is in the way goes first (the run
// `force` replaces, or what an earlier start of a resumed run left: rename cannot replace a
// directory that has files). Then the checkpoint, of no more use, goes.
void put_in_place(const std::map<std::string, std::string>& files, const fs::path& out,
                  bool replace) {
  const fs::path staging = unique_dir(out, kStagingPrefix);
  std::vector<std::string> entries;
  const auto add_entry = [&](const std::string& file) {
    const std::string top = fs::path(file).begin()->string();  // trajectories/a/b.csv: the folder
    if (std::find(entries.begin(), entries.end(), top) == entries.end()) entries.push_back(top);
  };
  try {
    for (const std::string& f : write_output_files(files, staging)) add_entry(f);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(staging, ec);
    throw;
  }
  replace_run(out, staging, entries, replace);
  // gains.json is in place: the run is finished, and its checkpoint of no more use.
  fs::remove(out / kCheckpointFile);
}

// The run directory as a run's storage (`ftctune run`, Python's tune): locked for the run,
// checkpoint.json after each iteration, the files staged and moved into place (put_in_place).
class DirectoryStorage final : public RunStorage {
 public:
  DirectoryStorage(const RunJobOptions& o, const RunLog& log) : o_(o), log_(log) {}
  // Claims the directory (the job's default one when none was given).
  void open(const Job& job) {
    out_ = o_.out.empty() ? default_out_dir(job.name) : o_.out;
    if (o_.resume) {
      // The same directory whatever it holds: the interrupted run is there.
      lock_ = std::make_unique<DirectoryLock>(out_, log_);
      if (!lock_->held())
        throw InputError("--out", "",
                         out_.string() + " is being written by another ftctune run; wait for it");
    } else if (o_.write) {
      lock_ = claim_run_directory(out_, !o_.out.empty(), o_.force, log_);
    }
  }
  // What runs stopped before they finished left behind (after the checkpoint is read).
  void clear_leftovers() {
    if (o_.write) handle_leftovers(out_, log_);
  }
  const fs::path& out() const { return out_; }
  std::string checkpoint_name() const override { return (out_ / kCheckpointFile).string(); }
  std::optional<Checkpoint> load_checkpoint(const std::string& job_sha256,
                                            std::uint64_t seed) override {
    if (!o_.resume) return std::nullopt;
    if (fs::exists(out_ / kCheckpointFile)) {
      Checkpoint c = read_checkpoint(out_ / kCheckpointFile, job_sha256, seed);
      say(log_, LogLevel::info,
          "resuming from " + checkpoint_name() + " after iteration " +
              std::to_string(c.iteration));
      return c;
    }
    if (fs::exists(out_ / "gains.json"))
      throw InputError(
          "--resume", "",
          out_.string() +
              " holds a finished run (gains.json): nothing to resume (a run written elsewhere is "
              "resumed with --out DIR)");
    // A batch script can always pass --resume: its first start has nothing to resume.
    say(log_, LogLevel::info,
        "no checkpoint in " + out_.string() + ": starting from the first iteration");
    return std::nullopt;
  }
  bool save_checkpoint(const std::string& job_sha256, std::uint64_t seed, const HistoryRow& h,
                       const Optimizer& optimizer, const std::vector<Trial>& trials) override {
    write_file_atomic(out_ / kCheckpointFile,
                      checkpoint_text(job_sha256, seed, h.iteration,
                                      run_checkpoint(optimizer, trials)));
    return true;
  }
  void put(const RunJobResult&, const std::map<std::string, std::string>& files) override {
    put_in_place(files, out_, o_.force || o_.resume);
  }

 private:
  const RunJobOptions& o_;
  const RunLog& log_;
  fs::path out_;
  std::unique_ptr<DirectoryLock> lock_;
};

}  // namespace

std::string parameters_text(const std::vector<std::string>& names, const Decision& x) {
  std::string s;
  char buf[64];
  for (std::size_t i = 0; i < names.size() && i < x.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%s%s = %.5g", i ? ", " : "", names[i].c_str(), x[i]);
    s += buf;
  }
  return s;
}

std::map<std::string, std::string> run_files(const RunJobResult& result) {
  std::map<std::string, std::string> files = output_files(result.outcome);
  if (result.random_baseline)
    files["history-random.csv"] = history_csv(*result.random_baseline);
  files["run.json"] = result.run_json;
  return files;
}

RunJobResult run_job(const Job& job, const RunJobOptions& o) {
  const RunLog& log = o.log;
  if (!job.tuning)
    throw InputError(o.job_file, "/tuning", "is required by ftctune run (what should be tuned?)");
  if (!o.storage && o.resume && o.force)
    throw InputError("--resume", "", "cannot be combined with --force");
  if (!o.storage && o.resume && !o.write)
    throw InputError("--resume", "", "needs the run's output directory (write = false)");
  // Memory by design: a job whose run would not fit is refused before any work.
  check_memory_budget(job, memory_budget_bytes(), o.job_file);
  const std::uint64_t seed = o.seed.value_or(job.tuning->seed);
  const std::string job_sha = canonical_job_sha256(job);
  // Where the checkpoints and files go: the caller's storage, or the output directory.
  std::optional<DirectoryStorage> directory;
  if (!o.storage) directory.emplace(o, log).open(job);
  RunStorage& storage = o.storage ? *o.storage : *directory;
  const bool writes = o.storage || o.write;
  const std::optional<Checkpoint> resumed = storage.load_checkpoint(job_sha, seed);
  if (directory) directory->clear_leftovers();
  const std::int64_t total = job.tuning->algorithm->evaluations();
  std::vector<std::string> names;
  for (const ParameterBounds& b : job.tuning->parameters) names.push_back(b.name);

  RunJobResult result;
  if (directory && o.write) result.out = directory->out();
  const std::string started = utc_now();
  const auto t0 = clock_type::now();
  EvaluatorFor evaluator(o.evaluator, o.threads);
  RunOptions ro;
  ro.seed = o.seed;
  ro.max_trajectory_rows = o.max_trajectory_rows;
  ro.capping = o.capping;
  ro.cache = o.cache;
  ro.interrupt = o.interrupt;
  if (resumed) ro.resume = &resumed->state;
  // Checkpoints: asked for, continuing one, or once the run looks like taking over a minute.
  const bool never = o.checkpoint == CheckpointPolicy::never || !writes;
  bool checkpointing = !never && (o.checkpoint == CheckpointPolicy::every_iteration || resumed);
  // Evaluations done before this process started (one trial each), for the ETA.
  const auto evaluations_before =
      static_cast<std::int64_t>(resumed ? resumed->state.value("trials", json::array()).size() : 0);
  // An algorithm with a stopping rule of its own (pagmo's cmaes and xnes: ftol, xtol) may stop
  // evaluating before its generations end: the iterations go on and evaluate nothing, so the
  // count stays below what `validate` said. Said once; the ETA then counts only what the run
  // evaluates after its iterations.
  std::int64_t last_evaluations = evaluations_before;
  bool stalled = false;
  ro.observer = [&](const HistoryRow& h, const Optimizer& optimizer,
                    const std::vector<Trial>& trials) {
    const double elapsed = std::chrono::duration<double>(clock_type::now() - t0).count();
    const double done = static_cast<double>(h.evaluations - evaluations_before);
    if (!stalled && h.iteration > 0 && h.evaluations == last_evaluations &&
        h.evaluations < total) {
      stalled = true;
      const json a = job.tuning->algorithm->to_json();
      const std::string name = a.contains("name") && a["name"].is_string()
                                   ? a["name"].get<std::string>()
                                   : job.tuning->algorithm->type();
      say(log, LogLevel::info,
          "iteration " + std::to_string(h.iteration) + ": " + name +
              " evaluated no candidate: it met its own stopping rule (for cmaes and xnes, "
              "tuning.algorithm.settings' ftol or xtol) after " +
              std::to_string(h.evaluations) + " of the " + std::to_string(total) +
              " evaluations its generations allow; the remaining iterations evaluate nothing");
    }
    last_evaluations = h.evaluations;
    // The ETA counts what the run evaluates after its iterations too: the comparison and the
    // noise floor (issue 41: "1944/1944 · ETA 0.0 s" with half of the job still to run).
    // The front's size (its noise floor reruns each point): found once per iteration, for the
    // report, the storage's progress and the ETA.
    const bool last = h.iteration == job.tuning->algorithm->iterations();
    const bool front = front_objectives(job) >= 2;
    const std::size_t points = front ? front_trials(job, trials, trials.size()).size() : 0;
    if (front) storage.front_so_far(points);
    const std::int64_t finishing = finishing_evaluations(job, points);
    const double left = static_cast<double>((stalled ? 0 : total - h.evaluations) + finishing);
    const double eta = done > 0 ? elapsed * left / done : 0.0;
    // After the last iteration's report: what the run still does.
    const auto say_finishing = [&] {
      if (!last) return;
      say(log, LogLevel::info,
          "iterations done; now " + std::to_string(finishing) + " more evaluations of the " +
              std::to_string(job.scenario_count()) + " scenario" +
              (job.scenario_count() == 1 ? "" : "s") + ": the comparison of " +
              std::to_string(job.compare.size() + 2) + " controllers and the noise floor (" +
              std::to_string(NoiseFloor{}.repeats) + " reruns of " +
              (points == 0 ? std::string("the tuned gains")
               : job.tuning->noise_floor == FrontNoiseFloor::picked
                   ? "the picked point of the front's " + std::to_string(points) +
                         " (\"noise_floor\": \"picked\")"
                   : "each of the front's " + std::to_string(points) + " points") +
              ")");
    };
    if (!checkpointing && !never && elapsed + eta > o.checkpoint_after_seconds) {
      checkpointing = true;
      say(log, LogLevel::info,
          "this run will take over a minute: it writes " + storage.checkpoint_name() +
              " after every iteration (ftctune run --resume continues from it)");
    }
    if (checkpointing && !storage.save_checkpoint(job_sha, seed, h, optimizer, trials)) {
      result.stopped = true;
      return false;
    }
    if (!o.on_iteration) {
      say_finishing();
      return true;
    }
    IterationReport report{h, total, job.tuning->algorithm->iterations(), elapsed, eta, {}};
    if (front) report.front_points = points;
    const bool go_on = o.on_iteration(report);
    result.stopped = !go_on;
    if (go_on) say_finishing();
    return go_on;
  };
  {
    std::string tuned;
    for (const std::string& n : names) tuned += (tuned.empty() ? "" : ", ") + n;
    say(log, LogLevel::info,
        "tuning " + tuned + " of job " + job.name + ": " + std::to_string(total) +
            " evaluations of " + std::to_string(job.scenario_count()) + " scenario" +
            (job.scenario_count() == 1 ? "" : "s") + ", " + job.tuning->algorithm->type() +
            " algorithm");
  }
  result.outcome = [&] {
    try {
      return tune(job, *evaluator.use, ro);
    } catch (const InputError& e) {
      // A state the optimiser refuses: the file and the field's path in it.
      if (!resumed || e.source() != "checkpoint") throw;
      std::vector<FieldError> errors = e.errors();
      for (FieldError& f : errors) f.path = "/state" + f.path;
      throw InputError(storage.checkpoint_name(), std::move(errors));
    }
  }();
  if (result.outcome.interrupted) result.stopped = true;
  result.wall_seconds = std::chrono::duration<double>(clock_type::now() - t0).count();
  // run.json: what run_metadata() says, and where, when and from what (the storage's own fields
  // last).
  const auto describe = [&](const std::map<std::string, std::string>& outputs) {
    json run = run_metadata(result.outcome, result.wall_seconds);
    json files = json::array();
    for (const auto& [name, content] : outputs) files.push_back(name);
    if (result.random_baseline) {
      files.push_back("history-random.csv");
      run["simulations"] =
          run["simulations"].get<std::int64_t>() + result.random_baseline->simulations;
      run["cached_trials"] =
          run["cached_trials"].get<std::int64_t>() + cached_trials(result.random_baseline->trials);
    }
    files.push_back("run.json");
    run["files"] = files;
    run["started_at"] = started;
    run["host"] = hostname();
    run["job_file"] = o.job_file;
    if (result.stopped) run["completed"] = false;
    storage.describe(run);
    result.files.clear();
    for (const json& f : files) result.files.push_back(f.get<std::string>());
    result.run_json = run.dump(2) + "\n";
  };
  if (result.stopped) {
    // Its best so far, compared as a finished run's best is, when the caller keeps it.
    if (!writes || !o.keep_partial || result.outcome.optimization.history.empty() ||
        !o.keep_partial())
      return result;
    try {
      compare_best(result.outcome, *evaluator.use, o.max_trajectory_rows);
      std::map<std::string, std::string> files = output_files(result.outcome);
      describe(files);
      files["run.json"] = result.run_json;
      storage.put(result, files);
      result.partial = true;
    } catch (const std::exception& e) {
      say(log, LogLevel::warn,
          std::string("the results of the stopped run could not be made: ") + e.what());
    }
    return result;
  }
  const TuningOutcome& r = result.outcome;

  // All computing first, then the files, gains.json last: a run stopped on the way (a full
  // disk, a kill) leaves no gains.json, so nothing takes its files for a finished run.
  if (o.baseline) {
    // Random search with the same budget and seed: what the algorithm buys (Fig. 5).
    Job random = job;
    random.tuning->algorithm = random_search_like(*job.tuning->algorithm);
    RunOptions rr;
    rr.seed = o.seed;
    rr.compare = false;
    rr.capping = o.capping;
    rr.cache = o.cache;
    result.random_baseline = tune(random, *evaluator.use, rr);
    say(log, LogLevel::info,
        "random search with the same budget: best J = " +
            g6(result.random_baseline->optimization.best_fitness) + " (" +
            parameters_text(names, result.random_baseline->optimization.best) + ")");
  }
  // Every file of the run, and every simulation, the random-search baseline's included.
  std::map<std::string, std::string> files = output_files(r);
  describe(files);
  if (result.random_baseline) files["history-random.csv"] = history_csv(*result.random_baseline);
  files["run.json"] = result.run_json;
  if (writes) storage.put(result, files);
  for (const std::string& w : r.warnings) say(log, LogLevel::warn, w);
  return result;
}

fs::path write_run(const RunJobResult& result, const fs::path& out, bool force, const RunLog& log) {
  if (result.stopped || !result.outcome.completed() || result.outcome.comparison.empty())
    throw InputError("run", "", "was stopped before it finished: it has no files to write");
  fs::path dir = out;
  const std::unique_ptr<DirectoryLock> lock = claim_run_directory(dir, true, force, log);
  handle_leftovers(dir, log);
  put_in_place(run_files(result), dir, force);
  return dir;
}

RunJobResult resume_job(const Job& job, RunJobOptions options) {
  options.resume = true;
  return run_job(job, options);
}

fs::path evaluation_dir(const Job& job, const RunLog& log) {
  // Beside the job's latest run (out/<name>, or -2, -3, ... where `run` moved on), whose report
  // then shows it.
  std::string why;
  const fs::path run = latest_run_dir(job, &why);
  say(log, LogLevel::info, why);
  return (run.empty() ? default_out_dir(job.name) : run) / "evaluation";
}

EvaluateJobResult evaluate_job(const Job& job, const EvaluateJobOptions& o) {
  EvaluateJobResult result;
  result.out = o.out.empty() ? evaluation_dir(job, o.log) : o.out;
  EvaluateOptions options;
  options.gains = o.gains;
  options.seed = o.seed;
  options.count = o.count;
  options.progress = o.progress;
  // A run's front: every point joins the controllers, labelled "point <i>" (its index).
  std::optional<Front> run_front;
  std::uint64_t run_seed = 0;
  if (!o.front.empty()) {
    if (!job.tuning)
      throw InputError("--front", "", "the job has no tuning section: it has no front");
    const std::string sha = canonical_job_sha256(job);
    run_front = read_front(o.front, job, sha);
    if (!run_front)
      throw InputError("--front", "",
                       (o.front / "front.json").string() +
                           " is not this job's front: no such file, or one of another job "
                           "(its job_sha256 is not " + sha.substr(0, 12) +
                           "...); name the directory of a run of this job with two or more "
                           "soft goals");
    if (run_front->points.empty())
      throw InputError("--front", "", (o.front / "front.json").string() + " has no point");
    if (run_front->held_out)
      throw InputError("--front", "",
                       (o.front / "front.json").string() +
                           " is a held-out front (of " + run_front->held_out->run +
                           "): name the run's directory");
    // The run's seed, as its front.json gives it (read_front has checked the file).
    const std::optional<std::string> text = read_file(o.front / "front.json");
    const json doc = text ? json::parse(*text, nullptr, false) : json();
    run_seed = doc.is_object() && doc.contains("seed") && doc["seed"].is_number_unsigned()
                   ? doc["seed"].get<std::uint64_t>()
                   : job.tuning->seed;
    const TuningProblem problem(job);
    for (std::size_t i = 0; i < run_front->points.size(); ++i)
      options.controllers.emplace_back("point " + std::to_string(i),
                                       problem.controller_with(run_front->points[i].parameters));
  }
  EvaluatorFor evaluator(o.evaluator, o.threads);
  result.threads = evaluator.use->concurrency();
  result.evaluation = evaluate_out_of_sample(job, options, *evaluator.use);
  write_evaluation(result.evaluation, result.out);
  if (run_front) {
    const EvaluationResult& ev = result.evaluation;
    const std::size_t first = ev.controllers.size() - run_front->points.size();
    std::vector<std::vector<double>> goals;
    for (std::size_t i = first; i < ev.controllers.size(); ++i)
      goals.push_back(ev.controllers[i].goals);
    // The job's compare entries and its own controller, held out alike (no gains files).
    std::vector<FrontCompared> compared;
    for (const EvaluatedController& c : ev.controllers)
      if (c.source == "compare" || c.source == "job")
        compared.push_back({c.label, c.source == "job" ? "baseline" : "compare", c.goals,
                            !(c.violation > 0)});
    FrontHeldOut where;
    std::error_code ec;
    const fs::path absolute = fs::weakly_canonical(fs::absolute(o.front), ec);
    where.run = (ec ? o.front : absolute).string();
    where.seed = ev.seed;
    where.count = ev.count;
    result.front =
        held_out_front(job, std::move(*run_front), where, goals, std::move(compared));
    write_file_atomic(result.out / "front.json",
                      front_document(job, canonical_job_sha256(job), run_seed, *result.front)
                              .dump(2) +
                          "\n");
  }
  if (o.figure) {
    result.figure = draw_evaluation(result.evaluation, result.out);
    if (result.front) result.front_figure = draw_held_out_front(*result.front, result.out);
  }
  return result;
}

LandscapeResult compute_landscape(const Job& job, const fs::path& out_dir,
                                  const LandscapeOptions& options, BatchEvaluator& evaluator) {
  const Landscape l = evaluate_landscape(job, options, evaluator);
  LandscapeResult r;
  fs::create_directories(out_dir);
  r.csv = out_dir / "landscape.csv";
  write_file_atomic(r.csv, landscape_csv(l));
  const LandscapeFigure figure = draw_landscape(job, l, out_dir, options);
  r.figure = figure.figure;
  r.params = l.params;
  r.simulations = l.simulations;
  r.best_objective = l.best_objective;
  r.best = l.best;
  r.fixed = l.fixed;
  r.fixed_source = l.fixed_source;
  r.path_points = figure.path_points;
  r.path_on_map = figure.path_on_map;
  return r;
}

LandscapeJobResult landscape_job(const Job& job, const LandscapeJobOptions& o) {
  LandscapeOptions lo;
  lo.n1 = o.n1;
  lo.n2 = o.n2;
  lo.params = o.params;
  lo.format = o.format;
  lo.progress = o.progress;
  // The job's latest run (out/<name>, or -2, -3, ... where `run` moved on): the landscape goes
  // into it, with its best-so-far path.
  std::string why;
  const fs::path run = latest_run_dir(job, &why);
  say(o.log, LogLevel::info, why);
  LandscapeJobResult result;
  result.out =
      o.out.empty() ? (run.empty() ? default_out_dir(job.name) : run) / "landscape" : o.out;
  const fs::path& out = result.out;
  // Before the work: a directory that can be written, and not one holding a landscape already
  // (like `run`, force replaces it).
  {
    if (const std::string problem = directory_problem(out); !problem.empty())
      throw InputError("--out", "", problem);
    std::error_code ec;
    if (!o.force && (fs::exists(out / "landscape.csv", ec) || fs::exists(out / "landscape.gp", ec)))
      throw InputError("--out", "",
                       out.string() +
                           " already holds a landscape; choose another directory, or pass "
                           "--force to replace it");
  }
  lo.history = o.history.empty() && !run.empty() && fs::is_regular_file(run / "history.csv")
                   ? run / "history.csv"
                   : o.history;
  // The unplotted parameters at the run's tuned values (the map then holds the tuned point),
  // or at the job's with at_job_values; the run's noise floor for the colours.
  if (!run.empty()) {
    const std::optional<std::string> text = read_file(run / "gains.json");
    const json gains = text ? json::parse(*text, nullptr, false) : json();
    if (gains.is_object()) {
      const double nf = json_io::json_number_or(
          gains.value(json::json_pointer("/noise_floor/relative_spread"), json()), 0.0);
      lo.noise_floor = nf;
      if (!o.at_job_values && gains.contains("tuned") && gains["tuned"].is_object()) {
        for (auto it = gains["tuned"].begin(); it != gains["tuned"].end(); ++it)
          if (it.value().is_number()) lo.fixed.emplace_back(it.key(), it.value().get<double>());
        lo.fixed_source = "the tuned value, " + (run / "gains.json").string();
      }
    }
  }
  {
    std::string params;
    for (const std::string& p : o.params) params += (params.empty() ? "" : ",") + p;
    say(o.log, LogLevel::info,
        "evaluating a " + std::to_string(o.n1) + "x" + std::to_string(o.n2) + " grid over " +
            (o.params.empty() ? std::string("the first two tuned parameters") : params) + " (" +
            std::to_string(job.scenarios.size()) + " simulations per point)");
  }
  EvaluatorFor evaluator(o.evaluator, o.threads);
  result.landscape = compute_landscape(job, out, lo, *evaluator.use);
  return result;
}

// ---- simulate --------------------------------------------------------------------------------

SimulateJobResult simulate_job(const Job& job, const sim::ControllerConfig& controller,
                               const SimulateJobOptions& o) {
  if (!(o.record_every > 0) || !std::isfinite(o.record_every))
    throw InputError("--record-every", "", "must be a finite number of seconds > 0");
  const TuningProblem problem(job);
  SimulateJobResult r;
  r.controller = controller;
  r.out = o.out.empty() ? default_out_dir(job.name) / "simulate" : o.out;
  // One scenario at a time: its trajectory is written (or, for Python, kept as CSV) and dropped,
  // so a job of many listed scenarios holds their metrics, not their trajectories.
  std::vector<sim::Metrics> metrics;
  json scenarios = json::array();
  for (std::size_t i = 0; i < job.scenarios.size(); ++i) {
    const sim::Scenario& s = job.scenarios[i];
    // An interval longer than the run records its first sample only (llround of 1e16 s / 1 ms
    // overflowed, and every sample was written).
    const double ratio = o.record_every / s.sample_time;
    const std::int64_t last = std::max<std::int64_t>(1, s.samples());
    const std::int64_t every =
        ratio >= static_cast<double>(last) ? last : std::max<std::int64_t>(1, std::llround(ratio));
    const sim::SimulationResult res = problem.simulate(controller, i, every);
    json m = metrics_json(res.metrics);
    m["name"] = s.name;
    // An unrecoverable scenario is one no gains can control once its faults start (the
    // plant's rule): its metrics are what happened, and the objective leaves it out.
    m["recoverable"] = problem.recoverable(i);
    m["counted"] = problem.counted(i);
    // A model valid only in part of the state space (rigid_body's Euler angles) says whether the
    // run left it; its metrics still count.
    if (res.model_invalid) m["model_invalid"] = *res.model_invalid;
    scenarios.push_back(std::move(m));
    metrics.push_back(res.metrics);
    r.counted += problem.counted(i) ? 1 : 0;
    const std::string file = i == 0 ? "trajectory.csv" : "trajectory-" + s.name + ".csv";
    if (o.write) {
      write_file_atomic(r.out / file, trajectory_csv(res.trajectory));
      r.trajectories.emplace_back(file, std::string());
    } else {
      r.trajectories.emplace_back(file, trajectory_csv(res.trajectory));
    }
    if (res.metrics.diverged) {
      char at[32];
      std::snprintf(at, sizeof at, "%.3f", res.metrics.diverged_at);
      r.warnings.push_back("scenario " + s.name + " diverged at t = " + at + " s");
    }
    if (res.model_invalid.value_or(false))
      r.warnings.push_back("scenario " + s.name +
                           ": the pitch angle passed ±85°, near the singularity of the 3-2-1 "
                           "Euler angles, where the rigid_body model is not valid "
                           "(model_invalid; its metrics still count)");
    if (!problem.recoverable(i))
      r.warnings.push_back("scenario " + s.name +
                           " is unrecoverable: no gains can control it once its faults start, so "
                           "the objective leaves it out");
    if (o.after_scenario) o.after_scenario();
  }
  r.evaluation = problem.score(std::move(metrics));
  const bool any = r.counted > 0;
  json& doc = r.document;
  doc["generator"] = {{"name", kToolName}, {"version", kVersion}};
  doc["job"] = job.name;
  doc["plant"] = to_json(job.plant);
  doc["controller"] = to_json(controller);
  doc["objective_definition"] = to_json(job.objective);
  // With no scenario counted there is no objective (the score's 0 would read as perfect).
  doc["objective"] = any ? json_number(r.evaluation.objective) : json(nullptr);
  doc["fitness"] = any ? json(r.evaluation.fitness) : json(nullptr);
  doc["scenarios"] = std::move(scenarios);
  if (o.write) write_file_atomic(r.out / "metrics.json", doc.dump(2) + "\n");  // the last file
  return r;
}

}  // namespace ftc::tune
