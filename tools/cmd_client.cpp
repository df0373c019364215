// Client commands of the tuning service: submit, status, fetch, cancel, jobs.
// Server from --server, else $FTCTUNE_SERVER, else http://127.0.0.1:8080; token from
// $FTCTUNE_TOKEN.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "cli.hpp"
#include "eta.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/run/documents.hpp"
#include "service/httplib.hpp"

namespace ftc::cli {
namespace {

using nlohmann::json;

struct ClientOptions {
  std::string server;
  bool json_output = false;
};

// A connection problem: one line, exit 1.
struct Unreachable : std::runtime_error {
  using std::runtime_error::runtime_error;
};
// The server answered with an error status.
struct ServerError : std::runtime_error {
  ServerError(int s, const std::string& m) : std::runtime_error(m), status(s) {}
  int status;
};

class Api {
 public:
  explicit Api(const ClientOptions& o) {
    url_ = o.server;
    if (url_.empty()) {
      const char* env = std::getenv("FTCTUNE_SERVER");
      url_ = env && *env ? env : "http://127.0.0.1:8080";
    }
    while (!url_.empty() && url_.back() == '/') url_.pop_back();
    client_ = std::make_unique<httplib::Client>(url_);
    if (!client_->is_valid()) throw InputError("--server", "", "not a valid server URL: " + url_);
    client_->set_connection_timeout(5, 0);
    client_->set_read_timeout(30, 0);
    client_->set_tcp_nodelay(true);  // no 40 ms wait per request on the kept-alive connection
    if (const char* token = std::getenv("FTCTUNE_TOKEN"); token && *token)
      client_->set_bearer_token_auth(token);
  }

  const std::string& url() const { return url_; }

  std::string get(const std::string& path) { return check(client_->Get(path.c_str()), path); }
  std::string post(const std::string& path, const std::string& body) {
    return check(client_->Post(path.c_str(), body, "application/json"), path);
  }
  std::string del(const std::string& path) { return check(client_->Delete(path.c_str()), path); }

 private:
  std::string check(const httplib::Result& r, const std::string& path) {
    if (!r)
      throw Unreachable("cannot reach the ftctune server at " + url_ + " (" +
                        httplib::to_string(r.error()) +
                        "); start one with `ftctune serve`, or point --server or FTCTUNE_SERVER "
                        "at a running one");
    if (r->status >= 400) {
      std::string msg = "HTTP " + std::to_string(r->status) + " from " + path;
      const json body = json::parse(r->body, nullptr, false);
      if (body.is_object() && body.contains("error")) {
        msg = body["error"].value("message", msg);
        if (body["error"].contains("details") && body["error"]["details"].is_array())
          for (const json& d : body["error"]["details"])
            if (d.is_object() && d.contains("path") && d.size() == 2)
              msg += "\n  " + d["path"].get<std::string>() + ": " + d["message"].get<std::string>();
      }
      throw ServerError(r->status, msg);
    }
    return r->body;
  }

  std::string url_;
  std::unique_ptr<httplib::Client> client_;
};

std::string describe(const json& j) {
  const json& p = j["progress"];
  std::string s = j["id"].get<std::string>() + "  " + j["name"].get<std::string>() + "  " +
                  j["status"].get<std::string>();
  // A succeeded run whose gains file warns (a saturated or unsettled loop, a value at a bound).
  if (j.contains("warnings") && j["warnings"].is_number_integer())
    if (const long long w = j["warnings"].get<long long>(); w > 0)
      s += " with " + std::to_string(w) + " warning" + (w == 1 ? "" : "s");
  if (!p["iteration"].is_null())
    s += "  iteration " + std::to_string(p["iteration"].get<int>()) + "/" +
         std::to_string(p["iterations"].get<int>());
  s += "  " + std::to_string(p["evaluations"].get<long long>()) + "/" +
       std::to_string(p["total_evaluations"].get<long long>()) + " evaluations";
  if (p["best"].is_object() && p["best"].contains("front")) {
    // A front's progress: its size so far, not one corner's J.
    const json& f = p["best"]["front"];
    const long long points = f.value("points", 0LL);
    s += "  front of " + std::to_string(points) + " point" + (points == 1 ? "" : "s") + " so far";
  } else if (!p["best_fitness"].is_null()) {
    char buf[48];
    std::snprintf(buf, sizeof buf, "  best J = %.6g", p["best_fitness"].get<double>());
    s += buf;
    for (auto it = p["best"].begin(); it != p["best"].end(); ++it) {
      std::snprintf(buf, sizeof buf, " %s = %.5g", it.key().c_str(), it.value().get<double>());
      s += buf;
    }
    // What J measures (a server older than this field does not say).
    if (const std::string what = j.value("objective", ""); !what.empty())
      s += "  (J: " + what + ")";
  }
  s += eta_text(j);  // a running job's: at the rate so far
  if (!j["error"].is_null()) s += "\n  error: " + j["error"].get<std::string>();
  if (j.contains("unstored") && j["unstored"].is_object())
    s += "\n  finished (" + j["unstored"]["status"].get<std::string>() + ") at " +
         j["unstored"]["finished_at"].get<std::string>() +
         "; its results wait in the server's memory until its store can write them";
  return s;
}

// Runs a client action, mapping failures to one line and an exit code.
int guarded(const std::function<int()>& body) {
  try {
    return body();
  } catch (const Unreachable& e) {
    std::fprintf(stderr, "ftctune: error: %s\n", e.what());
    return 1;
  } catch (const ServerError& e) {
    std::fprintf(stderr, "ftctune: error: %s\n", e.what());
    return e.status >= 500 ? 1 : 2;
  }
}

void print_json(const std::string& body) { std::printf("%s\n", json::parse(body).dump(2).c_str()); }

// A gains file of a job that has not finished (running, or cancelled) says so, once.
void note_partial(const std::string& id, const std::string& gains, bool quiet) {
  const json g = json::parse(gains, nullptr, false);
  if (quiet || !g.is_object() || !g.contains("optimizer") ||
      g["optimizer"].value("completed", true))
    return;
  std::fprintf(stderr,
               "ftctune: note: job %s has not finished all its iterations: its files are its "
               "results so far (gains.json records optimizer.completed false, which the gains "
               "loader refuses)\n",
               id.c_str());
}

// One folder name made of a name the server gave: letters, digits, '-', '_' and '.', not
// starting with a dot, at most 100 characters; "" when it is not one (a server may say
// anything: "../../.ssh", "/etc", ".." must not become a path).
std::string folder_name(const std::string& name) {
  if (name.empty() || name.size() > 100 || name.front() == '.') return "";
  for (const char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') return "";
  return name;
}

// Where a job's files go without -o: out/<job name>/service-<id>/, the job's name and id only
// as safe folder names (the id in place of an unsafe name; "job" for an unsafe id).
std::filesystem::path default_fetch_dir(const std::string& name, const std::string& id) {
  std::string short_id = folder_name(id.substr(0, 8));
  if (short_id.empty()) short_id = "job";
  std::string folder = folder_name(name);
  if (folder.empty()) {
    folder = folder_name(id).empty() ? short_id : id;
    std::fprintf(stderr,
                 "ftctune: warning: the server's name for job %s is not a safe folder name; "
                 "its files go under %s\n",
                 short_id.c_str(), default_out_dir_for(folder).c_str());
  }
  return default_out_dir_for(folder) / ("service-" + short_id);
}

int fetch_gains(Api& api, const std::string& id, const std::string& out, const std::string& name,
                bool quiet, bool force) {
  const std::string gains = api.get("/v1/jobs/" + id + "/gains");
  note_partial(id, gains, quiet);
  // By default in a folder of the service job's own, so a local run's gains.json is never
  // replaced by a fetched one; an existing file is only replaced with --force.
  const std::filesystem::path file =
      out.empty() ? default_fetch_dir(name, id) / "gains.json"
                  : std::filesystem::path(out);
  if (std::filesystem::exists(file) && !force)
    throw InputError(file.string(), "",
                     "exists already; pass --force to replace it or -o to write elsewhere");
  tune::write_file_atomic(file, gains);
  if (!quiet) std::printf("wrote %s\n", file.c_str());
  return 0;
}

// A name of a run's folder as the service lists it: one or more parts joined by '/', each of
// letters, digits, '_', '-' and '.' and not starting with '.' (the file names a run writes, and
// the scenario names, which the job's schema holds to the same characters).
bool stored_file_name(const std::string& name) {
  if (name.empty() || name.size() > 1024) return false;
  std::size_t start = 0;
  for (std::size_t i = 0; i <= name.size(); ++i) {
    if (i < name.size() && name[i] != '/') {
      const unsigned char c = static_cast<unsigned char>(name[i]);
      if (!(std::isalnum(c) || c == '_' || c == '-' || c == '.') || c >= 0x80) return false;
      continue;
    }
    if (i == start || name[start] == '.') return false;  // an empty part, ".", "..", ".hidden"
    start = i + 1;
  }
  return true;
}

// Everything a job has, beside the gains file: a finished job's (or a cancelled one's, partial)
// stored files, the folder `ftctune run` writes, which `ftctune report` takes, and report.html;
// a running job's gains, history and trials so far.
int fetch_all(Api& api, const std::string& id, const std::string& out, const std::string& name,
              const std::string& status, bool quiet, bool force) {
  const std::filesystem::path gains_file =
      out.empty() ? default_fetch_dir(name, id) / "gains.json"
                  : std::filesystem::path(out);
  const std::filesystem::path dir = gains_file.parent_path();
  std::vector<std::pair<std::string, std::string>> sources;  // request path, file
  if (status == "running") {
    sources = {{"/history?format=csv", "history.csv"}, {"/trials", "trials.csv"}};
  } else {
    const std::string listing = "/v1/jobs/" + id + "/files";
    const json list = json::parse(api.get(listing), nullptr, false);
    if (!list.is_object() || !list.contains("files") || !list["files"].is_array())
      throw InputError(listing, "/files", "expected an array of the job's files");
    for (std::size_t i = 0; i < list["files"].size(); ++i) {
      const json& f = list["files"][i];
      if (!f.is_object() || !f.contains("name") || !f["name"].is_string())
        throw InputError(listing, "/files/" + std::to_string(i) + "/name", "expected a string");
      const std::string file = f["name"];
      // Stored names are the server's: only names a run writes (stored_file_name) are taken,
      // all checked before anything is written, so that nothing lands outside the folder and a
      // name a path cannot hold (a NUL) does not stop the fetch half-way.
      if (!stored_file_name(file))
        throw InputError(listing, "/files/" + std::to_string(i) + "/name",
                         json(file).dump(-1, ' ', false, json::error_handler_t::replace) +
                             " is not a file name a run writes (parts of letters, digits, '_', "
                             "'-' and '.', not starting with '.', joined by '/'): nothing was "
                             "written");
      if (file == "gains.json") continue;
      sources.emplace_back("/files/" + file, file);
    }
    if (std::none_of(sources.begin(), sources.end(),
                     [](const auto& s) { return s.second == "report.html"; }))
      sources.emplace_back("/report", "report.html");
  }
  // Refuse before writing anything.
  for (const auto& [path, file] : sources)
    if (std::filesystem::exists(dir / file) && !force)
      throw InputError((dir / file).string(), "", "exists already; pass --force to replace it");
  if (std::filesystem::exists(gains_file) && !force)
    throw InputError(gains_file.string(), "",
                     "exists already; pass --force to replace it or -o to write elsewhere");
  // The gains file last, as `ftctune run` writes it: a folder with one holds the rest.
  for (const auto& [path, file] : sources) {
    tune::write_file_atomic(dir / file, api.get("/v1/jobs/" + id + path));
    if (!quiet) std::printf("wrote %s\n", (dir / file).c_str());
  }
  return fetch_gains(api, id, gains_file.string(), name, quiet, force);
}

// A job id, or a unique prefix of one among the newest 1000 jobs.
std::string resolve_id(Api& api, const std::string& id) {
  if (id.size() >= 16) return id;
  const json j = json::parse(api.get("/v1/jobs?limit=1000"));
  std::vector<std::string> hits;
  for (const json& job : j["jobs"])
    if (job["id"].get<std::string>().rfind(id, 0) == 0) hits.push_back(job["id"]);
  if (hits.size() == 1) return hits[0];
  if (hits.empty()) return id;  // the server answers 404 with its own message
  std::string list;
  for (const std::string& h : hits) list += (list.empty() ? "" : ", ") + h;
  throw InputError("id", "", "\"" + id + "\" is a prefix of several jobs: " + list);
}

// What `ftctune run` prints at its end, for a job the service ran: its warnings, the tuned
// values, the objective against the job's own controller's, the noise floor and the cost.
void print_summary(Api& api, const std::string& id) {
  const json gains = json::parse(api.get("/v1/jobs/" + id + "/gains"));
  const json comparison = json::parse(api.get("/v1/jobs/" + id + "/comparison"));
  const json run = json::parse(api.get("/v1/jobs/" + id + "/files/run.json"));
  for (const json& w : gains.value("warnings", json::array()))
    std::fprintf(stderr, "warning: %s\n", w.get<std::string>().c_str());
  std::fputs(tune::run_summary(gains, comparison, run, " on the server").c_str(), stdout);
}

}  // namespace

void add_client_commands(CLI::App& app, const Globals& g, Action& action) {
  auto o = std::make_shared<ClientOptions>();
  const auto common = [o](CLI::App* sub) {
    sub->add_option("--server", o->server,
                    "Server URL (default $FTCTUNE_SERVER or http://127.0.0.1:8080)");
    sub->add_flag("--json", o->json_output, "Print the server's JSON");
  };

  {
    auto job = std::make_shared<std::string>();
    auto wait = std::make_shared<bool>(false);
    auto out = std::make_shared<std::string>();
    auto force = std::make_shared<bool>(false);
    CLI::App* sub = app.add_subcommand("submit", "Submit a tuning job to the service");
    sub->add_option("job", *job, "Job file (ftctune.job/1)")->required();
    sub->add_flag("--wait", *wait, "Follow the progress, then fetch the gains file");
    sub->add_option("-o,--output", *out,
                    "With --wait: where to write the gains (default "
                    "out/<job name>/service-<id>/gains.json)")
        ->check(output_file());
    sub->add_flag("--force", *force, "Replace the output file if it exists");
    common(sub);
    sub->callback([&action, &g, o, job, wait, out, force] {
      action = [&g, o, job, wait, out, force] {
        return guarded([&] {
          const std::optional<std::string> text = tune::read_file(*job);
          if (!text) throw InputError(*job, "", "cannot open the job file");
          // Refuse before the job runs, not after.
          if (*wait && !out->empty() && std::filesystem::exists(*out) && !*force)
            throw InputError(*out, "", "exists already; pass --force to replace it");
          Api api(*o);
          const json created = json::parse(api.post("/v1/jobs", *text));
          const std::string id = created["id"];
          if (o->json_output && !*wait)
            print_json(created.dump());
          else
            std::printf("%s\n", id.c_str());
          std::fflush(stdout);
          if (!*wait) return 0;
          int last_iteration = -2;
          while (true) {
            const json j = json::parse(api.get("/v1/jobs/" + id));
            const std::string status = j["status"];
            const int it =
                j["progress"]["iteration"].is_null() ? -1 : j["progress"]["iteration"].get<int>();
            if (it != last_iteration && !g.quiet) {
              // describe() carries the running job's ETA (eta.hpp), as `status` shows it.
              std::fprintf(stderr, "%s\n", describe(j).c_str());
              last_iteration = it;
            }
            if (status == "succeeded") {
              const int rc = fetch_gains(api, id, *out, j["name"], g.quiet, *force);
              if (rc == 0 && !g.quiet)
                print_summary(api, id);
              return rc;
            }
            if (status == "failed" || status == "cancelled") {
              std::fprintf(stderr, "ftctune: job %s %s\n", id.c_str(), status.c_str());
              return 1;
            }
            std::this_thread::sleep_for(
                std::chrono::milliseconds(20));  // a status read costs ~0.1 ms
          }
        });
      };
    });
  }
  // status, fetch and cancel: one job id, then a request.
  using IdAction = std::function<int(Api&, const std::string& id)>;
  const auto id_command = [&](const char* name, const char* help, IdAction fn) {
    auto id = std::make_shared<std::string>();
    CLI::App* sub = app.add_subcommand(name, help);
    sub->add_option("id", *id, "Job id, or a prefix of one that no other job shares")->required();
    common(sub);
    sub->callback([&action, o, id, fn] {
      action = [o, id, fn] {
        return guarded([&] {
          Api api(*o);
          return fn(api, resolve_id(api, *id));
        });
      };
    });
    return sub;
  };
  id_command("status", "Show a job's status and progress", [o](Api& api, const std::string& id) {
    const std::string body = api.get("/v1/jobs/" + id);
    if (o->json_output)
      print_json(body);
    else
      std::printf("%s\n", describe(json::parse(body)).c_str());
    return 0;
  });
  auto out = std::make_shared<std::string>();
  auto force = std::make_shared<bool>(false);
  auto all = std::make_shared<bool>(false);
  CLI::App* fetch = id_command(
      "fetch", "Download a finished job's gains file (with --all, its other results too)",
      [&g, out, force, all](Api& api, const std::string& id) {
        const json j = json::parse(api.get("/v1/jobs/" + id));
        return *all ? fetch_all(api, id, *out, j["name"], j["status"], g.quiet, *force)
                    : fetch_gains(api, id, *out, j["name"], g.quiet, *force);
      });
  fetch->add_flag("--all", *all,
                  "Also every other file of the job (the folder `ftctune run` writes, which "
                  "`ftctune report` takes) and report.html, beside the gains file");
  fetch
      ->add_option("-o,--output", *out,
                   "Output file (default out/<job name>/service-<id>/gains.json)")
      ->check(output_file());
  fetch->add_flag("--force", *force, "Replace the output file if it exists");
  id_command("cancel", "Cancel a queued or running job", [o](Api& api, const std::string& id) {
    const std::string body = api.post("/v1/jobs/" + id + "/cancel", "");
    if (o->json_output) {
      print_json(body);
    } else {
      const json j = json::parse(body);
      std::printf(
          "%s %s\n", id.c_str(),
          j["status"] == "cancelled"
              ? "cancelled"
              : "will stop before its next pack of simulations, keeping its last finished "
                "iteration's results");
    }
    return 0;
  });
  id_command("delete", "Delete a finished job and its results from the service",
             [o](Api& api, const std::string& id) {
               const std::string body = api.del("/v1/jobs/" + id);
               if (o->json_output)
                 print_json(body);
               else
                 std::printf("%s deleted\n", id.c_str());
               return 0;
             });
  {
    auto status = std::make_shared<std::string>();
    auto limit = std::make_shared<int>(20);
    auto prune_days = std::make_shared<double>(-1);
    CLI::App* sub = app.add_subcommand("jobs", "List jobs, newest first; or prune old ones");
    sub->add_option("--status", *status, "Only jobs in this status");
    sub->add_option("--limit", *limit, "How many (default 20)");
    sub->add_option("--prune", *prune_days,
                    "Delete the finished jobs (succeeded, failed, cancelled) that finished more "
                    "than this many days ago, with their results")
        ->check(CLI::Validator(
            [](std::string& text) -> std::string {
              // CLI::Range lets NaN through (no comparison is true), which pruned nothing.
              char* end = nullptr;
              const double v = std::strtod(text.c_str(), &end);
              if (text.empty() || *end != '\0' || !std::isfinite(v) || v < 0 || v > 1e6)
                return "days are a number in 0..1000000, got \"" + json_io::printable(text) +
                       "\"";
              return "";
            },
            "DAYS"));
    common(sub);
    sub->callback([&action, o, status, limit, prune_days] {
      action = [o, status, limit, prune_days] {
        return guarded([&] {
          Api api(*o);
          if (*prune_days >= 0) {
            // Oldest last in the list: walk it all, then delete, so paging is not disturbed.
            const double now =
                std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch())
                    .count();
            const double cutoff = now - *prune_days * 86400;
            std::vector<std::string> old;
            for (int offset = 0;; offset += 500) {
              const json page =
                  json::parse(api.get("/v1/jobs?limit=500&offset=" + std::to_string(offset)));
              for (const json& job : page["jobs"]) {
                const std::string st = job["status"];
                const double finished = utc_seconds(job["finished_at"]);
                if ((st == "succeeded" || st == "failed" || st == "cancelled") &&
                    std::isfinite(finished) && finished <= cutoff)
                  old.push_back(job["id"]);
              }
              if (page["jobs"].size() < 500) break;
            }
            for (const std::string& id : old) api.del("/v1/jobs/" + id);
            std::printf("deleted %zu finished job%s older than %g day%s\n", old.size(),
                        old.size() == 1 ? "" : "s", *prune_days, *prune_days == 1 ? "" : "s");
            return 0;
          }
          std::string path = "/v1/jobs?limit=" + std::to_string(*limit);
          if (!status->empty()) path += "&status=" + *status;
          const std::string body = api.get(path);
          if (o->json_output) {
            print_json(body);
            return 0;
          }
          const json j = json::parse(body);
          std::printf("%-16s  %-20s  %-10s  %-19s  %9s  %s\n", "ID", "NAME", "STATE",
                      "SUBMITTED (UTC)", "DURATION", "PROGRESS");
          const double now =
              std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch())
                  .count();
          for (const json& job : j["jobs"]) {
            const double start = utc_seconds(job["started_at"]);
            const double end = job["finished_at"].is_null() ? now : utc_seconds(job["finished_at"]);
            char duration[32] = "-";
            if (std::isfinite(start) && std::isfinite(end))
              std::snprintf(duration, sizeof duration, "%.1f s", end - start);
            std::string submitted = job.value("created_at", "");
            if (submitted.size() >= 19)
              submitted = submitted.substr(0, 10) + " " + submitted.substr(11, 8);
            const json& p = job["progress"];
            const std::string progress = std::to_string(p["evaluations"].get<long long>()) + "/" +
                                         std::to_string(p["total_evaluations"].get<long long>()) +
                                         " evaluations";
            std::printf(
                "%-16s  %-20s  %-10s  %-19s  %9s  %s\n", job["id"].get<std::string>().c_str(),
                job["name"].get<std::string>().c_str(), job["status"].get<std::string>().c_str(),
                submitted.c_str(), duration, progress.c_str());
          }
          std::printf("(%zu of %lld)\n", j["jobs"].size(), j["total"].get<long long>());
          return 0;
        });
      };
    });
  }
}

}  // namespace ftc::cli
