// The output directory of a run: default place, lock, staging and the move into place.
#include "ftc/tune/api/run_directory.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>

#include "ftc/sim/input_error.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/run/checkpoint.hpp"
#include "ftc/tune/run/tuning_run.hpp"

namespace ftc::tune {

namespace fs = std::filesystem;
using nlohmann::json;

fs::path default_out_dir(const std::string& job_name) { return fs::path("out") / job_name; }

fs::path latest_run_dir(const Job& job, std::string* why) {
  const fs::path base = default_out_dir(job.name);
  const std::string prefix = base.filename().string() + "-";
  struct Found {
    fs::path dir;
    fs::file_time_type time;
    int suffix = 1;
    bool same_job = false;
  };
  std::vector<Found> runs;
  std::error_code ec;
  const auto consider = [&](const fs::path& dir, int suffix) {
    const fs::path gains = dir / "gains.json";
    std::error_code e;
    const fs::file_time_type t = fs::last_write_time(gains, e);
    if (e || !fs::is_regular_file(gains, e)) return;
    bool same = false;
    if (const std::optional<std::string> text = read_file(gains)) {
      const json g = json::parse(*text, nullptr, false);
      same = g.is_object() && g.contains("job") && g["job"].is_object() &&
             g["job"].value("sha256", "") == canonical_job_sha256(job);
    }
    runs.push_back({dir, t, suffix, same});
  };
  consider(base, 1);
  for (fs::directory_iterator it(base.parent_path(), ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.size() > 6 || digits.find_first_not_of("0123456789") != std::string::npos ||
        digits[0] == '0')
      continue;
    consider(it->path(), std::stoi(digits));
  }
  if (runs.empty()) {
    if (why) *why = "no run of job " + job.name + " in " + base.parent_path().string();
    return {};
  }
  const bool any_same =
      std::any_of(runs.begin(), runs.end(), [](const Found& f) { return f.same_job; });
  const Found* best = nullptr;
  for (const Found& f : runs)
    if ((f.same_job || !any_same) &&
        (!best || f.time > best->time || (f.time == best->time && f.suffix > best->suffix)))
      best = &f;
  if (why)
    *why =
        "the latest run of job " + job.name + " is " + best->dir.string() +
        (any_same ? "" : " (of another version of the job file: its SHA-256 differs)") +
        (runs.size() > 1 ? " (newest gains.json of " + std::to_string(runs.size()) + " runs)" : "");
  return best->dir;
}

std::string directory_problem(const fs::path& dir) {
  std::error_code ec;
  fs::path at = fs::absolute(dir, ec);
  if (ec) return ec.message();
  while (!fs::exists(at, ec) && at.has_parent_path() && at.parent_path() != at)
    at = at.parent_path();
  if (!fs::is_directory(at, ec))
    return at == fs::absolute(dir, ec) ? dir.string() + " exists and is not a directory"
                                       : std::string("cannot create ")
                                             .append(dir.string())
                                             .append(": ")
                                             .append(at.string())
                                             .append(" is not a directory");
  if (::access(at.c_str(), W_OK | X_OK) != 0)
    return std::string("cannot write in ")
        .append(at.string())
        .append(": ")
        .append(std::strerror(errno));
  return "";
}

fs::path unique_dir(const fs::path& out, const char* prefix) {
  const std::string base = std::string(prefix) + std::to_string(::getpid());
  for (unsigned k = 0;; ++k) {
    const fs::path p = out / (k ? base + "-" + std::to_string(k) : base);
    if (::mkdir(p.c_str(), 0755) == 0) return p;
    if (errno != EEXIST)
      throw fs::filesystem_error("cannot create the directory", p,
                                 std::error_code(errno, std::generic_category()));
  }
}

bool holds_run(const fs::path& d) {
  std::error_code ec;
  return fs::exists(d / "gains.json", ec) || fs::exists(d / "run.json", ec) ||
         fs::exists(d / kCheckpointFile, ec);
}

bool holds_interrupted_run(const fs::path& d) {
  std::error_code ec;
  return fs::exists(d / kCheckpointFile, ec);
}

DirectoryLock::DirectoryLock(const fs::path& dir, const RunLog& log) {
  fs::create_directories(dir);
  fd_ = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd_ < 0)
    throw fs::filesystem_error("cannot open", dir, std::error_code(errno, std::generic_category()));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    if (errno == EWOULDBLOCK) {
      ::close(fd_);
      fd_ = -1;
    } else {
      // Some network and cluster file systems cannot lock (NFS without lockd, Lustre
      // without flock): run unlocked rather than call that another run.
      say(log, LogLevel::warn,
          "cannot lock " + dir.string() + " (" + std::strerror(errno) +
              "): a second run into it would not be noticed");
    }
  }
}

DirectoryLock::~DirectoryLock() {
  if (fd_ >= 0) ::close(fd_);
}

std::unique_ptr<DirectoryLock> claim_run_directory(fs::path& out, bool given, bool force,
                                                   const RunLog& log) {
  const fs::path wanted = out;
  for (int k = 2;; ++k) {
    if (!holds_run(out) || force) {
      auto lock = std::make_unique<DirectoryLock>(out, log);
      // Another run may have finished there between the look and the lock.
      if (lock->held() && holds_run(out) && !force) lock.reset();
      if (lock && lock->held()) {
        if (out != wanted)
          say(log, LogLevel::warn,
              wanted.string() + " already holds a run or is in use: writing to " + out.string() +
                  " (--force replaces a run instead)");
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

void handle_leftovers(const fs::path& out, const RunLog& log) {
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
      say(log, LogLevel::warn,
          p.string() + " holds the whole files of a run stopped while it moved them into " +
              out.string() + ": kept (move them into " + out.string() +
              " to recover that run, or remove the directory)");
    } else if (name.rfind(kPreviousPrefix, 0) == 0) {
      say(log, LogLevel::warn,
          p.string() +
              " holds the earlier run that a --force run was replacing when it stopped: kept "
              "(move its files back into " +
              out.string() + " to recover that run, or remove the directory)");
    }
  }
}

void replace_run(const fs::path& out, const fs::path& staging,
                 const std::vector<std::string>& entries, bool replace) {
  fs::path previous;  // made when the first entry is set aside
  std::vector<std::string> set_aside, moved;
  try {
    if (replace && holds_run(out)) {
      for (const char* f : kRunEntries) {
        std::error_code ec;
        if (!fs::exists(fs::symlink_status(out / f, ec))) continue;
        if (set_aside.empty()) previous = unique_dir(out, kPreviousPrefix);
        move_into(out, previous, {f});
        set_aside.push_back(f);
      }
    }
    for (const std::string& e : entries) {
      move_into(staging, out, {e});
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
      throw OutputError(
          std::string(e.what()) + "; the new run's files are in " + staging.string() +
          (set_aside.empty() ? std::string() : " and the earlier run's in " + previous.string()) +
          ": move them back into " + out.string() + " by hand");
    if (!previous.empty()) fs::remove(previous, ec);
    fs::remove_all(staging, ec);
    sync_directory(out);
    throw;
  }
  std::error_code ec;
  if (!previous.empty()) fs::remove_all(previous, ec);
  fs::remove(staging, ec);
  sync_directory(out);
}

}  // namespace ftc::tune
