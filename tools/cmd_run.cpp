// ftctune run JOB: tune the job's controller and write the gains file and its companions.
#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <map>
#include <nlohmann/json.hpp>

#include "cli.hpp"
#include "ftc/runtime/controller_json.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/optimizers/random_search.hpp"
#include "ftc/tune/run/checkpoint.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/memory_budget.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "progress.hpp"

namespace ftc::cli {
namespace {

using nlohmann::json;

struct RunCliOptions {
  std::string job;
  std::string out;
  int threads = 0;
  std::optional<std::uint64_t> seed;
  bool report = false;
  bool baseline = false;
  bool force = false;
  bool checkpoint = false;     // after every iteration, from the first
  bool no_checkpoint = false;  // never (else: once the run looks like taking over a minute)
  bool resume = false;
};

// Where a run stages its files inside its directory, followed by the process id.
constexpr const char* kStagingPrefix = ".staging-";

constexpr const char* kPreviousPrefix = ".previous-";

// A new directory out/PREFIX<pid>, or out/PREFIX<pid>-K when that name is taken: a directory
// kept from an earlier run (which the next run names for recovery) is never reused, even when
// the process id comes round again, as it does for PID 1 in a container.
std::filesystem::path unique_dir(const std::filesystem::path& out, const char* prefix) {
  const std::string base = std::string(prefix) + std::to_string(::getpid());
  for (unsigned k = 0;; ++k) {
    const std::filesystem::path p = out / (k ? base + "-" + std::to_string(k) : base);
    if (::mkdir(p.c_str(), 0755) == 0) return p;
    if (errno != EEXIST)
      throw std::filesystem::filesystem_error("cannot create the directory", p,
                                              std::error_code(errno, std::generic_category()));
  }
}

// What runs stopped before they finished left behind (only a run holding the lock writes
// there, so any found by the holder are left over). A staging directory without gains.json was
// stopped while its files were written, and goes. One with gains.json holds a whole run that was
// stopped while moving into place, and a .previous-PID directory the run a --force was
// replacing: both are kept, and named, for the user to recover.
void handle_leftovers(const std::filesystem::path& out) {
  namespace fs = std::filesystem;
  std::error_code ec;
  std::vector<fs::path> found;
  for (const auto& e : fs::directory_iterator(out, ec)) found.push_back(e.path());
  std::sort(found.begin(), found.end());
  for (const fs::path& p : found) {
    const std::string name = p.filename().string();
    if (name.rfind(kStagingPrefix, 0) == 0) {
      if (!fs::exists(p / "gains.json", ec)) {
        fs::remove_all(p, ec);
        continue;
      }
      spdlog::warn(
          "{} holds the whole files of a run stopped while it moved them into {}: kept (move "
          "them into {} to recover that run, or remove the directory)",
          p.string(), out.string(), out.string());
    } else if (name.rfind(kPreviousPrefix, 0) == 0) {
      spdlog::warn(
          "{} holds the earlier run that a --force run was replacing when it stopped: kept (move "
          "its files back into {} to recover that run, or remove the directory)",
          p.string(), out.string());
    }
  }
}

// A run projected to take longer than this checkpoints after every iteration unless told not to.
constexpr double kCheckpointAfterSeconds = 60.0;

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

std::string params_text(const std::vector<std::string>& names, const tune::Decision& x) {
  std::string s;
  char buf[64];
  for (std::size_t i = 0; i < names.size() && i < x.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%s%s = %.5g", i ? ", " : "", names[i].c_str(), x[i]);
    s += buf;
  }
  return s;
}

// Whether a directory holds an ftctune run: a finished one (run.json and gains.json are what
// `run` writes first and last) or an interrupted one (its checkpoint).
bool holds_run(const std::filesystem::path& d) {
  std::error_code ec;
  return std::filesystem::exists(d / "gains.json", ec) ||
         std::filesystem::exists(d / "run.json", ec) ||
         std::filesystem::exists(d / tune::kCheckpointFile, ec);
}

// A finished run removes its checkpoint, so one that is there was left by a run that did not
// finish (perhaps one replacing a finished run with --force).
bool holds_interrupted_run(const std::filesystem::path& d) {
  std::error_code ec;
  return std::filesystem::exists(d / tune::kCheckpointFile, ec);
}

// Where a run writes, locked for the run. A run is never written over silently: a given --out
// that holds a run, or that another run is writing, is refused; the default out/<name> moves on
// to out/<name>-2, -3, ... (with a warning); --force
// replaces the run (its files are cleared only once the new run has finished, see
// replace_run). Other files in the directory (an evaluation, a landscape, fetched
// service results) are not a run and are left alone.
// An exclusive lock on the output directory for the whole run (flock on the directory itself,
// released when the process ends, however it ends): two runs into one directory would
// interleave their files.
class DirectoryLock {
 public:
  explicit DirectoryLock(const std::filesystem::path& dir) {
    std::filesystem::create_directories(dir);
    fd_ = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd_ < 0)
      throw std::filesystem::filesystem_error("cannot open", dir,
                                              std::error_code(errno, std::generic_category()));
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      if (errno == EWOULDBLOCK) {
        ::close(fd_);
        fd_ = -1;
      } else {
        // Some network and cluster file systems cannot lock (NFS without lockd, Lustre
        // without flock): run unlocked rather than call that another run.
        spdlog::warn("cannot lock {} ({}): a second run into it would not be noticed", dir.string(),
                     std::strerror(errno));
      }
    }
  }
  ~DirectoryLock() {
    if (fd_ >= 0) ::close(fd_);
  }
  DirectoryLock(const DirectoryLock&) = delete;
  DirectoryLock& operator=(const DirectoryLock&) = delete;
  bool held() const { return fd_ >= 0; }

 private:
  int fd_ = -1;
};

std::unique_ptr<DirectoryLock> run_directory(std::filesystem::path& out, bool given, bool force) {
  namespace fs = std::filesystem;
  const fs::path wanted = out;
  for (int k = 2;; ++k) {
    if (!holds_run(out) || force) {
      auto lock = std::make_unique<DirectoryLock>(out);
      // Another run may have finished there between the look and the lock.
      if (lock->held() && holds_run(out) && !force) lock.reset();
      if (lock && lock->held()) {
        if (out != wanted)
          spdlog::warn(
              "{} already holds a run or is in use: writing to {} (--force replaces a "
              "run instead)",
              wanted.string(), out.string());
        return lock;
      }
      // --force names the run to replace: never another directory's.
      if (given || force)
        throw InputError("--out", "",
                         out.string() +
                             " is being written by another ftctune run; wait for it to finish "
                             "or choose another directory");
    } else if (given) {
      throw InputError(
          "--out", "",
          out.string() + (holds_interrupted_run(out)
                              ? " holds an interrupted run (checkpoint.json); pass --resume to "
                                "continue it, or --force to start it over"
                              : " already holds a run; choose another directory, or pass "
                                "--force to replace that run"));
    }
    out = wanted.string() + "-" + std::to_string(k);
  }
}

// What a run writes: with --force these names of the earlier run make way for the new run's,
// so that no figure or trajectory of the earlier run is left beside the new ones.
constexpr const char* kRunEntries[] = {
    "gains.json",    "history.csv", "trials.csv",  "history-random.csv", "comparison.json",
    "comparison.md", "run.json",    "job.json",    "report.html",        "figures",
    "trajectories"};

// The move phase: the new run in `staging` takes the place of the earlier one in `out`. The
// earlier run's entries (when `replace`) are first set aside into .previous-PID, then the new
// ones move in by rename, gains.json last; only then is the earlier run deleted. A failure on
// the way undoes every move made, so `out` holds the earlier run as it was; if even that fails,
// both directories are kept and the error names them (the next run names them too).
void replace_run(const std::filesystem::path& out, const std::filesystem::path& staging,
                 const std::vector<std::string>& entries, bool replace) {
  namespace fs = std::filesystem;
  fs::path previous;  // made when the first entry is set aside
  std::vector<std::string> set_aside, moved;
  try {
    if (replace && holds_run(out)) {
      for (const char* f : kRunEntries) {
        std::error_code ec;
        if (!fs::exists(fs::symlink_status(out / f, ec))) continue;
        if (set_aside.empty()) previous = unique_dir(out, kPreviousPrefix);
        tune::move_into(out, previous, {f});
        set_aside.push_back(f);
      }
    }
    for (const std::string& e : entries) {
      tune::move_into(staging, out, {e});
      moved.push_back(e);
    }
  } catch (const std::exception& e) {
    bool undone = true;
    for (auto it = moved.rbegin(); it != moved.rend(); ++it)
      undone &= std::rename((out / *it).c_str(), (staging / *it).c_str()) == 0;
    for (auto it = set_aside.rbegin(); it != set_aside.rend() && undone; ++it)
      undone &= std::rename((previous / *it).c_str(), (out / *it).c_str()) == 0;
    std::error_code ec;
    if (!undone)
      throw tune::OutputError(
          std::string(e.what()) + "; the new run's files are in " + staging.string() +
          (set_aside.empty() ? std::string()
                             : " and the earlier run's in " + previous.string()) +
          ": move them back into " + out.string() + " by hand");
    if (!previous.empty()) fs::remove(previous, ec);
    fs::remove_all(staging, ec);
    tune::sync_directory(out);
    throw;
  }
  std::error_code ec;
  if (!previous.empty()) fs::remove_all(previous, ec);
  fs::remove(staging, ec);
  tune::sync_directory(out);
}

int run_tuning(const RunCliOptions& o, const Globals& g) {
  namespace fs = std::filesystem;
  using clock = std::chrono::steady_clock;
  const tune::Job job = tune::load_job(o.job);
  if (!job.tuning)
    throw InputError(o.job, "/tuning", "is required by ftctune run (what should be tuned?)");
  // Memory by design: a job whose run would not fit is refused before any work.
  tune::check_memory_budget(job, tune::memory_budget_bytes(), o.job);
  fs::path out = o.out.empty() ? default_out_dir(job) : fs::path(o.out);
  const std::uint64_t seed = o.seed.value_or(job.tuning->seed);
  const std::string job_sha = tune::canonical_job_sha256(job);
  std::unique_ptr<DirectoryLock> lock;
  std::optional<tune::Checkpoint> resumed;
  if (o.resume) {
    // The same directory whatever it holds: the interrupted run is there.
    lock = std::make_unique<DirectoryLock>(out);
    if (!lock->held())
      throw InputError("--out", "",
                       out.string() + " is being written by another ftctune run; wait for it");
    if (fs::exists(out / tune::kCheckpointFile)) {
      resumed = tune::read_checkpoint(out / tune::kCheckpointFile, job_sha, seed);
      spdlog::info("resuming from {} after iteration {}", (out / tune::kCheckpointFile).string(),
                   resumed->iteration);
    } else if (fs::exists(out / "gains.json")) {
      throw InputError(
          "--resume", "",
          out.string() +
              " holds a finished run (gains.json): nothing to resume (a run written elsewhere is "
              "resumed with --out DIR)");
    } else {
      // A batch script can always pass --resume: its first start has nothing to resume.
      spdlog::info("no checkpoint in {}: starting from the first iteration", out.string());
    }
  } else {
    lock = run_directory(out, !o.out.empty(), o.force);
  }
  handle_leftovers(out);
  const std::int64_t total = job.tuning->algorithm->evaluations();
  std::vector<std::string> names;
  for (const tune::ParameterBounds& b : job.tuning->parameters) names.push_back(b.name);

  const std::string started = utc_now();
  const auto t0 = clock::now();
  ProgressBar bar(!g.quiet);
  const std::unique_ptr<tune::BatchEvaluator> evaluator = make_evaluator(o.threads);
  tune::RunOptions ro;
  ro.seed = o.seed;
  if (resumed) ro.resume = &resumed->state;
  // Checkpoints: asked for, continuing one, or once the run looks like taking over a minute.
  bool checkpointing = !o.no_checkpoint && (o.checkpoint || resumed);
  // Evaluations done before this process started (one trial each), for the ETA.
  const auto evaluations_before =
      static_cast<std::int64_t>(resumed ? resumed->state.value("trials", json::array()).size() : 0);
  ro.observer = [&](const tune::HistoryRow& h, const tune::Optimizer& optimizer,
                    const std::vector<tune::Trial>& trials) {
    const double elapsed = std::chrono::duration<double>(clock::now() - t0).count();
    const double done = static_cast<double>(h.evaluations - evaluations_before);
    const double eta = done > 0 ? elapsed * static_cast<double>(total - h.evaluations) / done : 0.0;
    if (!checkpointing && !o.no_checkpoint && elapsed + eta > kCheckpointAfterSeconds) {
      checkpointing = true;
      spdlog::info(
          "this run will take over a minute: it writes {} after every iteration "
          "(ftctune run --resume continues from it)",
          (out / tune::kCheckpointFile).string());
    }
    if (checkpointing)
      tune::write_file_atomic(out / tune::kCheckpointFile,
                              tune::checkpoint_text(job_sha, seed, h.iteration,
                                                    tune::run_checkpoint(optimizer, trials)));
    bar.clear();
    spdlog::info(
        "iteration {}/{}: best J = {:.6g} ({}), {}/{} evaluations, {:.1f} s elapsed, ETA {:.1f} s",
        h.iteration, job.tuning->algorithm->iterations(), h.best_fitness,
        params_text(names, h.best), h.evaluations, total, elapsed, eta);
    bar.draw(h.evaluations, total, elapsed);
    return true;
  };
  spdlog::info("tuning {} of job {}: {} evaluations of {} scenario{}, {} algorithm",
               fmt::join(names, ", "), job.name, total, job.scenario_count(),
               job.scenario_count() == 1 ? "" : "s", job.tuning->algorithm->type());
  const tune::TuningOutcome r = [&] {
    try {
      return tune::tune(job, *evaluator, ro);
    } catch (const InputError& e) {
      // A state the optimiser refuses: the file and the field's path in it.
      if (!resumed || e.source() != "checkpoint") throw;
      std::vector<FieldError> errors = e.errors();
      for (FieldError& f : errors) f.path = "/state" + f.path;
      throw InputError((out / tune::kCheckpointFile).string(), std::move(errors));
    }
  }();
  bar.clear();
  const double wall = std::chrono::duration<double>(clock::now() - t0).count();

  // All computing first, then the files, gains.json last: a run stopped on the way (a full
  // disk, a kill) leaves no gains.json, so nothing takes its files for a finished run.
  std::optional<tune::TuningOutcome> random_baseline;
  if (o.baseline) {
    // Random search with the same budget and seed: what the algorithm buys (Fig. 5).
    tune::Job random = job;
    random.tuning->algorithm = tune::random_search_like(*job.tuning->algorithm);
    tune::RunOptions rr;
    rr.seed = o.seed;
    rr.compare = false;
    random_baseline = tune::tune(random, *evaluator, rr);
    spdlog::info("random search with the same budget: best J = {:.6g} ({})",
                 random_baseline->optimization.best_fitness,
                 params_text(names, random_baseline->optimization.best));
  }
  json run = tune::run_metadata(r, wall);
  // Every file of the run, and every simulation, the random-search baseline's included.
  const std::map<std::string, std::string> outputs = tune::output_files(r);
  json files = json::array();
  for (const auto& [name, content] : outputs) files.push_back(name);
  if (random_baseline) {
    files.push_back("history-random.csv");
    run["simulations"] = run["simulations"].get<std::int64_t>() + random_baseline->simulations;
  }
  files.push_back("run.json");
  run["files"] = files;
  run["started_at"] = started;
  run["host"] = hostname();
  run["job_file"] = o.job;

  // The files go to a staging directory inside `out` first, each synced: a full disk or a kill
  // on the way leaves `out` as it was, an earlier run included. Only then does the new run take
  // its place, entry by entry by rename (which needs no space) with gains.json last.
  const fs::path staging = unique_dir(out, kStagingPrefix);
  std::vector<std::string> entries;
  const auto add_entry = [&](const std::string& file) {
    const std::string top = fs::path(file).begin()->string();  // trajectories/a/b.csv: the folder
    if (std::find(entries.begin(), entries.end(), top) == entries.end()) entries.push_back(top);
  };
  try {
    if (random_baseline) {
      tune::write_file_atomic(staging / "history-random.csv", tune::history_csv(*random_baseline));
      add_entry("history-random.csv");
    }
    tune::write_file_atomic(staging / "run.json", run.dump(2) + "\n");
    add_entry("run.json");
    for (const std::string& f : tune::write_output_files(outputs, staging)) add_entry(f);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(staging, ec);
    throw;
  }
  // What is in the way goes first: the run --force replaces, or what an earlier start of a
  // resumed run left (rename cannot replace a directory that has files). The checkpoint stays
  // until gains.json is in place.
  replace_run(out, staging, entries, o.force || o.resume);
  // gains.json is in place: the run is finished, and its checkpoint of no more use.
  fs::remove(out / tune::kCheckpointFile);

  for (const std::string& w : r.warnings) spdlog::warn("{}", w);
  if (!g.quiet) {
    std::printf("tuned %s: %s\n", tune::display_name(job.controller.type).c_str(),
                params_text(names, r.optimization.best).c_str());
    // The objective with seven digits and the change in %: J to six digits can read the same
    // while the gains and the objective move.
    const double best = r.best().outcome.evaluation.objective;
    const double base = r.baseline().outcome.evaluation.objective;
    std::printf("  %s = %.6e (job's own controller: %.6e", tune::objective_label(job).c_str(), best,
                base);
    if (std::isfinite(best) && std::isfinite(base) && base > 0)
      std::printf(", %.3g %% %s", 100 * std::abs(base - best) / base,
                  best <= base ? "lower" : "higher");
    std::printf("); fitness J = %.6g\n", r.optimization.best_fitness);
    if (r.scenarios > r.listed_scenarios)
      std::printf("  over %zu scenarios: %zu listed, %zu ensemble members; %d unrecoverable%s\n",
                  r.scenarios, r.listed_scenarios, r.scenarios - r.listed_scenarios,
                  r.unrecoverable, r.left_out > 0 ? ", left out of the objective" : "");
    if (const std::string nf = tune::noise_floor_sentence(r); !nf.empty())
      std::printf("  %s\n", nf.c_str());
    std::printf("  %lld simulations on %d thread%s in %.2f s\n",
                static_cast<long long>(r.simulations), r.threads, r.threads == 1 ? "" : "s", wall);
    std::printf(
        "  wrote %s/{gains.json, history.csv, trials.csv, comparison.json, comparison.md, "
        "job.json, run.json%s} and trajectories/\n",
        out.c_str(), o.baseline ? ", history-random.csv" : "");
  }
  const int report_status = o.report ? render_run_report(out.string(), "html", g.quiet) : 0;
  // Gains that diverge on what the objective counts must not reach a spacecraft: the files stay
  // for diagnosis (and the gains loader refuses them), and the exit status says so, --quiet or
  // not, with a code of its own (3) that scripts can tell from an internal error (1).
  if (r.optimization.best_fitness < 0.0) {
    std::fprintf(stderr,
                 "ftctune: error: no candidate met the job's hard goals (total violation %.6g, "
                 "see trials.csv): %s/gains.json must not be deployed; relax an at_most or "
                 "widen tuning.parameters\n",
                 r.best().outcome.evaluation.violation, out.c_str());
    return 3;
  }
  if (!(r.optimization.best_fitness > 0.0)) {
    std::fprintf(stderr,
                 "ftctune: error: every candidate diverged (fitness 0): %s/gains.json holds a "
                 "diverging controller and must not be deployed; narrow "
                 "tuning.parameters or check the scenarios\n",
                 out.c_str());
    return 3;
  }
  return report_status;
}

}  // namespace

void add_run_command(CLI::App& app, const Globals& g, Action& action) {
  auto opts = std::make_shared<RunCliOptions>();
  CLI::App* sub = app.add_subcommand("run", "Tune a job's controller and write the gains file");
  sub->add_option("job", opts->job, "Job file (ftctune.job/1)")->required();
  sub->add_option("--out", opts->out, "Output directory (default out/<job name>)")
      ->check(output_directory());
  sub->add_option("--threads", opts->threads, "Worker threads (default: all cores)")
      ->check(CLI::Range(0, 4096));
  sub->add_option("--seed", opts->seed, "Seed instead of the job's tuning.seed")
      ->check(seed_value());
  sub->add_flag(
      "--baseline", opts->baseline,
      "Also run random search with the same budget (history-random.csv, drawn in Fig. 5)");
  sub->add_flag("--report", opts->report, "Then draw the figures and report.html (ftctune report)");
  sub->add_flag("--force", opts->force, "Replace the run in an output directory that holds one");
  CLI::Option* checkpoint = sub->add_flag(
      "--checkpoint", opts->checkpoint,
      "Write <out>/checkpoint.json after every iteration (default: once the run looks like "
      "taking over a minute)");
  sub->add_flag("--no-checkpoint", opts->no_checkpoint, "Never write a checkpoint")
      ->excludes(checkpoint);
  sub->add_flag("--resume", opts->resume,
                "Continue the interrupted run in --out (or out/<job name>) from its checkpoint; "
                "without one, start from the first iteration")
      ->excludes("--force");
  sub->callback([&action, &g, opts] { action = [&g, opts] { return run_tuning(*opts, g); }; });
}

}  // namespace ftc::cli
