#pragma once
// The output directory of a run (`ftctune run`, and the run API in api/api.hpp): where a run
// writes by default, the lock that keeps two runs out of one directory, the staging directory its
// files are written into first, and the move that puts them in place of an earlier run (undone
// on failure). Also the latest run of a job, which evaluate, landscape and report go beside.
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "ftc/tune/job/job.hpp"

namespace ftc::tune {

// Where the run API's messages for people go (the CLI logs them; a library user may drop them).
enum class LogLevel { info, warn };
using RunLog = std::function<void(LogLevel, const std::string&)>;
// Passes a message to the log when there is one.
inline void say(const RunLog& log, LogLevel level, const std::string& message) {
  if (log) log(level, message);
}

// Default output directory of a job: out/<job name>.
std::filesystem::path default_out_dir(const std::string& job_name);

// The latest finished run of a job: of out/<name>, out/<name>-2, -3, ... (where `run` writes
// when the earlier ones hold a run), the one whose gains.json is newest among those of this job
// (the same canonical SHA-256), else the newest of any job of that name. Empty when there is
// none. `why` says which it chose and why, for the log.
std::filesystem::path latest_run_dir(const Job& job, std::string* why = nullptr);

// Why `dir` cannot be made into a directory to write in ("" when it can): it, or the nearest of
// its ancestors that exists, must be a directory this process may write to.
std::string directory_problem(const std::filesystem::path& dir);

// Where a run stages its files inside its directory, followed by the process id; where a --force
// run sets the run it replaces aside.
inline constexpr const char* kStagingPrefix = ".staging-";
inline constexpr const char* kPreviousPrefix = ".previous-";

// What a run writes: with --force these names of the earlier run make way for the new run's,
// so that no figure or trajectory of the earlier run is left beside the new ones.
inline constexpr const char* kRunEntries[] = {
    "gains.json",      "history.csv",   "trials.csv",  "history-random.csv",
    "comparison.json", "comparison.md", "run.json",    "job.json",
    "report.html",     "figures",       "trajectories"};

// A new directory out/PREFIX<pid>, or out/PREFIX<pid>-K when that name is taken: a directory
// kept from an earlier run (which the next run names for recovery) is never reused, even when
// the process id comes round again, as it does for PID 1 in a container.
std::filesystem::path unique_dir(const std::filesystem::path& out, const char* prefix);

// Whether a directory holds an ftctune run: a finished one (run.json and gains.json are what
// `run` writes first and last) or an interrupted one (its checkpoint).
bool holds_run(const std::filesystem::path& dir);
// A finished run removes its checkpoint, so one that is there was left by a run that did not
// finish (perhaps one replacing a finished run with --force).
bool holds_interrupted_run(const std::filesystem::path& dir);

// An exclusive lock on an output directory (created if need be) for the whole run: flock on the
// directory itself, released when the lock is destroyed or the process ends, however it ends.
// Two runs into one directory would interleave their files. On a file system that cannot lock,
// the run goes on unlocked (with a warning to `log`).
class DirectoryLock {
 public:
  explicit DirectoryLock(const std::filesystem::path& dir, const RunLog& log = {});
  ~DirectoryLock();
  DirectoryLock(const DirectoryLock&) = delete;
  DirectoryLock& operator=(const DirectoryLock&) = delete;
  bool held() const { return fd_ >= 0; }

 private:
  int fd_ = -1;
};

// Where a run writes, locked for the run. A run is never written over silently: a given
// directory (`given`) that holds a run, or that another run is writing, is refused (InputError,
// source "--out"); the default out/<name> moves on to out/<name>-2, -3, ... (with a warning, and
// `out` is changed); `force` replaces the run (its files are cleared only once the new run has
// finished, see replace_run). Other files in the directory (an evaluation, a landscape, fetched
// service results) are not a run and are left alone.
std::unique_ptr<DirectoryLock> claim_run_directory(std::filesystem::path& out, bool given,
                                                   bool force, const RunLog& log = {});

// What runs stopped before they finished left behind (only a run holding the lock writes
// there, so any found by the holder are left over). A staging directory without gains.json was
// stopped while its files were written, and goes. One with gains.json holds a whole run that was
// stopped while moving into place, and a .previous-PID directory the run a --force was
// replacing: both are kept, and named in a warning, for the user to recover.
void handle_leftovers(const std::filesystem::path& out, const RunLog& log = {});

// The move phase: the new run in `staging` takes the place of the earlier one in `out`. The
// earlier run's entries (when `replace`) are first set aside into .previous-PID, then the new
// ones (`entries`, gains.json last) move in by rename; only then is the earlier run deleted. A
// failure on the way undoes every move made, so `out` holds the earlier run as it was; if even
// that fails, both directories are kept and the error (OutputError) names them.
void replace_run(const std::filesystem::path& out, const std::filesystem::path& staging,
                 const std::vector<std::string>& entries, bool replace);

}  // namespace ftc::tune
