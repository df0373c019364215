#include "ftc/tune/service/job_store.hpp"

#include <fcntl.h>
#include <sqlite3.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <random>
#include <stdexcept>

#include "ftc/sim/input_error.hpp"
#include "service/store_vfs.hpp"

namespace ftc::tune {

namespace {

std::string now_iso() {
  using namespace std::chrono;
  const auto now = system_clock::now();
  const std::time_t t = system_clock::to_time_t(now);
  const auto ms = duration_cast<milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<int>(ms));
  return buf;
}

std::string new_id() {
  static thread_local std::mt19937_64 gen{std::random_device{}()};
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(gen()));
  return buf;
}

constexpr const char* kSchema = R"sql(
CREATE TABLE IF NOT EXISTS jobs (
  seq               INTEGER PRIMARY KEY AUTOINCREMENT,
  id                TEXT NOT NULL UNIQUE,
  name              TEXT NOT NULL,
  status            TEXT NOT NULL,
  job_json          TEXT NOT NULL,
  idempotency_key   TEXT UNIQUE,
  created_at        TEXT NOT NULL,
  started_at        TEXT NOT NULL DEFAULT '',
  finished_at       TEXT NOT NULL DEFAULT '',
  updated_at        TEXT NOT NULL,
  iteration         INTEGER NOT NULL DEFAULT -1,
  iterations        INTEGER NOT NULL,
  evaluations       INTEGER NOT NULL DEFAULT 0,
  total_evaluations INTEGER NOT NULL,
  best_fitness      REAL,
  best              TEXT NOT NULL DEFAULT '{}',
  error             TEXT NOT NULL DEFAULT '',
  cancel_requested  INTEGER NOT NULL DEFAULT 0,
  attempts          INTEGER NOT NULL DEFAULT 0,
  checkpoint        TEXT,
  client            TEXT NOT NULL DEFAULT '',
  objective         TEXT NOT NULL DEFAULT '',
  warnings          INTEGER NOT NULL DEFAULT 0
);
CREATE INDEX IF NOT EXISTS jobs_by_status ON jobs(status, seq);
-- The trials of a running job, one row per iteration, appended beside its checkpoint.
CREATE TABLE IF NOT EXISTS checkpoint_trials (
  job_id    TEXT NOT NULL,
  iteration INTEGER NOT NULL,
  trials    TEXT NOT NULL,
  PRIMARY KEY (job_id, iteration)
);
-- What the store knows about itself; 'probe' is rewritten to learn whether the disk takes writes.
CREATE TABLE IF NOT EXISTS meta (
  key   TEXT PRIMARY KEY,
  value TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS artifacts (
  job_id  TEXT NOT NULL,
  name    TEXT NOT NULL,
  content BLOB NOT NULL,
  PRIMARY KEY (job_id, name)
);
)sql";

constexpr const char* kColumns =
    "id, seq, name, status, created_at, started_at, finished_at, updated_at, iteration, "
    "iterations, evaluations, total_evaluations, best_fitness, best, error, cancel_requested, "
    "attempts, objective, warnings";

}  // namespace

bool StoreError::full() const { return code_ == SQLITE_FULL; }

bool StoreError::transient() const {
  switch (code_) {
    case SQLITE_FULL:
    case SQLITE_IOERR:
    case SQLITE_BUSY:
    case SQLITE_LOCKED:
    case SQLITE_NOMEM:
    case SQLITE_READONLY:
    case SQLITE_CANTOPEN:
    case SQLITE_PROTOCOL:
      return true;
    default:
      return false;
  }
}

std::string JobStore::timestamp() { return now_iso(); }

const char* to_string(JobStatus s) {
  switch (s) {
    case JobStatus::queued:
      return "queued";
    case JobStatus::running:
      return "running";
    case JobStatus::succeeded:
      return "succeeded";
    case JobStatus::failed:
      return "failed";
    case JobStatus::cancelled:
      return "cancelled";
  }
  return "?";
}

std::optional<JobStatus> job_status_from_string(std::string_view s) {
  for (JobStatus j : {JobStatus::queued, JobStatus::running, JobStatus::succeeded,
                      JobStatus::failed, JobStatus::cancelled})
    if (s == to_string(j)) return j;
  return std::nullopt;
}

// A prepared statement; binds by 1-based index, steps, reads columns, finalizes on scope exit.
class JobStore::Statement {
 public:
  Statement(sqlite3* db, const char* sql) : db_(db) {
    if (const int rc = sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr); rc != SQLITE_OK)
      fail(rc, "prepare: ");
  }
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement& bind(int i, const std::string& v) {
    sqlite3_bind_text(stmt_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
    return *this;
  }
  // Not copied (a result file can be a few hundred MB): `v` must outlive the statement.
  Statement& bind_blob(int i, const std::string& v) {
    sqlite3_bind_blob64(stmt_, i, v.data(), v.size(), SQLITE_STATIC);
    return *this;
  }
  Statement& bind(int i, std::int64_t v) {
    sqlite3_bind_int64(stmt_, i, v);
    return *this;
  }
  Statement& bind(int i, double v) {
    sqlite3_bind_double(stmt_, i, v);
    return *this;
  }
  Statement& bind_null(int i) {
    sqlite3_bind_null(stmt_, i);
    return *this;
  }
  bool step() {  // true while a row is available
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    fail(rc, "");
  }
  std::string text(int c) const {
    const auto* p = reinterpret_cast<const char*>(sqlite3_column_text(stmt_, c));
    return p ? std::string(p, static_cast<std::size_t>(sqlite3_column_bytes(stmt_, c)))
             : std::string();
  }
  std::string blob(int c) const {
    const auto* p = static_cast<const char*>(sqlite3_column_blob(stmt_, c));
    return p ? std::string(p, static_cast<std::size_t>(sqlite3_column_bytes(stmt_, c)))
             : std::string();
  }
  std::int64_t integer(int c) const { return sqlite3_column_int64(stmt_, c); }
  bool is_null(int c) const { return sqlite3_column_type(stmt_, c) == SQLITE_NULL; }
  double real(int c) const { return sqlite3_column_double(stmt_, c); }

  JobRecord record() const {
    JobRecord r;
    r.id = text(0);
    r.seq = integer(1);
    r.name = text(2);
    r.status = job_status_from_string(text(3)).value_or(JobStatus::failed);
    r.created_at = text(4);
    r.started_at = text(5);
    r.finished_at = text(6);
    r.updated_at = text(7);
    r.iteration = static_cast<int>(integer(8));
    r.iterations = static_cast<int>(integer(9));
    r.evaluations = integer(10);
    r.total_evaluations = integer(11);
    if (!is_null(12)) r.best_fitness = real(12);
    r.best = nlohmann::json::parse(text(13), nullptr, false);
    r.error = text(14);
    r.cancel_requested = integer(15) != 0;
    r.attempts = static_cast<int>(integer(16));
    r.objective = text(17);
    r.warnings = static_cast<int>(integer(18));
    return r;
  }

 private:
  [[noreturn]] void fail(int rc, const char* what) const {
    throw StoreError(std::string("job store: ") + what + sqlite3_errmsg(db_), rc & 0xff);
  }
  sqlite3* db_;
  sqlite3_stmt* stmt_ = nullptr;
};

JobStore::JobStore(const std::filesystem::path& directory) {
  namespace fs = std::filesystem;
  // Jobs, results and the queue are the server owner's alone: a directory created here is 0700
  // and the files are 0600 (SQLite gives its -wal and -shm files the database file's mode).
  // A directory the user already had (even `--store .`) keeps its mode.
  if (fs::create_directories(directory))
    fs::permissions(directory, fs::perms::owner_all, fs::perm_options::replace);
  // One server per store: two would run the same queue and jobs twice.
  const std::string lock = (directory / "lock").string();
  lock_fd_ = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0600);
  if (lock_fd_ < 0)
    throw InputError(
        "--store", "",
        std::string("cannot open ").append(lock).append(": ").append(std::strerror(errno)));
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    ::close(lock_fd_);
    throw InputError("--store", "",
                     directory.string() +
                         " is in use by another ftctune serve (one server per "
                         "store); stop it or give another --store");
  }
  ::fchmod(lock_fd_, 0600);
  db_path_ = directory / "ftctune.db";
  if (const int fd = ::open(db_path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0600); fd >= 0) {
    ::fchmod(fd, 0600);
    ::close(fd);
  }
  if (sqlite3_open_v2(db_path_.c_str(), &db_,
                      SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX,
                      service_detail::store_vfs()) != SQLITE_OK) {
    const std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    ::close(lock_fd_);
    throw std::runtime_error("cannot open " + db_path_.string() + ": " + msg);
  }
  sqlite3_busy_timeout(db_, 5000);
  exec("PRAGMA journal_mode=WAL");
  exec("PRAGMA synchronous=FULL");
  exec(kSchema);
  // Columns a store made by an older server lacks: the client (before the queue quota), what J
  // measures and the finished run's warnings (before the jobs list grouped and badged them).
  for (const auto& [column, definition] :
       {std::pair<const char*, const char*>{"client", "TEXT NOT NULL DEFAULT ''"},
        {"objective", "TEXT NOT NULL DEFAULT ''"},
        // -1: not counted (its gains file says; the dashboard's job page counts them there).
        {"warnings", "INTEGER NOT NULL DEFAULT -1"}}) {
    bool has = false;
    {
      Statement q(db_, "SELECT 1 FROM pragma_table_info('jobs') WHERE name = ?");
      q.bind(1, std::string(column));
      has = q.step();
    }
    if (!has)
      exec((std::string("ALTER TABLE jobs ADD COLUMN ") + column + " " + definition).c_str());
  }
}

JobStore::~JobStore() {
  sqlite3_close(db_);
  if (lock_fd_ >= 0) ::close(lock_fd_);
}

void JobStore::exec(const char* sql) {
  char* err = nullptr;
  if (const int rc = sqlite3_exec(db_, sql, nullptr, nullptr, &err); rc != SQLITE_OK) {
    const std::string msg = err ? err : "unknown error";
    sqlite3_free(err);
    throw StoreError(std::string("job store: ") + msg, rc & 0xff);
  }
}

// `synced` commits wait for the disk (synchronous=FULL); the others (progress, checkpoints) are
// only written to the WAL file, which survives a killed process but maybe not a power cut —
// losing a checkpoint then just means resuming one iteration earlier.
template <class F>
auto JobStore::transaction(F&& body, bool synced) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!synced) exec("PRAGMA synchronous=NORMAL");
  struct Restore {
    JobStore* self;
    bool active;
    ~Restore() {
      if (active) sqlite3_exec(self->db_, "PRAGMA synchronous=FULL", nullptr, nullptr, nullptr);
    }
  } restore{this, !synced};
  exec("BEGIN IMMEDIATE");
  try {
    if constexpr (std::is_void_v<decltype(body())>) {
      body();
      exec("COMMIT");
    } else {
      auto result = body();
      exec("COMMIT");
      return result;
    }
  } catch (...) {
    sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

Submitted JobStore::submit(const Submission& s, const QueueQuota& quota) {
  return transaction([&] {
    Submitted out;
    if (s.idempotency_key) {
      Statement q(
          db_,
          (std::string("SELECT ") + kColumns + " FROM jobs WHERE idempotency_key = ?").c_str());
      q.bind(1, *s.idempotency_key);
      if (q.step()) {
        out.record = q.record();
        return out;
      }
    }
    const auto queued = [&](const std::string* client) {
      Statement q(db_, client ? "SELECT COUNT(*) FROM jobs WHERE status = 'queued' AND client = ?"
                              : "SELECT COUNT(*) FROM jobs WHERE status = 'queued'");
      if (client) q.bind(1, *client);
      q.step();
      return q.integer(0);
    };
    if (quota.per_client > 0)
      if (const std::int64_t n = queued(&s.client); n >= quota.per_client) {
        out.refused = Submitted::Refusal::client_quota;
        out.queued = n;
        return out;
      }
    if (quota.total > 0)
      if (const std::int64_t n = queued(nullptr); n >= quota.total) {
        out.refused = Submitted::Refusal::queue_full;
        out.queued = n;
        return out;
      }
    const std::string now = now_iso();
    const std::string id = new_id();
    Statement ins(db_,
                  "INSERT INTO jobs (id, name, status, job_json, idempotency_key, created_at, "
                  "updated_at, iterations, total_evaluations, client, objective, warnings) "
                  "VALUES (?, ?, 'queued', ?, ?, ?, ?, ?, ?, ?, ?, 0)");
    ins.bind(1, id).bind(2, s.name).bind(3, s.job_json);
    if (s.idempotency_key)
      ins.bind(4, *s.idempotency_key);
    else
      ins.bind_null(4);
    ins.bind(5, now).bind(6, now).bind(7, std::int64_t{s.iterations}).bind(8, s.total_evaluations);
    ins.bind(9, s.client).bind(10, s.objective);
    ins.step();
    out.record = *select_job(id);
    out.created = true;
    return out;
  });
}

std::optional<JobRecord> JobStore::get(const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  return select_job(id);
}

std::optional<JobRecord> JobStore::select_job(const std::string& id) {
  Statement q(db_, (std::string("SELECT ") + kColumns + " FROM jobs WHERE id = ?").c_str());
  q.bind(1, id);
  if (!q.step()) return std::nullopt;
  return q.record();
}

void JobStore::set_finished(const std::string& id, JobStatus status, const std::string& error,
                            const std::string& finished_at) {
  const std::string now = now_iso();
  Statement u(db_,
              "UPDATE jobs SET status = ?, error = ?, finished_at = ?, updated_at = ?, "
              "checkpoint = NULL WHERE id = ?");
  u.bind(1, std::string(to_string(status))).bind(2, error);
  u.bind(3, finished_at.empty() ? now : finished_at).bind(4, now).bind(5, id);
  u.step();
  Statement d(db_, "DELETE FROM checkpoint_trials WHERE job_id = ?");
  d.bind(1, id);
  d.step();
}

std::string JobStore::job_json(const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  Statement q(db_, "SELECT job_json FROM jobs WHERE id = ?");
  q.bind(1, id);
  return q.step() ? q.text(0) : std::string();
}

namespace {

// " WHERE …" for a status and a name filter ("" when neither), bound from index 1 by bind_filter.
std::string filter_sql(std::optional<JobStatus> status, const std::string& name) {
  std::string w;
  if (status) w += " WHERE status = ?";
  if (!name.empty()) w += std::string(status ? " AND" : " WHERE") + " instr(name, ?) > 0";
  return w;
}

}  // namespace

std::vector<JobRecord> JobStore::list(std::optional<JobStatus> status, int limit, int offset,
                                      const std::string& name) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string sql = std::string("SELECT ") + kColumns + " FROM jobs" +
                          filter_sql(status, name) + " ORDER BY seq DESC LIMIT ? OFFSET ?";
  Statement q(db_, sql.c_str());
  int i = 1;
  if (status) q.bind(i++, std::string(to_string(*status)));
  if (!name.empty()) q.bind(i++, name);
  q.bind(i, std::int64_t{limit});
  q.bind(i + 1, std::int64_t{offset});
  std::vector<JobRecord> out;
  while (q.step()) out.push_back(q.record());
  return out;
}

std::int64_t JobStore::count(std::optional<JobStatus> status, const std::string& name) {
  std::lock_guard<std::mutex> lock(mutex_);
  Statement q(db_, ("SELECT COUNT(*) FROM jobs" + filter_sql(status, name)).c_str());
  int i = 1;
  if (status) q.bind(i++, std::string(to_string(*status)));
  if (!name.empty()) q.bind(i, name);
  q.step();
  return q.integer(0);
}

std::optional<JobRecord> JobStore::claim_next() {
  return transaction([&]() -> std::optional<JobRecord> {
    Statement q(db_, "SELECT id FROM jobs WHERE status = 'queued' ORDER BY seq LIMIT 1");
    if (!q.step()) return std::nullopt;
    const std::string id = q.text(0);
    const std::string now = now_iso();
    Statement u(db_,
                "UPDATE jobs SET status = 'running', attempts = attempts + 1, updated_at = ?, "
                "started_at = CASE WHEN started_at = '' THEN ? ELSE started_at END WHERE id = ?");
    u.bind(1, now).bind(2, now).bind(3, id);
    u.step();
    return select_job(id);
  });
}

void JobStore::record_progress(const std::string& id, int iteration, std::int64_t evaluations,
                               double best_fitness, const nlohmann::json& best,
                               const std::string& checkpoint, const std::string& new_trials) {
  transaction(
      [&] {
        Statement t(db_, "INSERT OR REPLACE INTO checkpoint_trials VALUES (?, ?, ?)");
        t.bind(1, id).bind(2, std::int64_t{iteration}).bind(3, new_trials);
        t.step();
        Statement u(db_,
                    "UPDATE jobs SET iteration = ?, evaluations = ?, best_fitness = ?, best = ?, "
                    "checkpoint = ?, updated_at = ? WHERE id = ?");
        u.bind(1, std::int64_t{iteration}).bind(2, evaluations);
        if (std::isfinite(best_fitness))
          u.bind(3, best_fitness);
        else
          u.bind_null(3);
        u.bind(4, best.dump()).bind(5, checkpoint).bind(6, now_iso()).bind(7, id);
        u.step();
      },
      /*synced=*/false);
}

std::vector<std::string> JobStore::checkpoint_trials(const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  Statement q(db_, "SELECT trials FROM checkpoint_trials WHERE job_id = ? ORDER BY iteration");
  q.bind(1, id);
  std::vector<std::string> out;
  while (q.step()) out.push_back(q.text(0));
  return out;
}

std::optional<JobStore::Checkpoint> JobStore::checkpoint_with_trials(const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  Checkpoint c;
  {
    Statement q(db_, "SELECT checkpoint, iteration FROM jobs WHERE id = ?");
    q.bind(1, id);
    if (!q.step() || q.is_null(0)) return std::nullopt;
    c.optimizer = q.text(0);
    c.iteration = static_cast<int>(q.integer(1));
  }
  Statement t(db_, "SELECT trials FROM checkpoint_trials WHERE job_id = ? ORDER BY iteration");
  t.bind(1, id);
  while (t.step()) c.trials.push_back(t.text(0));
  return c;
}

std::optional<std::string> JobStore::checkpoint(const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  Statement q(db_, "SELECT checkpoint FROM jobs WHERE id = ?");
  q.bind(1, id);
  if (!q.step() || q.is_null(0)) return std::nullopt;
  return q.text(0);
}

void JobStore::finish_succeeded(const std::string& id,
                                const std::map<std::string, std::string>& artifacts,
                                const std::string& finished_at, int warnings) {
  transaction([&] {
    for (const auto& [name, content] : artifacts) insert_artifact(id, name, content);
    set_finished(id, JobStatus::succeeded, "", finished_at);
    Statement u(db_, "UPDATE jobs SET warnings = ? WHERE id = ?");
    u.bind(1, std::int64_t{warnings}).bind(2, id);
    u.step();
  });
}

void JobStore::finish_failed(const std::string& id, const std::string& error,
                             const std::string& finished_at) {
  transaction([&] { set_finished(id, JobStatus::failed, error, finished_at); });
}

void JobStore::finish_cancelled(const std::string& id, const std::string& finished_at,
                                const std::map<std::string, std::string>& artifacts) {
  transaction([&] {
    for (const auto& [name, content] : artifacts) insert_artifact(id, name, content);
    set_finished(id, JobStatus::cancelled, "", finished_at);
  });
}

void JobStore::requeue(const std::string& id) {
  transaction([&] {
    Statement u(
        db_,
        "UPDATE jobs SET status = 'queued', updated_at = ? WHERE id = ? AND status = 'running'");
    u.bind(1, now_iso()).bind(2, id);
    u.step();
  });
}

std::optional<JobRecord> JobStore::request_cancel(const std::string& id) {
  return transaction([&]() -> std::optional<JobRecord> {
    const std::string now = now_iso();
    Statement q(db_,
                "UPDATE jobs SET status = 'cancelled', finished_at = ?, updated_at = ?, "
                "cancel_requested = 1 WHERE id = ? AND status = 'queued'");
    q.bind(1, now).bind(2, now).bind(3, id);
    q.step();
    Statement r(
        db_,
        "UPDATE jobs SET cancel_requested = 1, updated_at = ? WHERE id = ? AND status = 'running'");
    r.bind(1, now).bind(2, id);
    r.step();
    return select_job(id);
  });
}

bool JobStore::cancel_requested(const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  Statement q(db_, "SELECT cancel_requested FROM jobs WHERE id = ?");
  q.bind(1, id);
  return q.step() && q.integer(0) != 0;
}

JobStore::Removal JobStore::remove(const std::string& id) {
  return transaction([&] {
    std::string status;
    {
      Statement q(db_, "SELECT status FROM jobs WHERE id = ?");
      q.bind(1, id);
      if (!q.step()) return Removal::not_found;
      status = q.text(0);
    }
    if (status == "queued" || status == "running") return Removal::active;
    for (const char* sql :
         {"DELETE FROM artifacts WHERE job_id = ?",
          "DELETE FROM checkpoint_trials WHERE job_id = ?", "DELETE FROM jobs WHERE id = ?"}) {
      Statement d(db_, sql);
      d.bind(1, id);
      d.step();
    }
    return Removal::removed;
  });
}

JobStore::Recovery JobStore::recover(int max_attempts) {
  return transaction([&] {
    Recovery r;
    std::vector<std::pair<std::string, int>> given_up;
    {
      Statement q(db_, "SELECT id, attempts FROM jobs WHERE status = 'running' AND attempts >= ?");
      q.bind(1, std::int64_t{max_attempts});
      while (q.step()) given_up.emplace_back(q.text(0), static_cast<int>(q.integer(1)));
    }
    for (const auto& [id, attempts] : given_up) {
      set_finished(id, JobStatus::failed,
                   "given up after " + std::to_string(attempts) +
                       " starts: the server stopped while it ran each time (a crash, a kill or "
                       "running out of memory); not retried again");
      ++r.failed;
    }
    Statement u(db_, "UPDATE jobs SET status = 'queued', updated_at = ? WHERE status = 'running'");
    u.bind(1, now_iso());
    u.step();
    r.requeued = sqlite3_changes(db_);
    return r;
  });
}

void JobStore::probe() {
  transaction([&] {
    Statement u(db_, "INSERT OR REPLACE INTO meta (key, value) VALUES ('probe', ?)");
    u.bind(1, now_iso());
    u.step();
  });
}

std::optional<std::string> JobStore::artifact(const std::string& id, const std::string& name) {
  std::lock_guard<std::mutex> lock(mutex_);
  Statement q(db_, "SELECT content FROM artifacts WHERE job_id = ? AND name = ?");
  q.bind(1, id).bind(2, name);
  if (!q.step()) return std::nullopt;
  return q.blob(0);
}

std::map<std::string, std::string> JobStore::artifacts(const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  Statement q(db_, "SELECT name, content FROM artifacts WHERE job_id = ?");
  q.bind(1, id);
  std::map<std::string, std::string> out;
  while (q.step()) out[q.text(0)] = q.blob(1);
  return out;
}

std::map<std::string, std::uint64_t> JobStore::artifact_sizes(const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  Statement q(db_, "SELECT name, length(content) FROM artifacts WHERE job_id = ?");
  q.bind(1, id);
  std::map<std::string, std::uint64_t> out;
  while (q.step()) out[q.text(0)] = static_cast<std::uint64_t>(q.integer(1));
  return out;
}

void JobStore::put_artifact(const std::string& id, const std::string& name,
                            const std::string& content) {
  transaction([&] { insert_artifact(id, name, content); });
}

void JobStore::insert_artifact(const std::string& id, const std::string& name,
                               const std::string& content) {
  Statement a(db_, "INSERT OR REPLACE INTO artifacts (job_id, name, content) VALUES (?, ?, ?)");
  a.bind(1, id).bind(2, name).bind_blob(3, content);
  a.step();
}

}  // namespace ftc::tune
