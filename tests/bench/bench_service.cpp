// Service measurements (issue figures), against an in-process server on a loopback port:
//   1. overhead: Table 1 job submitted over HTTP until its gains are fetched, versus the same
//      tuning run in process (what `ftctune run` does), median of 5 each;
//   2. latency of GET /v1/jobs/{id} while the Table 1 job runs (p50, p99);
//   3. submissions per second of tiny jobs from 8 client threads;
//   4. live updates: a job's tuning time (run.json's wall_seconds) with 0 and with 20 event
//      streams (GET /v1/events, the dashboard's pages) open, interleaved, median of 7 each.
// Run: build/tests/ftc_bench_service [events]   (events: only the fourth)
#include <signal.h>
#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <thread>

#include "service/httplib.hpp"
#include "ftc/tune/service/service.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/tuning_run.hpp"

using nlohmann::json;
using clk = std::chrono::steady_clock;

namespace {

double seconds_since(clk::time_point t0) {
  return std::chrono::duration<double>(clk::now() - t0).count();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(p * static_cast<double>(v.size())))];
}

}  // namespace

// `n` pages following the live updates: `curl -N` processes reading GET /v1/events, so that
// their reading costs this process (the server's) nothing, as browsers' would not.
class Pages {
 public:
  Pages(int port, int n, httplib::Client& c) : c_(c) {
    const std::string url = "http://127.0.0.1:" + std::to_string(port) + "/v1/events";
    for (int i = 0; i < n; ++i) {
      const pid_t pid = ::fork();
      if (pid == 0) {
        ::execlp("curl", "curl", "-sN", "--max-time", "600", "-o", "/dev/null", url.c_str(),
                 static_cast<char*>(nullptr));
        ::_exit(127);
      }
      pids_.push_back(pid);
    }
    // Every stream open before the job starts.
    while (json::parse(c.Get("/healthz")->body)["event_streams"] != n)
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ~Pages() {
    for (pid_t pid : pids_) ::kill(pid, SIGTERM);
    for (pid_t pid : pids_) ::waitpid(pid, nullptr, 0);
    // The server notices closed streams at its next keep-alive write.
    while (json::parse(c_.Get("/healthz")->body)["event_streams"] != 0)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }

 private:
  httplib::Client& c_;
  std::vector<pid_t> pids_;
};

double cpu_seconds() {
  rusage ru{};
  ::getrusage(RUSAGE_SELF, &ru);
  return static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
         static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec) / 1e6;
}

int main(int argc, char** argv) {
  const bool only_events = argc > 1 && std::string(argv[1]) == "events";
  spdlog::set_level(spdlog::level::warn);  // the service logs every job; keep the figures readable
  std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/table1.json");
  const json table1 = json::parse(in);
  const auto store = std::filesystem::temp_directory_path() / "ftctune-bench-service";
  std::filesystem::remove_all(store);

  ftc::tune::ServiceOptions o;
  o.port = 0;
  o.store = store;
  o.threads = 2;
  o.max_connections_per_client = 40;  // 20 pages and the benchmark's own requests, all loopback
  ftc::tune::TuningService service(o);
  const int port = service.start();
  httplib::Client c("127.0.0.1", port);
  c.set_read_timeout(60, 0);

  // 4. Live updates: the same job with no page open and with 20, interleaved.
  const auto live_updates = [&] {
    json job = table1;
    job["tuning"]["algorithm"]["iterations"] = 30;  // about 2 s: long enough to time
    // The job's wall time (run.json) and this process's CPU time while it ran.
    const auto run_once = [&](int pages, std::vector<double>& wall, std::vector<double>& cpu) {
      std::unique_ptr<Pages> open = pages > 0 ? std::make_unique<Pages>(port, pages, c) : nullptr;
      const double cpu0 = cpu_seconds();
      const std::string id =
          json::parse(c.Post("/v1/jobs", job.dump(), "application/json")->body)["id"];
      while (json::parse(c.Get(("/v1/jobs/" + id).c_str())->body)["status"] != "succeeded")
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      cpu.push_back(cpu_seconds() - cpu0);
      const json run = json::parse(c.Get(("/v1/jobs/" + id + "/files/run.json").c_str())->body);
      wall.push_back(run["wall_seconds"].get<double>());
    };
    constexpr int kRounds = 9;
    std::vector<double> wall0, wall20, cpu0, cpu20;
    for (int rep = 0; rep < kRounds; ++rep) {
      if (rep % 2 == 0) {
        run_once(0, wall0, cpu0);
        run_once(20, wall20, cpu20);
      } else {
        run_once(20, wall20, cpu20);
        run_once(0, wall0, cpu0);
      }
    }
    std::printf("table1 (30 iterations), wall:     0 pages median %.3f s, 20 pages %.3f s "
                "(%+.1f %%), median of %d, interleaved\n",
                median(wall0), median(wall20), 100 * (median(wall20) / median(wall0) - 1), kRounds);
    std::printf("                         CPU:      0 pages median %.3f s, 20 pages %.3f s "
                "(%+.1f %%)\n",
                median(cpu0), median(cpu20), 100 * (median(cpu20) / median(cpu0) - 1));
  };
  if (only_events) {
    live_updates();
    service.stop();
    std::filesystem::remove_all(store);
    return 0;
  }

  // 1. Overhead.
  std::vector<double> direct, via_service;
  const ftc::tune::Job job = ftc::tune::parse_job(table1, "table1");
  for (int rep = 0; rep < 5; ++rep) {
    auto t0 = clk::now();
    ftc::tune::TbbEvaluator evaluator(2);
    const auto files = ftc::tune::output_files(ftc::tune::tune(job, evaluator));
    direct.push_back(seconds_since(t0));

    t0 = clk::now();
    const std::string id =
        json::parse(c.Post("/v1/jobs", table1.dump(), "application/json")->body)["id"];
    while (json::parse(c.Get(("/v1/jobs/" + id).c_str())->body)["status"] != "succeeded")
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    const std::string gains = c.Get(("/v1/jobs/" + id + "/gains").c_str())->body;
    via_service.push_back(seconds_since(t0));
    if (gains != files.at("gains.json")) std::printf("MISMATCH: service gains differ from run\n");
  }
  const double d = median(direct), s = median(via_service);
  std::printf("table1 in process (ftctune run):  median %.3f s of 5\n", d);
  std::printf("table1 submit -> gains fetched:   median %.3f s of 5 (overhead %+.1f %%)\n", s,
              100 * (s / d - 1));

  // 2. Status latency while the job runs.
  const std::string id =
      json::parse(c.Post("/v1/jobs", table1.dump(), "application/json")->body)["id"];
  std::vector<double> latency_ms;
  httplib::Client poller("127.0.0.1", port);
  for (;;) {
    const auto t0 = clk::now();
    auto r = poller.Get(("/v1/jobs/" + id).c_str());
    latency_ms.push_back(1000 * seconds_since(t0));
    if (json::parse(r->body)["status"] == "succeeded") break;
  }
  std::printf("GET /v1/jobs/{id} during a run:   p50 %.3f ms, p99 %.3f ms over %zu requests\n",
              percentile(latency_ms, 0.5), percentile(latency_ms, 0.99), latency_ms.size());

  // 3. Submission rate of tiny jobs.
  json tiny = table1;
  tiny["name"] = "tiny";
  tiny["scenarios"][0]["duration"] = 0.05;
  tiny["objective"]["window"] = {0, 0.05};
  tiny["tuning"]["algorithm"]["population"] = 2;
  tiny["tuning"]["algorithm"]["iterations"] = 1;
  const std::string body = tiny.dump();
  constexpr int kThreads = 8, kPerThread = 25;
  std::atomic<int> ok{0};
  const auto t0 = clk::now();
  std::vector<std::thread> clients;
  for (int t = 0; t < kThreads; ++t)
    clients.emplace_back([&] {
      httplib::Client cc("127.0.0.1", port);
      for (int i = 0; i < kPerThread; ++i)
        if (auto r = cc.Post("/v1/jobs", body, "application/json"); r && r->status == 201) ++ok;
    });
  for (std::thread& t : clients) t.join();
  const double took = seconds_since(t0);
  std::printf("tiny submissions, %d threads:      %d accepted in %.3f s = %.0f per second\n",
              kThreads, ok.load(), took, ok.load() / took);
  while (json::parse(c.Get("/healthz")->body)["queued"] != 0)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  live_updates();
  service.stop();
  std::filesystem::remove_all(store);
  return 0;
}
