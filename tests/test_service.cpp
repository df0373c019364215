#include <arpa/inet.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sqlite3.h>
#include <sys/mount.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <set>
#include <sstream>
#include <thread>

#include "../tools/eta.hpp"
#include "cli_runner.hpp"
#include "ftc/runtime/gains.hpp"
#include "ftc/tune/api/api.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/front.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "ftc/tune/service/job_store.hpp"
#include "ftc/tune/service/service.hpp"
#include "goal_job.hpp"
#include "io/text.hpp"
#include "server_process.hpp"
#include "service/events.hpp"
#include "service/httplib.hpp"
#include "short_job.hpp"

using nlohmann::json;
using namespace ftc;
using namespace ftc::testing;
using namespace std::chrono_literals;

namespace {

// Long enough to be caught running: 8 bats × 60 iterations on 10 s (about 1.5 s on 2 threads).
json long_job(const std::string& name = "long") {
  json j = short_table1_job();
  j["name"] = name;
  j["scenarios"][0]["duration"] = 10;
  j["objective"]["window"] = {0, 10};
  j["tuning"]["algorithm"]["population"] = 8;
  j["tuning"]["algorithm"]["iterations"] = 60;
  return j;
}

// A file of the uninterrupted run of `job`, as `ftctune run` writes it.
std::string expected_file(const json& job, const std::string& name) {
  tune::TbbEvaluator evaluator(2);
  return tune::output_files(tune::tune(tune::parse_job(job, "expected"), evaluator)).at(name);
}
std::string expected_gains(const json& job) { return expected_file(job, "gains.json"); }

struct Service {
  explicit Service(tune::ServiceOptions o = {}) : dir(fresh_dir("service")) {
    o.port = 0;
    if (o.store == tune::ServiceOptions{}.store) o.store = dir / "store";
    if (o.threads == 0) o.threads = 2;
    service = std::make_unique<tune::TuningService>(o);
    port = service->start();
    client = std::make_unique<httplib::Client>("127.0.0.1", port);
    client->set_read_timeout(30, 0);
  }
  json submit(const json& job, int expected_status = 201) {
    auto r = client->Post("/v1/jobs", job.dump(), "application/json");
    EXPECT_TRUE(r);
    EXPECT_EQ(r->status, expected_status) << r->body;
    return json::parse(r->body);
  }
  json get(const std::string& path) {
    auto r = client->Get(path.c_str());
    EXPECT_TRUE(r);
    EXPECT_EQ(r->status, 200) << path << ": " << r->body;
    return json::parse(r->body);
  }
  // Polls until the job is in a terminal state (or the deadline passes); returns the last view.
  json wait_done(const std::string& id, std::chrono::seconds deadline = 60s) {
    const auto end = std::chrono::steady_clock::now() + deadline * FTC_TEST_SLOWDOWN;
    json j;
    do {
      j = get("/v1/jobs/" + id);
      const std::string s = j["status"];
      if (s == "succeeded" || s == "failed" || s == "cancelled") return j;
      std::this_thread::sleep_for(10ms);
    } while (std::chrono::steady_clock::now() < end);
    ADD_FAILURE() << "job " << id << " did not finish: " << j.dump();
    return j;
  }
  std::filesystem::path dir;
  std::unique_ptr<tune::TuningService> service;
  int port = 0;
  std::unique_ptr<httplib::Client> client;
};

// Polls until the job runs and has completed `iterations` iterations.
void wait_running(Service& s, const std::string& id, int iterations) {
  json v;
  for (int i = 0; i < 4000 * FTC_TEST_SLOWDOWN; ++i) {
    v = s.get("/v1/jobs/" + id);
    if (v["status"] == "running" && !v["progress"]["iteration"].is_null() &&
        v["progress"]["iteration"].get<int>() >= iterations)
      return;
    std::this_thread::sleep_for(5ms);
  }
  FAIL() << "job " << id << " never ran " << iterations << " iterations: " << v.dump();
}

// Polls /healthz until `holds` says yes (or 60 s pass, stretched under an emulator); returns
// the last answer.
json wait_health(Service& s, const std::function<bool(const json&)>& holds) {
  json h;
  for (int i = 0; i < 6000 * FTC_TEST_SLOWDOWN; ++i) {
    h = s.get("/healthz");
    if (holds(h)) break;
    std::this_thread::sleep_for(10ms);
  }
  return h;
}

// Frees the store's "disk" (the seam of job_store.hpp) however the test ends.
struct FreeDiskOnExit {
  ~FreeDiskOnExit() { tune::inject_store_full(0); }
};

// A connection to the server from a chosen loopback address (all of 127.0.0.0/8 reaches the
// loopback interface), so that one test can be several clients.
int connect_from(const char* source, int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  ::inet_pton(AF_INET, source, &a.sin_addr);
  a.sin_port = 0;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return -1;
  }
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

bool send_all(int fd, const std::string& data) {
  return ::send(fd, data.data(), data.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(data.size());
}

// What the server sends on `fd` until it closes the connection (then *closed) or `timeout`
// passes.
std::string read_until_closed(int fd, std::chrono::milliseconds timeout, bool* closed = nullptr) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  std::string reply;
  if (closed) *closed = false;
  for (auto now = std::chrono::steady_clock::now(); now < end;
       now = std::chrono::steady_clock::now()) {
    pollfd p{fd, POLLIN, 0};
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(end - now).count();
    if (::poll(&p, 1, static_cast<int>(left)) <= 0) break;
    char buf[4096];
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n <= 0) {
      if (closed) *closed = true;
      break;
    }
    reply.append(buf, static_cast<std::size_t>(n));
  }
  return reply;
}

// One request from `source`, and the whole reply.
std::string raw_request(const char* source, int port, const std::string& request) {
  const int fd = connect_from(source, port);
  if (fd < 0) return "";
  send_all(fd, request);
  std::string reply = read_until_closed(fd, 30s);
  ::close(fd);
  return reply;
}

std::string post_job(const json& job) {
  const std::string body = job.dump();
  return "POST /v1/jobs HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\nContent-Type: "
         "application/json\r\nContent-Length: " +
         std::to_string(body.size()) + "\r\n\r\n" + body;
}

int status_of(const std::string& reply) {
  return reply.rfind("HTTP/1.1 ", 0) == 0 ? std::atoi(reply.c_str() + 9) : -1;
}

void expect_error(const httplib::Result& r, int status, const std::string& code) {
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, status) << r->body;
  const json body = json::parse(r->body, nullptr, false);
  ASSERT_TRUE(body.is_object()) << r->body;
  EXPECT_EQ(body["error"]["code"], code) << r->body;
  EXPECT_TRUE(body["error"]["message"].is_string());
  EXPECT_TRUE(body["error"]["details"].is_array() || body["error"]["details"].is_object());
}

}  // namespace

TEST(Service, LifecycleGivesTheSameGainsAsRun) {
  Service s;
  const json job = short_table1_job();
  const json created = s.submit(job);
  EXPECT_EQ(created["status"], "queued");
  const std::string id = created["id"];
  EXPECT_EQ(created["links"]["gains"], "/v1/jobs/" + id + "/gains");

  std::set<std::string> seen;
  int last_iteration = -1;
  json view;
  for (int i = 0; i < 6000 * FTC_TEST_SLOWDOWN; ++i) {
    view = s.get("/v1/jobs/" + id);
    seen.insert(view["status"].get<std::string>());
    if (!view["progress"]["iteration"].is_null()) {
      const int it = view["progress"]["iteration"];
      EXPECT_GE(it, last_iteration);  // progress only moves forward
      last_iteration = it;
    }
    if (view["status"] == "succeeded") break;
    std::this_thread::sleep_for(5ms);
  }
  ASSERT_EQ(view["status"], "succeeded") << view.dump();
  EXPECT_EQ(view["progress"]["iteration"], 2);
  EXPECT_EQ(view["progress"]["evaluations"], 9);
  EXPECT_TRUE(view["progress"]["best"].contains("Kp"));
  EXPECT_FALSE(view["started_at"].is_null());
  EXPECT_FALSE(view["finished_at"].is_null());
  EXPECT_EQ(view["attempts"], 1);

  auto gains = s.client->Get(("/v1/jobs/" + id + "/gains").c_str());
  ASSERT_TRUE(gains);
  EXPECT_EQ(gains->status, 200);
  EXPECT_EQ(gains->body, expected_gains(job));  // byte for byte what `ftctune run` writes

  auto csv = s.client->Get(("/v1/jobs/" + id + "/history").c_str());
  EXPECT_EQ(csv->body.substr(0, 22), "iteration,best_fitness");
  EXPECT_EQ(s.get("/v1/jobs/" + id + "/history?format=json").size(), 3u);
  EXPECT_EQ(s.get("/v1/jobs/" + id + "/comparison")["controllers"].size(), 4u);
  auto md = s.client->Get(("/v1/jobs/" + id + "/comparison?format=md").c_str());
  EXPECT_NE(md->body.find("| tuned PI-FOSMC"), std::string::npos);
  auto report = s.client->Get(("/v1/jobs/" + id + "/report").c_str());
  ASSERT_TRUE(report);
  EXPECT_EQ(report->status, 200);
  EXPECT_EQ(report->get_header_value("Content-Type"), "text/html; charset=utf-8");
  EXPECT_NE(report->body.find("data:image/png;base64,"), std::string::npos);
  EXPECT_EQ(s.client->Get(("/v1/jobs/" + id + "/report").c_str())->body, report->body);  // kept

  const std::string second = s.submit(tiny_job())["id"];
  s.wait_done(second);
  const json all = s.get("/v1/jobs");
  ASSERT_EQ(all["jobs"].size(), 2u);
  EXPECT_EQ(all["jobs"][0]["id"], second);  // newest first
  EXPECT_EQ(s.get("/v1/jobs?status=succeeded&limit=1")["jobs"].size(), 1u);
  EXPECT_EQ(s.get("/v1/jobs?status=succeeded&limit=1&offset=1")["jobs"][0]["id"], id);
  EXPECT_EQ(s.get("/v1/jobs?status=queued")["total"], 0);
  EXPECT_EQ(s.get("/healthz")["status"], "ok");
}

// The service's job runner goes through the run API (run_job with the job store as its storage):
// every file it stores is the one run_job gives, byte for byte, and run.json is run_job's too:
// it now lists the run's files and its host, as only `ftctune run`'s did, with the job's id and
// attempts in place of a job file.
TEST(Service, StoresTheFilesOfTheRunApiByteForByte) {
  Service s;
  const json job = tiny_job("through-the-api");
  const std::string id = s.submit(job)["id"];
  ASSERT_EQ(s.wait_done(id)["status"], "succeeded");
  tune::TbbEvaluator evaluator(2);
  tune::RunJobOptions o;
  o.write = false;
  o.evaluator = &evaluator;
  const tune::RunJobResult api = tune::run_job(tune::parse_job(job, "job"), o);
  const std::map<std::string, std::string> expected = tune::run_files(api);
  std::set<std::string> stored;
  const json listing = s.get("/v1/jobs/" + id + "/files");
  for (const json& f : listing["files"]) stored.insert(f["name"].get<std::string>());
  std::set<std::string> names;
  for (const auto& [name, content] : expected) names.insert(name);
  EXPECT_EQ(stored, names);
  for (const auto& [name, content] : expected) {
    if (name == "run.json") continue;
    auto r = s.client->Get(("/v1/jobs/" + id + "/files/" + name).c_str());
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200) << name;
    EXPECT_EQ(r->body, content) << name;
  }
  const json ours = s.get("/v1/jobs/" + id + "/files/run.json"),
             theirs = json::parse(expected.at("run.json"));
  for (const char* key : {"files", "host", "seed", "generator", "threads", "ranks",
                          "threads_per_rank", "evaluator", "simulations"})
    EXPECT_EQ(ours[key], theirs[key]) << key;
  EXPECT_EQ(ours["job_id"], id);
  EXPECT_EQ(ours["attempts"], 1);
  EXPECT_FALSE(ours.contains("job_file"));
  EXPECT_FALSE(ours.contains("completed"));
}

// RFC 9112 §6.3: a request without Content-Length (nor Transfer-Encoding) has an empty body.
// POST /cancel without one cancels; PUT and PATCH without one get 405 like with a body. They
// were read as bodies until the deadline and answered 400.
TEST(Service, RequestWithoutContentLengthHasAnEmptyBody) {
  Service s;
  const std::string running = s.submit(long_job())["id"];
  const std::string queued = s.submit(tiny_job())["id"];
  const auto t0 = std::chrono::steady_clock::now();
  std::string reply =
      raw_request("127.0.0.1", s.port,
                  "POST /v1/jobs/" + queued +
                      "/cancel HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(status_of(reply), 202) << reply;
  EXPECT_NE(reply.find("\"cancelled\""), std::string::npos) << reply;
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 5s);  // not waiting for a body
  for (const char* method : {"PUT", "PATCH"}) {
    reply = raw_request("127.0.0.1", s.port,
                        std::string(method) + " /v1/jobs/" + queued +
                            " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n");
    EXPECT_EQ(status_of(reply), 405) << method << ": " << reply;
  }
  auto r = s.client->Post(("/v1/jobs/" + running + "/cancel").c_str(), "", "application/json");
  ASSERT_TRUE(r);
}

TEST(Service, CancelsQueuedAndRunningJobs) {
  Service s;
  const std::string running = s.submit(long_job())["id"];
  const std::string queued = s.submit(tiny_job())["id"];

  auto r = s.client->Post(("/v1/jobs/" + queued + "/cancel").c_str(), "", "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 202);
  EXPECT_EQ(json::parse(r->body)["status"], "cancelled");

  json view;
  for (int i = 0; i < 2000 * FTC_TEST_SLOWDOWN; ++i) {
    view = s.get("/v1/jobs/" + running);
    if (view["status"] == "running" && !view["progress"]["iteration"].is_null()) break;
    std::this_thread::sleep_for(5ms);
  }
  ASSERT_EQ(view["status"], "running");
  const auto asked = std::chrono::steady_clock::now();
  r = s.client->Post(("/v1/jobs/" + running + "/cancel").c_str(), "", "application/json");
  EXPECT_EQ(r->status, 202);
  const json done = s.wait_done(running);
  const double took =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - asked).count();
  EXPECT_EQ(done["status"], "cancelled");
  EXPECT_LT(done["progress"]["iteration"].get<int>(), 60);
  // One iteration takes about 25 ms here (and up to a second under an emulator).
  EXPECT_LT(took, 1.0 * FTC_TEST_SLOWDOWN) << "a running job must stop within one iteration";

  const json q = s.get("/v1/jobs/" + queued);
  EXPECT_EQ(q["status"], "cancelled");
  EXPECT_TRUE(q["started_at"].is_null());  // it never started
  EXPECT_EQ(q["attempts"], 0);
  // The cancelled job keeps what it ran (PartialResults below); the queued one ran nothing.
  expect_error(s.client->Get(("/v1/jobs/" + queued + "/gains").c_str()), 409, "not_ready");
  expect_error(s.client->Post(("/v1/jobs/" + running + "/cancel").c_str(), "", "application/json"),
               409, "conflict");
}

TEST(Service, RejectsBadRequestsWithJsonErrors) {
  tune::ServiceOptions o;
  o.max_body_bytes = 16 * 1024;
  o.max_steps = 1e6;
  Service s(o);
  auto& c = *s.client;

  expect_error(c.Post("/v1/jobs", "{not json", "application/json"), 400, "invalid_json");
  json bad = tiny_job();
  bad["controller"]["Kp"] = -1;
  bad["scenarios"][0]["faults"][0]["actuator"] = 9;
  auto r = c.Post("/v1/jobs", bad.dump(), "application/json");
  expect_error(r, 400, "invalid_job");
  std::set<std::string> paths;
  const json body = json::parse(r->body);
  for (const json& d : body["error"]["details"]) paths.insert(d["path"]);
  EXPECT_TRUE(paths.count("/controller/Kp")) << r->body;
  EXPECT_TRUE(paths.count("/scenarios/0/faults/0/actuator"));
  json no_tuning = tiny_job();
  no_tuning.erase("tuning");
  expect_error(c.Post("/v1/jobs", no_tuning.dump(), "application/json"), 400, "invalid_job");

  expect_error(c.Post("/v1/jobs", std::string(20 * 1024, ' '), "application/json"), 413,
               "payload_too_large");
  // A form upload is no job (the library could not even hand its parts over): 415, not 500.
  expect_error(c.Post("/v1/jobs", httplib::MultipartFormDataItems{{"job", "{}", "job.json", ""}}),
               415, "unsupported_media_type");
  // Chunked (no Content-Length): the limit holds while the body arrives; the server keeps at
  // most the limit of it and answers 413 (it used to hold all 8 MiB, then say 400).
  {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<std::uint16_t>(s.port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    const std::string head =
        "POST /v1/jobs HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
        "Transfer-Encoding: chunked\r\n\r\n";
    ASSERT_EQ(::send(fd, head.data(), head.size(), MSG_NOSIGNAL),
              static_cast<ssize_t>(head.size()));
    const std::string chunk = "10000\r\n" + std::string(0x10000, ' ') + "\r\n";
    std::size_t sent = 0;
    for (int i = 0; i < 128; ++i) {  // 8 MiB
      const ssize_t n = ::send(fd, chunk.data(), chunk.size(), MSG_NOSIGNAL);
      if (n <= 0) break;
      sent += static_cast<std::size_t>(n);
    }
    ::send(fd, "0\r\n\r\n", 5, MSG_NOSIGNAL);
    timeval wait{10, 0};
    ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &wait, sizeof wait);
    std::string reply;
    char buf[4096];
    while (reply.find("payload_too_large") == std::string::npos) {
      const ssize_t got = ::recv(fd, buf, sizeof buf, 0);
      if (got <= 0) break;
      reply.append(buf, static_cast<std::size_t>(got));
    }
    ::close(fd);
    EXPECT_EQ(reply.rfind("HTTP/1.1 413", 0), 0u) << reply;
    EXPECT_NE(reply.find("payload_too_large"), std::string::npos) << reply;
    EXPECT_EQ(sent, 128u * chunk.size());
  }
  r = c.Post("/v1/jobs", short_table1_job().dump(), "application/json");  // 9 × 5000 steps… fits
  EXPECT_EQ(r->status, 201) << r->body;
  // 488 × 10000 steps, each with 2 faults: 4.88e6 × (1 + 2/32) = 5.185e6 > 1e6
  r = c.Post("/v1/jobs", long_job().dump(), "application/json");
  expect_error(r, 400, "job_too_large");
  EXPECT_NE(json::parse(r->body)["error"]["message"].get<std::string>().find(
                "5.18 times the server's budget"),
            std::string::npos)
      << r->body;
  // Steps are priced by their faults: 9 × 100 000 steps fit as they are (9e5 < 1e6), not with
  // 4 faults each (9e5 × (1 + 4/32) = 1.01e6). Before, a job of 15 000 faults was admitted on
  // its plain step count and took 45 s an iteration.
  json faulty = short_table1_job();
  faulty["scenarios"][0]["duration"] = 100;
  faulty["objective"]["window"] = {0, 100};
  faulty["scenarios"][0]["faults"].push_back(
      {{"actuator", 3}, {"type", "loss_of_effectiveness"}, {"onset", 50}, {"fraction", 0.1}});
  r = c.Post("/v1/validate", faulty.dump(), "application/json");
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(json::parse(r->body)["steps"], 9e5);
  EXPECT_EQ(json::parse(r->body)["step_cost"], 9e5 * (1 + 3.0 / 32));
  faulty["scenarios"][0]["faults"].push_back(
      {{"actuator", 3}, {"type", "loss_of_effectiveness"}, {"onset", 60}, {"fraction", 0.1}});
  r = c.Post("/v1/jobs", faulty.dump(), "application/json");
  expect_error(r, 400, "job_too_large");
  EXPECT_NE(json::parse(r->body)["error"]["message"].get<std::string>().find(
                "1.01 times the server's budget of 1e+06"),
            std::string::npos)
      << r->body;
  EXPECT_NE(json::parse(r->body)["error"]["message"].get<std::string>().find("1 + f/32"),
            std::string::npos);

  expect_error(c.Get("/v1/jobs/0123456789abcdef"), 404, "not_found");
  expect_error(c.Get("/v1/jobs/0123456789abcdef/gains"), 404, "not_found");
  expect_error(c.Post("/v1/jobs/0123456789abcdef/cancel", "", "application/json"), 404,
               "not_found");
  expect_error(c.Get("/v2/anything"), 404, "not_found");
  r = c.Delete("/v1/jobs");
  expect_error(r, 405, "method_not_allowed");
  EXPECT_EQ(r->get_header_value("Allow"), "GET, POST");
  expect_error(c.Put("/healthz", "", "text/plain"), 405, "method_not_allowed");
  expect_error(c.Get("/v1/jobs?status=done"), 400, "invalid_parameter");
  expect_error(c.Get("/v1/jobs?limit=0"), 400, "invalid_parameter");

  // Idempotency: the same key returns the same job; the key with another job is a conflict.
  httplib::Headers key = {{"Idempotency-Key", "abc-1"}};
  r = c.Post("/v1/jobs", key, tiny_job().dump(), "application/json");
  ASSERT_EQ(r->status, 201);
  const std::string id = json::parse(r->body)["id"];
  r = c.Post("/v1/jobs", key, tiny_job().dump(), "application/json");
  EXPECT_EQ(r->status, 200);
  EXPECT_EQ(json::parse(r->body)["id"], id);
  expect_error(c.Post("/v1/jobs", key, tiny_job("other").dump(), "application/json"), 409,
               "idempotency_conflict");

  // A client that disconnects in the middle of a request leaves the server serving.
  for (const char* partial :
       {"POST /v1/jobs HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 5000\r\n\r\n{\"sche",
        "GET /v1/jo"}) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(s.port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    ASSERT_GT(::send(fd, partial, std::strlen(partial), 0), 0);
    ::close(fd);
  }
  EXPECT_EQ(s.get("/healthz")["status"], "ok");
  EXPECT_EQ(s.get("/v1/jobs")["total"], 2);  // nothing was created by the broken requests
}

TEST(Service, TokenIsRequiredWhenConfigured) {
  tune::ServiceOptions o;
  o.token = "s3cret-token";
  Service s(o);
  expect_error(s.client->Get("/healthz"), 401, "unauthorized");
  httplib::Client wrong("127.0.0.1", s.port);
  wrong.set_bearer_token_auth("s3cret-tokem");
  expect_error(wrong.Get("/v1/jobs"), 401, "unauthorized");
  httplib::Client right("127.0.0.1", s.port);
  right.set_bearer_token_auth("s3cret-token");
  auto r = right.Get("/v1/jobs");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);

  tune::ServiceOptions open;
  open.bind = "0.0.0.0";
  const auto errs = open.validate();
  ASSERT_EQ(errs.size(), 1u);
  EXPECT_NE(errs[0].message.find("without --token-file"), std::string::npos);
  EXPECT_THROW(tune::TuningService{open}, InputError);
}

TEST(Service, BodyThatIsNotUtf8IsA400ThatDoesNotEchoIt) {
  Service s;
  auto& c = *s.client;
  std::string text = tiny_job().dump();
  text.replace(text.find("\"tiny\""), 6, "\"ti\xff\xfeny\"");
  for (const std::string& body : {text, std::string("{\"name\": 1, \xc0\xaf}")}) {
    const auto r = c.Post("/v1/jobs", body, "application/json");
    expect_error(r, 400, "invalid_json");
    EXPECT_NE(r->body.find("not UTF-8"), std::string::npos) << r->body;
    for (char ch : r->body) ASSERT_LT(static_cast<unsigned char>(ch), 0x80) << r->body;
  }
  // A path that decodes to bytes that are not UTF-8 still gets a JSON error, not a 500.
  const auto r = c.Get("/v1/jobs/%FF%FE");
  expect_error(r, 404, "not_found");
  EXPECT_EQ(s.get("/v1/jobs")["total"], 0);
}

TEST(Service, NumberOutOfRangeOrDuplicateKeyIsA400NamingThePath) {
  Service s;
  auto& c = *s.client;
  json j = tiny_job();
  j["controller"]["Kp"] = "HERE";
  std::string big = j.dump();
  big.replace(big.find("\"HERE\""), 6, "1e400");
  std::string twice = tiny_job().dump();
  twice.replace(twice.find("\"name\":"), 7, "\"name\":\"x\",\"name\":");
  for (const auto& [body, path] : {std::pair{big, "/controller/Kp"}, std::pair{twice, "/name"}}) {
    const auto r = c.Post("/v1/jobs", body, "application/json");
    expect_error(r, 400, "invalid_json");
    const json e = json::parse(r->body)["error"];
    ASSERT_EQ(e["details"].size(), 1u) << r->body;
    EXPECT_EQ(e["details"][0]["path"], path) << r->body;
  }
}

TEST(Service, LoopbackIsJudgedByTheResolvedAddresses) {
  for (const char* host : {"127.0.0.1", "127.0.0.2", "localhost", "::1"})
    EXPECT_TRUE(tune::is_loopback(host)) << host;
  // 127.x.example starts like a loopback address but names nothing (or anything).
  for (const char* host : {"127.x.example", "0.0.0.0", "::", "", "127.0.0.1.invalid"})
    EXPECT_FALSE(tune::is_loopback(host)) << host;
  tune::ServiceOptions o;
  o.bind = "127.x.example";
  const auto errs = o.validate();
  ASSERT_EQ(errs.size(), 1u);
  EXPECT_NE(errs[0].message.find("refusing to listen on 127.x.example without --token-file"),
            std::string::npos)
      << errs[0].message;
  EXPECT_NE(errs[0].message.find("cannot resolve it"), std::string::npos) << errs[0].message;
  o.bind = "0.0.0.0";
  EXPECT_NE(o.validate().at(0).message.find("it resolves to 0.0.0.0"), std::string::npos);
  o.token = "t";
  EXPECT_TRUE(o.validate().empty());
}

TEST(Service, SecondServerOnAPortInUseIsRefused) {
  Service first;
  tune::ServiceOptions o;
  o.port = first.port;
  o.store = first.dir / "second-store";
  o.threads = 1;
  tune::TuningService second(o);
  try {
    second.start();
    ADD_FAILURE() << "a second server listens on port " << first.port;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("address in use"), std::string::npos) << e.what();
  }
  EXPECT_EQ(first.get("/healthz")["status"], "ok");
}

TEST(Service, StoreIsLockedAgainstASecondServer) {
  Service s;
  tune::ServiceOptions o;
  o.store = s.dir / "store";
  try {
    tune::TuningService second{o};
    ADD_FAILURE() << "a second server opened the store";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("is in use by another ftctune serve"), std::string::npos)
        << e.what();
  }
}

// The store holds every user's jobs and results: only its owner may read it.
TEST(Service, StoreIsPrivateToItsOwner) {
  Service s;
  const auto mode = [](const std::filesystem::path& p) {
    struct stat st {};
    EXPECT_EQ(::stat(p.c_str(), &st), 0) << p;
    return st.st_mode & 07777;
  };
  EXPECT_EQ(mode(s.dir / "store"), 0700u);
  for (const char* f : {"lock", "ftctune.db", "ftctune.db-wal"})
    EXPECT_EQ(mode(s.dir / "store" / f), 0600u) << f;
}

TEST(Service, FiftyConcurrentSubmissionsAllComplete) {
  Service s;
  std::vector<std::string> ids(50);
  std::atomic<int> failures{0};
  std::vector<std::thread> clients;
  for (int t = 0; t < 8; ++t)
    clients.emplace_back([&, t] {
      httplib::Client c("127.0.0.1", s.port);
      for (int i = t; i < 50; i += 8) {
        auto r =
            c.Post("/v1/jobs", tiny_job("tiny" + std::to_string(i)).dump(), "application/json");
        if (!r || r->status != 201) {
          ++failures;
          continue;
        }
        ids[static_cast<std::size_t>(i)] = json::parse(r->body)["id"];
      }
    });
  for (std::thread& t : clients) t.join();
  EXPECT_EQ(failures.load(), 0);
  EXPECT_EQ(std::set<std::string>(ids.begin(), ids.end()).size(), 50u);
  for (const std::string& id : ids) EXPECT_EQ(s.wait_done(id)["status"], "succeeded") << id;
  EXPECT_EQ(s.get("/v1/jobs?status=succeeded")["total"], 50);
}

TEST(Service, ConcurrentJobsRunSideBySideWithTheSameGains) {
  tune::ServiceOptions o;
  o.concurrent_jobs = 2;
  o.threads = 1;
  Service s(o);
  const std::vector<json> jobs = {long_job("p"), long_job("q")};
  std::vector<std::string> ids;
  for (const json& j : jobs) ids.push_back(s.submit(j)["id"]);
  bool both_running = false;
  for (int i = 0; i < 4000 * FTC_TEST_SLOWDOWN && !both_running; ++i) {
    both_running = s.get("/v1/jobs?status=running")["total"] == 2;
    if (!both_running) std::this_thread::sleep_for(2ms);
  }
  EXPECT_TRUE(both_running) << "--concurrent-jobs 2 never ran two jobs at once";
  const std::string expected = expected_gains(jobs[0]);  // the two jobs differ only in name
  for (const std::string& id : ids) {
    ASSERT_EQ(s.wait_done(id)["status"], "succeeded");
    const json got = json::parse(s.client->Get(("/v1/jobs/" + id + "/gains").c_str())->body);
    json want = json::parse(expected);
    EXPECT_EQ(got["tuned"], want["tuned"]);
    EXPECT_EQ(got["history"], want["history"]);
  }
}

TEST(Service, RecoversFromSigkillWithoutLosingOrRepeatingJobs) {
  const auto dir = fresh_dir("sigkill");
  const std::vector<json> jobs = {long_job("a"), long_job("b"), tiny_job("c")};
  std::vector<std::string> ids;
  std::string killed;
  {
    ServerProcess server(dir / "store", dir / "serve.log");
    httplib::Client c("127.0.0.1", server.port());
    for (const json& j : jobs) {
      auto r = c.Post("/v1/jobs", j.dump(), "application/json");
      ASSERT_TRUE(r && r->status == 201);
      ids.push_back(json::parse(r->body)["id"]);
    }
    // Kill it while the first job is in the middle of its run.
    for (int i = 0; i < 4000 * FTC_TEST_SLOWDOWN && killed.empty(); ++i) {
      auto r = c.Get(("/v1/jobs/" + ids[0]).c_str());
      const json v = json::parse(r->body);
      if (v["status"] == "running" && !v["progress"]["iteration"].is_null() &&
          v["progress"]["iteration"].get<int>() >= 3)
        killed = ids[0];
      else
        std::this_thread::sleep_for(2ms);
    }
    ASSERT_FALSE(killed.empty()) << "never saw the job running";
    EXPECT_EQ(server.signal_and_wait(SIGKILL), -SIGKILL);
  }
  ServerProcess server(dir / "store", dir / "serve.log");
  httplib::Client c("127.0.0.1", server.port());
  for (std::size_t k = 0; k < ids.size(); ++k) {
    json v;
    for (int i = 0; i < 6000 * FTC_TEST_SLOWDOWN; ++i) {
      v = json::parse(c.Get(("/v1/jobs/" + ids[k]).c_str())->body);
      if (v["status"] != "queued" && v["status"] != "running") break;
      std::this_thread::sleep_for(10ms);
    }
    ASSERT_EQ(v["status"], "succeeded") << v.dump();
    EXPECT_EQ(v["attempts"], k == 0 ? 2 : 1) << "job " << k;
    EXPECT_EQ(c.Get(("/v1/jobs/" + ids[k] + "/gains").c_str())->body, expected_gains(jobs[k]))
        << "job " << k;
  }
  // The resumed job's trials table holds the trials from before the kill too.
  EXPECT_EQ(c.Get(("/v1/jobs/" + killed + "/trials").c_str())->body,
            expected_file(jobs[0], "trials.csv"));
  EXPECT_EQ(json::parse(c.Get("/v1/jobs")->body)["total"], 3);
}

// A bounded soak: the server is SIGKILLed at seeded random moments while 20 jobs are submitted
// from 4 clients (each retrying with its Idempotency-Key until acknowledged) and run; every
// acknowledged job finishes exactly once, with the gains file of an uninterrupted run. The
// longer version is FTC_SOAK_JOBS and FTC_SOAK_KILLS in the environment (docs/reliability.md).
TEST(Service, SoakOfSigkillsLosesAndRepeatsNoJob) {
  const auto env_int = [](const char* name, int fallback) {
    const char* v = std::getenv(name);
    return v && *v ? std::max(1, std::atoi(v)) : fallback;
  };
  const int n_jobs = env_int("FTC_SOAK_JOBS", 20), kills = env_int("FTC_SOAK_KILLS", 3);
  const auto dir = fresh_dir("soak");
  std::vector<json> jobs;
  for (int i = 0; i < n_jobs; ++i) {
    json j = short_table1_job();
    j["name"] = "soak-" + std::to_string(i);
    j["tuning"]["seed"] = 100 + i;
    j["tuning"]["algorithm"]["iterations"] = 30;  // about 0.25 s: kills land inside runs
    jobs.push_back(std::move(j));
  }
  std::mutex port_mutex;
  auto server = std::make_unique<ServerProcess>(dir / "store", dir / "serve.log");
  int port = server->port();
  std::vector<std::string> ids(static_cast<std::size_t>(n_jobs));
  std::vector<std::thread> clients;
  for (int c = 0; c < 4; ++c)
    clients.emplace_back([&, c] {
      for (int i = c; i < n_jobs; i += 4) {
        const httplib::Headers key = {{"Idempotency-Key", "soak-" + std::to_string(i)}};
        const auto deadline = std::chrono::steady_clock::now() + 120s * FTC_TEST_SLOWDOWN;
        while (std::chrono::steady_clock::now() < deadline) {
          int p = 0;
          {
            std::lock_guard<std::mutex> lock(port_mutex);
            p = port;
          }
          httplib::Client cl("127.0.0.1", p);
          cl.set_connection_timeout(1, 0);
          cl.set_read_timeout(5, 0);
          auto r = cl.Post("/v1/jobs", key, jobs[static_cast<std::size_t>(i)].dump(),
                           "application/json");
          if (r && (r->status == 201 || r->status == 200)) {  // 200: a retry of a stored one
            ids[static_cast<std::size_t>(i)] = json::parse(r->body)["id"];
            break;
          }
          std::this_thread::sleep_for(20ms);
        }
      }
    });
  std::mt19937 moments(29);
  for (int k = 0; k < kills; ++k) {
    std::this_thread::sleep_for(
        std::chrono::milliseconds(std::uniform_int_distribution<int>(300, 1500)(moments)));
    EXPECT_EQ(server->signal_and_wait(SIGKILL), -SIGKILL);
    server = std::make_unique<ServerProcess>(dir / "store", dir / "serve.log");
    std::lock_guard<std::mutex> lock(port_mutex);
    port = server->port();
  }
  for (std::thread& t : clients) t.join();

  httplib::Client c("127.0.0.1", server->port());
  c.set_read_timeout(30, 0);
  int resumed = 0;  // jobs a kill interrupted, run again from their checkpoint
  for (int i = 0; i < n_jobs; ++i) {
    const std::string& id = ids[static_cast<std::size_t>(i)];
    ASSERT_FALSE(id.empty()) << "job " << i << " was never acknowledged";
    json v;
    const auto deadline = std::chrono::steady_clock::now() + 120s * FTC_TEST_SLOWDOWN;
    while (std::chrono::steady_clock::now() < deadline) {
      const auto r = c.Get(("/v1/jobs/" + id).c_str());
      ASSERT_TRUE(r) << "the server did not answer for job " << i;
      v = json::parse(r->body);
      if (v["status"] != "queued" && v["status"] != "running") break;
      std::this_thread::sleep_for(20ms);
    }
    ASSERT_EQ(v["status"], "succeeded") << "job " << i << ": " << v.dump();
    if (v["attempts"].get<int>() > 1) ++resumed;
    const auto g = c.Get(("/v1/jobs/" + id + "/gains").c_str());
    ASSERT_TRUE(g) << "the server did not answer for job " << i << "'s gains";
    EXPECT_EQ(g->body, expected_gains(jobs[static_cast<std::size_t>(i)])) << "job " << i;
  }
  // How many kills landed inside a job depends on the machine's speed, so it is reported (in
  // the test's output and its XML property), not asserted.
  std::printf("soak: %d jobs, %d kills, %d jobs resumed after a kill\n", n_jobs, kills, resumed);
  ::testing::Test::RecordProperty("resumed", resumed);
  // Exactly once: the store holds each job once, however often its submission was retried.
  const auto all = c.Get("/v1/jobs");
  ASSERT_TRUE(all);
  EXPECT_EQ(json::parse(all->body)["total"], n_jobs);
  EXPECT_EQ(std::set<std::string>(ids.begin(), ids.end()).size(), static_cast<std::size_t>(n_jobs));
}

TEST(Service, SigtermCheckpointsTheRunningJobAndExits) {
  const auto dir = fresh_dir("sigterm");
  const json job = long_job();
  std::string id;
  {
    ServerProcess server(dir / "store", dir / "serve.log");
    httplib::Client c("127.0.0.1", server.port());
    id = json::parse(c.Post("/v1/jobs", job.dump(), "application/json")->body)["id"];
    for (int i = 0; i < 4000 * FTC_TEST_SLOWDOWN; ++i) {
      const json v = json::parse(c.Get(("/v1/jobs/" + id).c_str())->body);
      if (v["status"] == "running" && !v["progress"]["iteration"].is_null()) break;
      std::this_thread::sleep_for(2ms);
    }
    EXPECT_EQ(server.signal_and_wait(SIGTERM), 0);
  }
  ServerProcess server(dir / "store", dir / "serve.log");
  httplib::Client c("127.0.0.1", server.port());
  json v;
  for (int i = 0; i < 6000 * FTC_TEST_SLOWDOWN; ++i) {
    v = json::parse(c.Get(("/v1/jobs/" + id).c_str())->body);
    if (v["status"] == "succeeded") break;
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_EQ(v["status"], "succeeded") << v.dump();
  EXPECT_EQ(v["attempts"], 2);
  EXPECT_EQ(c.Get(("/v1/jobs/" + id + "/gains").c_str())->body, expected_gains(job));
}

TEST(Cli, ClientCommandsTalkToTheService) {
  Service s;
  const auto dir = fresh_dir("client");
  {
    std::ofstream f(dir / "job.json");
    f << tiny_job().dump();
  }
  const std::string server = " --server http://127.0.0.1:" + std::to_string(s.port);
  CliResult r = run_cli("submit '" + (dir / "job.json").string() + "' --wait -o '" +
                            (dir / "gains.json").string() + "'" + server,
                        dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string id = r.out.substr(0, r.out.find('\n'));
  EXPECT_EQ(id.size(), 16u) << r.out;
  EXPECT_EQ(slurp(dir / "gains.json"), expected_gains(tiny_job()));
  // The summary `run` prints, and an ETA on the progress lines.
  // (The tuned values in the job's order: once printed as nothing at all.)
  EXPECT_NE(r.out.find("tuned PI-FOSMC: Kp = "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(", Ki = "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("(job's own controller: "), std::string::npos) << r.out;
  // The objective named as run names it: metric, window and aggregate, not the bare metric.
  const std::string label = tune::objective_label(tune::parse_job(tiny_job(), "tiny job"));
  EXPECT_NE(r.out.find("  " + label + " = "), std::string::npos) << label << "\n" << r.out;
  EXPECT_NE(r.out.find("simulations on "), std::string::npos) << r.out;
  r = run_cli("status " + id + server, dir);
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("succeeded"), std::string::npos) << r.out;
  // Its J named by what it measures, and its gains file's warnings counted (issue 41).
  EXPECT_NE(r.out.find("  (J: " + label + ")"), std::string::npos) << r.out;
  const std::size_t warned =
      json::parse(slurp(dir / "gains.json")).value("warnings", json::array()).size();
  EXPECT_EQ(
      r.out.find("succeeded with " + std::to_string(warned) + " warning") != std::string::npos,
      warned > 0)
      << r.out;
  r = run_cli("jobs --json" + server, dir);
  EXPECT_EQ(json::parse(r.out)["total"], 1);
  r = run_cli("fetch " + id + " -o '" + (dir / "again.json").string() + "'" + server, dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(slurp(dir / "again.json"), slurp(dir / "gains.json"));
  r = run_cli("cancel " + id + server, dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("has already succeeded"), std::string::npos) << r.err;
  r = run_cli("status ffffffffffffffff" + server, dir);
  EXPECT_EQ(r.exit_code, 2);
  r = run_cli("status " + id + " --server http://127.0.0.1:1", dir);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("cannot reach the ftctune server at http://127.0.0.1:1"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("ftctune serve"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1);

  // A unique prefix of an id will do; the table has a header; --all brings every result, and
  // an existing file is not written over without --force.
  r = run_cli("jobs" + server, dir);
  EXPECT_EQ(r.out.rfind("ID ", 0), 0u) << r.out;
  EXPECT_NE(r.out.find("SUBMITTED (UTC)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(id + "  "), std::string::npos) << r.out;
  const std::string all = (dir / "all" / "gains.json").string();
  r = run_cli("fetch " + id.substr(0, 6) + " --all -o '" + all + "'" + server, dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* f : {"gains.json", "history.csv", "trials.csv", "comparison.json",
                        "comparison.md", "report.html", "job.json", "run.json"})
    EXPECT_TRUE(std::filesystem::exists(dir / "all" / f)) << f;
  EXPECT_EQ(slurp(dir / "all" / "gains.json"), slurp(dir / "gains.json"));
  r = run_cli("report '" + (dir / "all").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;  // the folder `run` writes
  r = run_cli("fetch " + id.substr(0, 6) + " -o '" + all + "'" + server, dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("exists already; pass --force"), std::string::npos) << r.err;
  EXPECT_EQ(
      run_cli("fetch " + id.substr(0, 6) + " --force -o '" + all + "'" + server, dir).exit_code, 0);

  // Retention: a job that finished less than a day ago survives --prune 1; --prune 0 removes
  // every finished job with its results, and delete removes one.
  r = run_cli("jobs --prune 1" + server, dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("deleted 0 finished jobs older than 1 day"), std::string::npos) << r.out;
  r = run_cli("jobs --prune 0" + server, dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("deleted 1 finished job older than 0 days"), std::string::npos) << r.out;
  r = run_cli("status " + id + server, dir);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  r = run_cli("delete " + id + server, dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("no job " + id), std::string::npos) << r.err;
}

// A running job serves its history, trials and best gains so far; a cancelled one keeps them,
// with the rest of a run's files, all marked partial: the same rows as the uninterrupted run's
// first iterations, and a gains file that records optimizer.completed false.
TEST(Service, RunningAndCancelledJobsServeTheirPartialResults) {
  const json job = long_job("partial");
  const std::string full_trials = expected_file(job, "trials.csv");
  const std::string full_history = expected_file(job, "history.csv");
  Service s;
  const std::string id = s.submit(job)["id"];
  wait_running(s, id, 3);
  const auto lines = [](const std::string& text) {
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string l; std::getline(in, l);) out.push_back(l);
    return out;
  };
  // Every row served is the uninterrupted run's row of the same place.
  const auto expect_prefix = [&](const std::string& part, const std::string& full) {
    const std::vector<std::string> a = lines(part), b = lines(full);
    ASSERT_GE(a.size(), 2u) << part;
    ASSERT_LE(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << "line " << i;
  };

  auto trials = s.client->Get(("/v1/jobs/" + id + "/trials").c_str());
  ASSERT_TRUE(trials);
  ASSERT_EQ(trials->status, 200) << trials->body;
  EXPECT_EQ(trials->get_header_value("Ftctune-Partial"), "true");
  expect_prefix(trials->body, full_trials);
  EXPECT_GE(lines(trials->body).size(), 1u + 4 * 8);  // iterations 0..3 of 8 bats, at least
  auto history = s.client->Get(("/v1/jobs/" + id + "/history").c_str());
  ASSERT_EQ(history->status, 200) << history->body;
  expect_prefix(history->body, full_history);
  const json rows = s.get("/v1/jobs/" + id + "/history?format=json");
  ASSERT_GE(rows.size(), 4u);
  EXPECT_EQ(rows[0]["iteration"], 0);
  EXPECT_TRUE(rows[0]["best"].contains("Kp"));
  auto gains = s.client->Get(("/v1/jobs/" + id + "/gains").c_str());
  ASSERT_EQ(gains->status, 200) << gains->body;
  EXPECT_EQ(json::parse(gains->body)["optimizer"]["completed"], false);
  expect_error(s.client->Get(("/v1/jobs/" + id + "/comparison").c_str()), 409, "not_ready");
  EXPECT_EQ(s.get("/v1/jobs/" + id)["partial"], true);

  ASSERT_EQ(s.client->Post(("/v1/jobs/" + id + "/cancel").c_str(), "", "application/json")->status,
            202);
  const json done = s.wait_done(id);
  ASSERT_EQ(done["status"], "cancelled");
  EXPECT_EQ(done["partial"], true);
  const int ran = done["progress"]["iteration"];
  ASSERT_LT(ran, 60);
  gains = s.client->Get(("/v1/jobs/" + id + "/gains").c_str());
  ASSERT_EQ(gains->status, 200) << gains->body;
  EXPECT_EQ(gains->get_header_value("Ftctune-Partial"), "true");
  const json g = json::parse(gains->body);
  EXPECT_EQ(g["optimizer"]["completed"], false);
  EXPECT_EQ(g["history"].size(), static_cast<std::size_t>(ran + 1));
  EXPECT_EQ(g["history"].back()["best"], done["progress"]["best"]);
  EXPECT_TRUE(g["baseline"]["objective"].is_number());  // compared as a finished run's best is
  trials = s.client->Get(("/v1/jobs/" + id + "/trials").c_str());
  expect_prefix(trials->body, full_trials);
  EXPECT_EQ(lines(trials->body).size(), 1u + done["progress"]["evaluations"].get<std::size_t>());
  expect_prefix(s.client->Get(("/v1/jobs/" + id + "/history").c_str())->body, full_history);
  EXPECT_EQ(s.get("/v1/jobs/" + id + "/comparison")["controllers"].size(), 4u);

  // The folder `ftctune run` writes: fetch --all brings it, and `ftctune report` takes it.
  const json listing = s.get("/v1/jobs/" + id + "/files");
  EXPECT_EQ(listing["partial"], true);
  std::set<std::string> names;
  for (const json& f : listing["files"]) names.insert(f["name"].get<std::string>());
  for (const char* f : {"gains.json", "history.csv", "trials.csv", "job.json", "comparison.json",
                        "comparison.md", "run.json"})
    EXPECT_TRUE(names.count(f)) << f;
  expect_error(s.client->Get(("/v1/jobs/" + id + "/files/nothing.csv").c_str()), 404, "not_found");
  const auto dir = fresh_dir("partial-fetch");
  const std::string server = " --server http://127.0.0.1:" + std::to_string(s.port);
  CliResult r = run_cli(
      "fetch " + id + " --all -o '" + (dir / "run" / "gains.json").string() + "'" + server, dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("optimizer.completed false"), std::string::npos) << r.err;
  for (const std::string& f : names) EXPECT_TRUE(std::filesystem::exists(dir / "run" / f)) << f;
  EXPECT_EQ(slurp(dir / "run" / "gains.json"), gains->body);
  r = run_cli("report '" + (dir / "run").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

// A client of GET /v1/events on its own thread, collecting what it receives.
struct EventClient {
  EventClient(int port, const std::string& path) {
    client = std::make_unique<httplib::Client>("127.0.0.1", port);
    client->set_read_timeout(60, 0);
    thread = std::thread([this, path] {
      auto r = client->Get(
          path.c_str(),
          [this](const httplib::Response& res) {
            status = res.status;
            return res.status == 200;
          },
          [this](const char* data, std::size_t n) {
            std::lock_guard<std::mutex> lock(mutex);
            text.append(data, n);
            return !stop;
          });
      ended = true;
    });
  }
  ~EventClient() {
    stop = true;
    client->stop();  // a stream waiting for its next event
    thread.join();
  }
  std::string received() {
    std::lock_guard<std::mutex> lock(mutex);
    return text;
  }
  // The data of every event of `type`, parsed.
  std::vector<json> events(const std::string& type) {
    std::vector<json> out;
    const std::string t = received();
    const std::string marker = "event: " + type + "\ndata: ";
    for (std::size_t i = t.find(marker); i != std::string::npos; i = t.find(marker, i + 1)) {
      const std::size_t start = i + marker.size(), end = t.find('\n', start);
      if (end == std::string::npos) break;
      out.push_back(json::parse(t.substr(start, end - start)));
    }
    return out;
  }
  bool wait_for(const std::function<bool(EventClient&)>& holds, std::chrono::seconds deadline) {
    const auto end = std::chrono::steady_clock::now() + deadline * FTC_TEST_SLOWDOWN;
    while (std::chrono::steady_clock::now() < end) {
      if (holds(*this)) return true;
      std::this_thread::sleep_for(5ms);
    }
    return holds(*this);
  }
  std::mutex mutex;
  std::string text;
  std::atomic<int> status{0};
  std::atomic<bool> stop{false}, ended{false};
  std::unique_ptr<httplib::Client> client;
  std::thread thread;
};

// Every open stream gets each change of a job as the store commits it (queued, started, each
// iteration, finished); a stream may follow one job only. Streams are capped (at half the
// connection threads), the API stays answered with every stream open, and stopping the server
// ends them.
TEST(Service, EventsStreamEachChangeToEveryOpenPage) {
  tune::ServiceOptions o;
  o.max_connections = 12;
  o.max_connections_per_client = 11;  // up to 5 streams from one address
  o.max_event_streams = 4;
  Service s(o);
  std::vector<std::unique_ptr<EventClient>> pages;
  for (int i = 0; i < 2; ++i) pages.push_back(std::make_unique<EventClient>(s.port, "/v1/events"));
  for (auto& p : pages)
    ASSERT_TRUE(p->wait_for(
        [](EventClient& c) { return c.received().find(": ftctune events") != std::string::npos; },
        10s));
  const std::string other = s.submit(tiny_job("other"))["id"];
  s.wait_done(other);
  // The store commits a job's end before the hub tells it: wait until the pages were told, or
  // a stream opened in between would rightly get that last change.
  for (auto& p : pages)
    ASSERT_TRUE(p->wait_for(
        [&](EventClient& c) {
          for (const json& e : c.events("job"))
            if (e["id"] == other && e["status"] == "succeeded") return true;
          return false;
        },
        10s))
        << p->received();
  auto one = std::make_unique<EventClient>(s.port, "/v1/events?job=" + other);
  // A job runs meanwhile, so that the next one waits in the queue until its stream is open.
  const std::string blocker = s.submit(long_job("blocker"))["id"];
  const std::string id = s.submit(short_table1_job())["id"];
  auto mine = std::make_unique<EventClient>(s.port, "/v1/jobs/" + id + "/events");
  ASSERT_TRUE(mine->wait_for(
      [](EventClient& c) { return c.received().find(": ftctune events") != std::string::npos; },
      10s));
  s.client->Post(("/v1/jobs/" + blocker + "/cancel").c_str(), "", "application/json");
  // The fifth stream is one too many; the API still answers.
  EventClient fifth(s.port, "/v1/events");
  ASSERT_TRUE(fifth.wait_for([](EventClient& c) { return c.ended.load(); }, 10s));
  EXPECT_EQ(fifth.status, 503);
  EXPECT_EQ(s.get("/healthz")["status"], "ok");
  s.wait_done(id);

  const auto of_job = [&](EventClient& c) {
    std::vector<json> out;
    for (const json& e : c.events("job"))
      if (e["id"] == id) out.push_back(e);
    return out;
  };
  for (auto& p : pages) {
    ASSERT_TRUE(p->wait_for(
        [&](EventClient& c) {
          const std::vector<json> ev = of_job(c);
          return !ev.empty() && ev.back()["status"] == "succeeded";
        },
        10s))
        << p->received();
    std::vector<int> iterations;
    for (const json& e : of_job(*p))
      if (e["status"] == "running" && !e["progress"]["iteration"].is_null())
        iterations.push_back(e["progress"]["iteration"]);
    EXPECT_EQ(iterations, (std::vector<int>{0, 1, 2})) << p->received();
    EXPECT_EQ(of_job(*p).front()["status"], "queued");
  }
  // Opened while it was queued: every change from its start on. Its last event may still be on
  // the way when the job's status already reads succeeded, as for the pages above.
  ASSERT_TRUE(mine->wait_for(
      [&](EventClient& c) {
        const std::vector<json> ev = c.events("job");
        return !ev.empty() && ev.back()["status"] == "succeeded";
      },
      10s))
      << mine->received();
  std::vector<int> iterations;
  for (const json& e : mine->events("job")) {
    EXPECT_EQ(e["id"], id);
    if (e["status"] == "running" && !e["progress"]["iteration"].is_null())
      iterations.push_back(e["progress"]["iteration"]);
  }
  EXPECT_EQ(iterations, (std::vector<int>{0, 1, 2})) << mine->received();
  EXPECT_EQ(mine->events("job").back()["status"], "succeeded");
  EXPECT_TRUE(one->events("job").empty());  // its job changed no more
  // A page closed frees its stream within seconds (the next keep-alive write fails).
  EXPECT_EQ(s.get("/healthz")["event_streams"], 4);
  one.reset();
  EXPECT_EQ(wait_health(s, [](const json& h) { return h["event_streams"] == 3; })["event_streams"],
            3);

  ASSERT_EQ(s.client->Delete(("/v1/jobs/" + other).c_str())->status, 200);
  ASSERT_TRUE(pages[0]->wait_for([](EventClient& c) { return !c.events("deleted").empty(); }, 10s));
  EXPECT_EQ(pages[0]->events("deleted")[0]["id"], other);

  // Stopping the server ends every stream at once.
  const auto t0 = std::chrono::steady_clock::now();
  s.service->stop();
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
  for (auto& p : pages)
    EXPECT_TRUE(p->wait_for([](EventClient& c) { return c.ended.load(); }, 10s));
}

// The dashboard's files are served to anyone (the page asks for the token; they hold no data)
// with a policy that allows only their own scripts; the API needs the token as before, and every
// answer forbids sniffing and gives no CORS header.
TEST(Service, DashboardIsServedWithAStrictPolicy) {
  tune::ServiceOptions o;
  o.token = "secret-token";
  Service s(o);
  auto page = s.client->Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_EQ(page->get_header_value("Content-Type"), "text/html; charset=utf-8");
  EXPECT_NE(page->body.find("<script src=\"/ui/app.js\""), std::string::npos);
  EXPECT_EQ(page->body.find("<script>"), std::string::npos);  // no inline script
  const std::string policy = page->get_header_value("Content-Security-Policy");
  EXPECT_NE(policy.find("script-src 'self'"), std::string::npos) << policy;
  EXPECT_EQ(policy.find("unsafe-inline"), std::string::npos) << policy;
  EXPECT_EQ(page->get_header_value("X-Content-Type-Options"), "nosniff");
  for (const char* asset : {"/ui/app.js", "/ui/style.css", "/ui/chart.min.js"}) {
    auto r = s.client->Get(asset);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200) << asset;
    EXPECT_GT(r->body.size(), 1000u) << asset;
  }
  auto api = s.client->Get("/v1/jobs");
  EXPECT_EQ(api->status, 401);
  EXPECT_EQ(api->get_header_value("X-Content-Type-Options"), "nosniff");
  EXPECT_FALSE(api->has_header("Access-Control-Allow-Origin"));
  EXPECT_EQ(api->get_header_value("Cache-Control"), "no-store");  // job data is never cached
  EXPECT_EQ(s.client->Get("/v1/events")->status, 401);
  EXPECT_EQ(s.client->Get("/v1/metrics")->status, 401);
  EXPECT_EQ(s.client->Get("/ui/other.js")->status, 401);  // only the dashboard's own files

  // The list filters by name, for a page of a large store.
  s.client->set_bearer_token_auth("secret-token");
  s.wait_done(s.submit(tiny_job("alpha"))["id"]);
  s.wait_done(s.submit(tiny_job("beta"))["id"]);
  const json found = s.get("/v1/jobs?name=alp");
  EXPECT_EQ(found["total"], 1);
  ASSERT_EQ(found["jobs"].size(), 1u);
  EXPECT_EQ(found["jobs"][0]["name"], "alpha");
  const json both = s.get("/v1/jobs?name=a&status=succeeded&limit=1");
  EXPECT_EQ(both["total"], 2);
  ASSERT_EQ(both["jobs"].size(), 1u);
  EXPECT_EQ(both["jobs"][0]["name"], "beta");  // newest first
  EXPECT_EQ(s.get("/v1/jobs?name=a&status=queued")["total"], 0);
}

// POST /v1/validate checks a job as a submission would, and submits nothing.
// Plant plugins: the server runs the ones it was started with (serve --plugin) and no other,
// whatever a job names and wherever the plant search path points; nothing a job says makes it
// load a library.
TEST(Service, RunsOnlyThePlantPluginsItWasStartedWith) {
  const std::filesystem::path lib =
      std::filesystem::path(FTC_PLUGIN_DIR) / "ftctune_plant_reaction_wheel_pendulum.so";
  ::setenv("FTCTUNE_PLANT_PATH", FTC_PLUGIN_DIR "/broken", 1);
  tune::ServiceOptions o;
  o.plugins = {lib};
  Service s(o);
  json job =
      json::parse(slurp(std::filesystem::path(FTC_SOURCE_DIR) / "examples/plant-plugin/job.json"));
  job["tuning"]["algorithm"]["iterations"] = 2;
  const json view = s.wait_done(s.submit(job)["id"]);
  EXPECT_EQ(view["status"], "succeeded") << view.dump();
  // A library the search path holds, and one that is nowhere: both refused, 422, at /plant/model.
  for (const char* other : {"plugin:throws", "plugin:not_anywhere"}) {
    json j = job;
    j["plant"] = {{"model", other}};
    for (const char* route : {"/v1/jobs", "/v1/validate"}) {
      const auto r = s.client->Post(route, j.dump(), "application/json");
      ASSERT_TRUE(r);
      EXPECT_EQ(r->status, 422) << r->body;
      const json e = json::parse(r->body)["error"];
      EXPECT_EQ(e["code"], "plugin_not_loaded");
      EXPECT_EQ(e["details"][0]["path"], "/plant/model");
      EXPECT_NE(e["message"].get<std::string>().find(
                    "is not one of the plugins this server was started with "
                    "(plugin:reaction_wheel_pendulum); a job cannot make it load a library"),
                std::string::npos)
          << e.dump();
    }
  }
  ::unsetenv("FTCTUNE_PLANT_PATH");
}

TEST(Service, APluginOfAnotherAbiStopsTheServerFromStarting) {
  const std::string lib = FTC_PLUGIN_DIR "/broken/ftctune_plant_wrong_abi.so";
  const auto dir = fresh_dir("plugin-abi");
  const CliResult r = run_cli("serve --port 0 --store store --plugin '" + lib + "'", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("was built for plant ABI 2"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("rebuild it with ftctune_add_plant"), std::string::npos) << r.err;
}

TEST(Service, ValidateChecksAJobWithoutSubmittingIt) {
  Service s;
  auto r = s.client->Post("/v1/validate", short_table1_job().dump(), "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  const json ok = json::parse(r->body);
  EXPECT_EQ(ok["valid"], true);
  EXPECT_EQ(ok["name"], short_table1_job()["name"]);
  EXPECT_EQ(ok["total_evaluations"], 9);
  json bad = short_table1_job();
  bad["scenarios"][0]["duration"] = -1;
  bad["tuning"]["parameters"]["Kp"] = {"low", 50};
  r = s.client->Post("/v1/validate", bad.dump(), "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400);
  const json e = json::parse(r->body);
  EXPECT_EQ(e["error"]["code"], "invalid_job");
  std::set<std::string> paths;
  for (const json& d : e["error"]["details"]) paths.insert(d["path"].get<std::string>());
  EXPECT_TRUE(paths.count("/scenarios/0/duration")) << r->body;
  EXPECT_TRUE(paths.count("/tuning/parameters/Kp")) << r->body;
  // The same details as a submission's 400.
  auto submitted = s.client->Post("/v1/jobs", bad.dump(), "application/json");
  EXPECT_EQ(submitted->status, 400);
  EXPECT_EQ(json::parse(submitted->body)["error"]["details"], e["error"]["details"]);
  expect_error(s.client->Post("/v1/validate", "{", "application/json"), 400, "invalid_json");
  expect_error(s.client->Get("/v1/validate"), 405, "method_not_allowed");
  EXPECT_EQ(s.get("/v1/jobs")["total"], 0);  // nothing was submitted

  // 30 000 broken scenarios (a 90 KB body): the first 100 errors listed, the rest counted. It
  // answered every one, 11.8 MB for a 300 KB body.
  json many = short_table1_job();
  many["scenarios"] = json::array();
  for (int i = 0; i < 30000; ++i) many["scenarios"].push_back(json::object());
  r = s.client->Post("/v1/validate", many.dump(), "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400);
  const json capped = json::parse(r->body);
  ASSERT_EQ(capped["error"]["details"].size(), tune::kMaxReportedErrors);
  EXPECT_GT(capped["error"]["details_omitted"].get<std::size_t>(), 30000u);
  EXPECT_LT(r->body.size(), 20000u);
  EXPECT_NE(capped["error"]["message"].get<std::string>().find(
                "(and " +
                std::to_string(capped["error"]["details_omitted"].get<std::size_t>() + 99) +
                " more)"),
            std::string::npos)
      << capped["error"]["message"];
}

// Jobs are checked on one worker, one at a time, under a deadline: a request whose check is not
// done in time is answered 503, and one whose client hung up is given up (never run when it was
// still waiting). Before, each request checked its body on its own thread to the end: a 300 KB
// body took 54-63 s, and the server kept both cores busy after the client had gone.
TEST(Service, JobsAreCheckedOneAtATimeUnderADeadlineAndGivenUpWhenTheClientLeaves) {
  tune::ServiceOptions o;
  o.check_timeout = 0.3;
  Service s(o);
  // 200 000 empty scenarios: 400 000 errors, about 1.3 s to check on this machine.
  json broken = short_table1_job();
  broken["scenarios"] = json::array();
  for (int i = 0; i < 200000; ++i) broken["scenarios"].push_back(json::object());
  const std::string body = broken.dump();
  const auto idle = [](const json& h) {
    return h["checks"]["queued"] == 0 && h["checks"]["running"] == false;
  };

  auto r = s.client->Post("/v1/validate", body, "application/json");
  expect_error(r, 503, "check_timeout");
  EXPECT_EQ(r->get_header_value("Retry-After"), "10");
  EXPECT_NE(r->body.find("not checked within 0.3 s (--check-timeout"), std::string::npos) << r->body;
  json h = s.get("/healthz");  // answered while the check runs on
  EXPECT_EQ(h["checks"]["abandoned"], 1) << h.dump();
  h = wait_health(s, idle);
  ASSERT_TRUE(idle(h)) << h.dump();
  EXPECT_EQ(h["checks"]["skipped"], 0);  // it had started: it ran to its end
  // A small job is checked in time, by validate and by submit alike.
  r = s.client->Post("/v1/validate", short_table1_job().dump(), "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200) << r->body;
  expect_error(s.client->Post("/v1/jobs", body, "application/json"), 503, "check_timeout");
  EXPECT_EQ(s.get("/v1/jobs")["total"], 0);
  ASSERT_TRUE(idle(wait_health(s, idle)));

  // Three clients send the body and hang up: one check starts, the others are never run.
  const std::string request =
      "POST /v1/validate HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
      "Content-Length: " +
      std::to_string(body.size()) + "\r\n\r\n" + body;
  tune::ServiceOptions patient;
  patient.check_timeout = 600;
  Service p(patient);
  for (int i = 0; i < 3; ++i) {
    const int fd = connect_from("127.0.0.1", p.port);
    ASSERT_GE(fd, 0);
    EXPECT_TRUE(send_all(fd, request));
    ::close(fd);
  }
  h = wait_health(p, [](const json& x) { return x["checks"]["abandoned"] == 3; });
  EXPECT_EQ(h["checks"]["abandoned"], 3) << h.dump();
  h = wait_health(p, idle);
  ASSERT_TRUE(idle(h)) << h.dump();
  EXPECT_GE(h["checks"]["skipped"].get<int>(), 1) << h.dump();
}

// DELETE removes a finished job with its results; a queued or running one is refused.
TEST(Service, DeleteRemovesFinishedJobsOnly) {
  Service s;
  auto& c = *s.client;
  const std::string done = s.submit(tiny_job())["id"];
  s.wait_done(done);
  const std::string waiting = s.submit(long_job())["id"];
  const auto r = c.Delete(("/v1/jobs/" + waiting).c_str());
  expect_error(r, 409, "conflict");
  EXPECT_EQ(c.Delete(("/v1/jobs/" + done).c_str())->status, 200);
  expect_error(c.Get(("/v1/jobs/" + done).c_str()), 404, "not_found");
  expect_error(c.Get(("/v1/jobs/" + done + "/gains").c_str()), 404, "not_found");
  expect_error(c.Delete(("/v1/jobs/" + done).c_str()), 404, "not_found");
  c.Post(("/v1/jobs/" + waiting + "/cancel").c_str(), "", "application/json");
}

// A job that takes the server down each time it runs is not retried forever: after
// max_attempts starts, crash recovery fails it with the reason; younger jobs go back to the queue.
TEST(Service, CrashRecoveryGivesUpAJobAfterItsAttempts) {
  const auto dir = fresh_dir("retry-cap");
  std::string doomed, young;
  {
    tune::JobStore store(dir / "store");
    const auto submit = [&](const std::string& name) {
      tune::Submission sub;
      sub.job_json = tiny_job(name).dump();
      sub.name = name;
      sub.iterations = 1;
      sub.total_evaluations = 1;
      return store.submit(sub).record.id;
    };
    doomed = submit("doomed");
    // Started, and the server "crashed" under it, twice; the third start crashes too.
    for (int i = 0; i < 2; ++i) {
      ASSERT_EQ(store.claim_next()->id, doomed);
      const tune::JobStore::Recovery r = store.recover(3);
      EXPECT_EQ(r.requeued, 1);
      EXPECT_EQ(r.failed, 0);
    }
    ASSERT_EQ(store.claim_next()->id, doomed);
    young = submit("young");
    ASSERT_EQ(store.claim_next()->id, young);
    const tune::JobStore::Recovery r = store.recover(3);
    EXPECT_EQ(r.failed, 1);
    EXPECT_EQ(r.requeued, 1);
    const tune::JobRecord d = *store.get(doomed);
    EXPECT_EQ(d.status, tune::JobStatus::failed);
    EXPECT_EQ(d.attempts, 3);
    EXPECT_NE(d.error.find("given up after 3 starts"), std::string::npos) << d.error;
    EXPECT_EQ(store.get(young)->status, tune::JobStatus::queued);
  }
}

// A store that cannot write (a full disk) refuses the write whole: nothing changes, reads go on,
// and the same write succeeds once there is room.
TEST(Service, StoreOnAFullDiskRefusesWritesAndChangesNothing) {
  const auto dir = fresh_dir("store-full");
  FreeDiskOnExit free_disk;
  tune::JobStore store(dir / "store");
  tune::Submission sub;
  sub.job_json = tiny_job().dump();
  sub.name = "tiny";
  sub.iterations = 1;
  sub.total_evaluations = 2;
  const std::string id = store.submit(sub).record.id;
  tune::inject_store_full(1);
  try {
    store.submit(sub);
    ADD_FAILURE() << "a submission was written to a full disk";
  } catch (const tune::StoreError& e) {
    EXPECT_TRUE(e.full());
    EXPECT_TRUE(e.transient());
    EXPECT_NE(std::string(e.what()).find("database or disk is full"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(store.claim_next(), tune::StoreError);
  EXPECT_EQ(store.count(std::nullopt), 1);
  EXPECT_EQ(store.get(id)->status, tune::JobStatus::queued);
  EXPECT_EQ(store.get(id)->attempts, 0);
  tune::inject_store_full(0);
  const std::optional<tune::JobRecord> claimed = store.claim_next();
  ASSERT_TRUE(claimed);
  EXPECT_EQ(claimed->id, id);
  EXPECT_EQ(claimed->attempts, 1);
}

// Issue 13, defect 1: a full disk cost a finished job its results, failed it and left the next
// job `running` until a restart. Now the results wait in memory and are written once there is
// room, without a restart; nothing else starts meanwhile, cancel still works, and new
// submissions get 507.
TEST(Service, FullDiskKeepsAFinishedJobsResultsUntilTheStoreWritesAgain) {
  tune::ServiceOptions o;
  o.store_retry_seconds = 0.1;
  Service s(o);
  FreeDiskOnExit free_disk;
  const json job = long_job();
  const std::string a = s.submit(job)["id"];
  const std::string queued = s.submit(tiny_job("queued"))["id"];
  wait_running(s, a, 2);
  tune::inject_store_full(1);

  auto r = s.client->Post("/v1/jobs", tiny_job("refused").dump(), "application/json");
  expect_error(r, 507, "insufficient_storage");
  EXPECT_NE(r->body.find("database or disk is full"), std::string::npos) << r->body;
  EXPECT_EQ(r->get_header_value("Retry-After"), "1");
  // The store cannot record the cancellation: it holds in memory (the job is not started).
  r = s.client->Post(("/v1/jobs/" + queued + "/cancel").c_str(), "", "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  EXPECT_TRUE(json::parse(r->body)["cancel_requested"].get<bool>());

  // The running job finishes (its checkpoints are refused too); its results wait in memory.
  json health = wait_health(s, [](const json& h) { return h["store"]["unstored_jobs"] == 1; });
  ASSERT_EQ(health["store"]["unstored_jobs"], 1) << health.dump();
  EXPECT_EQ(health["status"], "degraded");
  EXPECT_FALSE(health["store"]["writable"].get<bool>());
  EXPECT_EQ(health["store"]["unrecorded_cancels"], 1);
  const json held = s.get("/v1/jobs/" + a);
  EXPECT_EQ(held["status"], "running");
  EXPECT_EQ(held["unstored"]["status"], "succeeded") << held.dump();
  expect_error(s.client->Get(("/v1/jobs/" + a + "/gains").c_str()), 409, "not_ready");
  r = s.client->Post("/v1/jobs", tiny_job("refused").dump(), "application/json");
  expect_error(r, 507, "insufficient_storage");
  EXPECT_NE(r->body.find("1 finished job waits in memory"), std::string::npos) << r->body;
  std::this_thread::sleep_for(300ms);  // a few retries: none gets through, nothing else starts
  EXPECT_EQ(s.get("/v1/jobs/" + queued)["attempts"], 0);
  EXPECT_EQ(s.get("/v1/jobs?status=running")["total"], 1);

  tune::inject_store_full(0);
  const json done = s.wait_done(a, 10s);
  EXPECT_EQ(done["status"], "succeeded");
  EXPECT_TRUE(done["unstored"].is_null());
  EXPECT_EQ(done["finished_at"], held["unstored"]["finished_at"]);  // when it finished
  EXPECT_EQ(s.client->Get(("/v1/jobs/" + a + "/gains").c_str())->body, expected_gains(job));
  const json cancelled = s.wait_done(queued, 10s);
  EXPECT_EQ(cancelled["status"], "cancelled");
  EXPECT_EQ(cancelled["attempts"], 0);
  health = wait_health(s, [](const json& h) { return h["status"] == "ok"; });
  EXPECT_EQ(health["status"], "ok") << health.dump();
  EXPECT_TRUE(health["store"]["error"].is_null());
  const std::string after = s.submit(tiny_job("after"))["id"];
  EXPECT_EQ(s.wait_done(after)["status"], "succeeded");
  EXPECT_EQ(s.get("/v1/jobs?status=running")["total"], 0);

  // The files layer's seam: a report drawn on a full temporary disk is a 507 too, and the next
  // request draws it.
  tune::inject_io_failure(1);
  expect_error(s.client->Get(("/v1/jobs/" + a + "/report").c_str()), 507, "insufficient_storage");
  EXPECT_EQ(s.client->Get(("/v1/jobs/" + a + "/report").c_str())->status, 200);
}

// Cancelling a job whose results are held drops them: it ends cancelled once the store writes.
TEST(Service, CancellingAJobWhoseResultsAreHeldDropsThem) {
  tune::ServiceOptions o;
  o.store_retry_seconds = 0.1;
  Service s(o);
  FreeDiskOnExit free_disk;
  const std::string a = s.submit(long_job())["id"];
  wait_running(s, a, 2);
  tune::inject_store_full(1);
  const json health =
      wait_health(s, [](const json& h) { return h["store"]["unstored_jobs"] == 1; });
  ASSERT_EQ(health["store"]["unstored_jobs"], 1) << health.dump();
  auto r = s.client->Post(("/v1/jobs/" + a + "/cancel").c_str(), "", "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  EXPECT_EQ(json::parse(r->body)["unstored"]["status"], "cancelled") << r->body;
  expect_error(s.client->Post(("/v1/jobs/" + a + "/cancel").c_str(), "", "application/json"), 409,
               "conflict");
  tune::inject_store_full(0);
  EXPECT_EQ(s.wait_done(a, 10s)["status"], "cancelled");
  expect_error(s.client->Get(("/v1/jobs/" + a + "/gains").c_str()), 409, "not_ready");
}

// The same on a real full disk: a small tmpfs holds the store. Needs root (to mount it); skipped
// elsewhere.
TEST(Service, RealFullDiskOnATmpfs) {
  if (::geteuid() != 0) GTEST_SKIP() << "mounting a tmpfs needs root";
  const auto dir = fresh_dir("tmpfs");
  const auto mnt = dir / "mnt";
  std::filesystem::create_directories(mnt);
  if (::mount("tmpfs", mnt.c_str(), "tmpfs", 0, "size=8m,mode=0700") != 0)
    GTEST_SKIP() << "cannot mount a tmpfs: " << std::strerror(errno);
  struct Unmount {
    std::filesystem::path at;
    ~Unmount() { ::umount2(at.c_str(), MNT_DETACH); }
  } unmount{mnt};
  tune::ServiceOptions o;
  o.store = mnt / "store";
  o.store_retry_seconds = 0.1;
  Service s(o);
  // Fill the disk, then free 192 KiB: room for the submission and the checkpoints, not for the
  // results (about 0.5 MB).
  const auto filler = mnt / "filler";
  {
    const int fd = ::open(filler.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0600);
    ASSERT_GE(fd, 0);
    const std::string chunk(1 << 16, 'x');
    off_t size = 0;
    for (ssize_t n; (n = ::write(fd, chunk.data(), chunk.size())) > 0;) size += n;
    EXPECT_EQ(errno, ENOSPC);
    ASSERT_EQ(::ftruncate(fd, size - (192 << 10)), 0);
    ::close(fd);
  }
  const json job = short_table1_job();
  const std::string id = s.submit(job)["id"];
  const json health =
      wait_health(s, [](const json& h) { return h["store"]["unstored_jobs"] == 1; });
  ASSERT_EQ(health["store"]["unstored_jobs"], 1) << health.dump();
  expect_error(s.client->Post("/v1/jobs", tiny_job().dump(), "application/json"), 507,
               "insufficient_storage");
  std::filesystem::remove(filler);
  EXPECT_EQ(s.wait_done(id, 10s)["status"], "succeeded");
  EXPECT_EQ(s.client->Get(("/v1/jobs/" + id + "/gains").c_str())->body, expected_gains(job));
  EXPECT_EQ(s.submit(tiny_job())["status"], "queued");
}

// Issue 13, defect 2: what one job may store is bounded. A job that cannot fit is refused when
// submitted; one that outgrows the limit fails with the reason, while it runs (its checkpointed
// trials) or at its end (its result files).
// Memory by design: a job whose run would hold more than --max-job-mib (a few numbers per
// ensemble member and controller scored at once) is refused when submitted, 413 saying how much
// it would need. The audit's 1e6-member job drove the server to 1.79 GB when members were held;
// now generated as they are simulated, it needs an estimated 235 MB: over a limit of 128 MiB.
TEST(Service, JobAboveTheMemoryBudgetIsRefusedWith413) {
  tune::ServiceOptions o;
  o.max_steps = 1e18;  // the memory check, not the steps budget
  o.max_job_memory_bytes = std::uint64_t{128} << 20;
  Service s(o);
  json j = tiny_job("million-members");
  j["ensemble"] = {{"count", 1000000}, {"seed", 1}};
  auto r = s.client->Post("/v1/jobs", j.dump(), "application/json");
  expect_error(r, 413, "job_too_large");
  EXPECT_NE(r->body.find("the job would need about 235 MB of memory (1 listed scenario and its "
                         "comparison at about 0.0898 MB, 1000000 ensemble "
                         "members at about 168 bytes each, 4 trials at about 1344 bytes each, "
                         "its result files held to be stored at about 0.00432 MB)"),
            std::string::npos)
      << r->body;
  EXPECT_NE(r->body.find("above the server's limit of 134 MB per job"), std::string::npos)
      << r->body;
  j["ensemble"]["count"] = 1000;  // about 67 MB
  r = s.client->Post("/v1/jobs", j.dump(), "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 201) << r->body;
  // Accepted is all this test needs: the job is cancelled rather than left running.
  const std::string id = json::parse(r->body)["id"];
  s.client->Post(("/v1/jobs/" + id + "/cancel").c_str(), "", "application/json");
}

// The service holds a copy of a job's result files to store them, which `ftctune run` does not:
// a job of 6 scenarios of 200 s with 12 controllers peaked `run` at 713 MB and the server at
// 996 MB, while the run's estimate alone was 932 MB. Its estimate now adds the files, at 13 bytes
// a number (they stored 278.1 MB).
TEST(Service, TheMemoryEstimateCountsTheResultFilesTheServerHolds) {
  json j = short_table1_job();
  j["name"] = "long";
  json scenario = j["scenarios"][0];
  scenario["duration"] = 200;
  j["scenarios"] = json::array();
  for (int i = 0; i < 6; ++i) {
    scenario["name"] = "s" + std::to_string(i);
    j["scenarios"].push_back(scenario);
  }
  j["objective"]["window"] = {0, 200};
  const json compared = j["compare"];
  j["compare"] = json::array();
  for (int i = 0; i < 10; ++i) {
    json c = compared[i % 2];
    c["label"] = "C" + std::to_string(i);
    j["compare"].push_back(c);
  }
  tune::ServiceOptions o;
  o.max_job_memory_bytes = 950'000'000;  // above the run's estimate, below the server's peak
  Service s(o);
  auto r = s.client->Post("/v1/jobs", j.dump(), "application/json");
  expect_error(r, 413, "job_too_large");
  EXPECT_NE(r->body.find("6 listed scenarios and their comparison at about 865 MB"),
            std::string::npos)
      << r->body;
  EXPECT_NE(r->body.find("its result files held to be stored at about 281 MB"), std::string::npos)
      << r->body;
  EXPECT_EQ(s.get("/v1/jobs")["total"], 0);
}

TEST(Service, StoredBytesPerJobAreBounded) {
  tune::ServiceOptions o;
  o.max_stored_bytes = 1 << 20;
  Service s(o);
  const auto scenario_of = [](double duration) {
    json j = tiny_job("long-scenario");
    j["scenarios"][0]["duration"] = duration;
    j["objective"]["window"] = {0, duration};
    return j;
  };
  // 600 s: 20000 rows (the default limit) × 15 numbers × 4 controllers is above 1 MiB.
  auto r = s.client->Post("/v1/jobs", scenario_of(600).dump(), "application/json");
  expect_error(r, 400, "job_too_large");
  EXPECT_NE(r->body.find("would take at least 9.6 MB"), std::string::npos) << r->body;

  // 17.5 s: estimated below the limit, stored above it.
  json v = s.wait_done(s.submit(scenario_of(17.5))["id"]);
  EXPECT_EQ(v["status"], "failed");
  EXPECT_NE(v["error"].get<std::string>().find("its results take 1.4 MB, above the server's "
                                               "limit of 1.0 MB per job (--max-stored-mib)"),
            std::string::npos)
      << v.dump();

  // 14000 evaluations: estimated at 0.9 MB, their trials outgrow the limit in the checkpoints.
  json many = tiny_job("many-trials");
  many["tuning"]["algorithm"]["population"] = 100;
  many["tuning"]["algorithm"]["iterations"] = 139;
  v = s.wait_done(s.submit(many)["id"]);
  EXPECT_EQ(v["status"], "failed");
  EXPECT_NE(v["error"].get<std::string>().find("its checkpoint (the optimiser's state and the "
                                               "trials so far) reached"),
            std::string::npos)
      << v.dump();
  EXPECT_LT(v["progress"]["iteration"].get<int>(), 139) << "it stopped when it crossed the limit";
  EXPECT_EQ(s.get("/healthz")["status"], "ok");
}

// The service stores trajectories for the report at no more than --trajectory-rows rows: a
// longer scenario is recorded every k-th 10 ms sample (the same rows, fewer of them); the
// metrics, computed from every sample, do not change.
TEST(Service, StoredTrajectoriesAreDecimatedToTheRowLimit) {
  tune::ServiceOptions o;
  o.trajectory_rows = 100;
  Service s(o);
  const json job = short_table1_job();  // 5 s: 500 rows of 10 ms
  const std::string id = s.submit(job)["id"];
  ASSERT_EQ(s.wait_done(id)["status"], "succeeded");
  const std::string comparison = s.client->Get(("/v1/jobs/" + id + "/comparison").c_str())->body;
  EXPECT_EQ(s.client->Get(("/v1/jobs/" + id + "/report").c_str())->status, 200);
  s.service.reset();  // frees the store for the reading below

  tune::TbbEvaluator evaluator(2);
  const std::map<std::string, std::string> full =
      tune::output_files(tune::tune(tune::parse_job(job, "full"), evaluator));
  EXPECT_EQ(comparison, full.at("comparison.json"));
  tune::JobStore store(s.dir / "store");
  int trajectories = 0;
  for (const auto& [name, csv] : store.artifacts(id)) {
    if (name.rfind("trajectories/", 0) != 0) continue;
    ++trajectories;
    const auto lines = [](const std::string& text) {
      std::vector<std::string> out;
      std::istringstream in(text);
      for (std::string line; std::getline(in, line);) out.push_back(line);
      return out;
    };
    const std::vector<std::string> kept = lines(csv), all = lines(full.at(name));
    ASSERT_EQ(all.size(), 501u) << name;
    ASSERT_EQ(kept.size(), 101u) << name;  // the header and 100 rows
    for (std::size_t k = 0; k < 100; ++k) EXPECT_EQ(kept[1 + k], all[1 + 5 * k]) << name << k;
  }
  EXPECT_EQ(trajectories, 4);
}

// Issue 13, defect 2: the queue has a quota, per client address (429) and in all (503), both
// with Retry-After; a resubmission with a used Idempotency-Key still finds its job.
TEST(Service, QueueQuotaAnswers429PerClientAnd503WhenFull) {
  tune::ServiceOptions o;
  o.max_queued = 3;
  o.max_queued_per_client = 2;
  Service s(o);
  const std::string running = s.submit(long_job())["id"];
  wait_running(s, running, 0);  // running jobs do not count
  httplib::Headers key = {{"Idempotency-Key", "first"}};
  auto r = s.client->Post("/v1/jobs", key, tiny_job("1").dump(), "application/json");
  ASSERT_EQ(r->status, 201) << r->body;
  const std::string first = json::parse(r->body)["id"];
  s.submit(tiny_job("2"));
  r = s.client->Post("/v1/jobs", tiny_job("3").dump(), "application/json");
  expect_error(r, 429, "too_many_jobs");
  EXPECT_EQ(r->get_header_value("Retry-After"), "60");
  EXPECT_NE(r->body.find("this client (127.0.0.1) has 2 jobs queued"), std::string::npos)
      << r->body;

  std::string reply = raw_request("127.0.0.2", s.port, post_job(tiny_job("other-client")));
  EXPECT_EQ(status_of(reply), 201) << reply;
  reply = raw_request("127.0.0.3", s.port, post_job(tiny_job("third-client")));
  EXPECT_EQ(status_of(reply), 503) << reply;
  EXPECT_NE(reply.find("\"queue_full\""), std::string::npos) << reply;
  EXPECT_NE(reply.find("Retry-After: 60"), std::string::npos) << reply;

  r = s.client->Post("/v1/jobs", key, tiny_job("1").dump(), "application/json");
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(json::parse(r->body)["id"], first);
  EXPECT_EQ(s.get("/v1/jobs?status=queued")["total"], 3);
  s.client->Post(("/v1/jobs/" + running + "/cancel").c_str(), "", "application/json");
}

// Issue 13, defect 3: clients trickling their requests a line at a time no longer hold the
// server's threads: one address gets at most --max-connections-per-client of them (the rest are
// answered 429 at once), a request's headers and body each have a deadline (408, connection
// closed), and /healthz from another client is answered throughout. Here 12 connections from
// 127.0.0.2 send a header line every 0.5 s, well within the 5 s any one wait is allowed.
TEST(Service, SlowClientsAreCutOffAndHealthStaysAnswered) {
  tune::ServiceOptions o;
  o.header_timeout = 1.5;
  o.body_timeout = 1.5;
  o.max_connections = 8;
  o.max_connections_per_client = 4;
  Service s(o);
  using Clock = std::chrono::steady_clock;
  struct Trickler {
    int fd = -1;
    std::string reply;
    bool closed = false;
    double closed_after = 0;  // seconds from its first byte
  };
  std::vector<Trickler> tricklers(12);
  std::vector<std::thread> threads;
  for (Trickler& t : tricklers)
    threads.emplace_back([&t, port = s.port] {
      t.fd = connect_from("127.0.0.2", port);
      if (t.fd < 0) return;
      const auto start = Clock::now();
      send_all(t.fd, "GET /healthz HTTP/1.1\r\n");
      for (int line = 0; line < 12 && !t.closed; ++line) {  // 6 s of header lines
        t.reply += read_until_closed(t.fd, 500ms, &t.closed);
        if (!t.closed && !send_all(t.fd, "X-Slow: " + std::to_string(line) + "\r\n")) break;
      }
      if (!t.closed) t.reply += read_until_closed(t.fd, 3s, &t.closed);
      t.closed_after = std::chrono::duration<double>(Clock::now() - start).count();
      ::close(t.fd);
    });
  // Meanwhile another client asks for /healthz every 0.25 s.
  std::this_thread::sleep_for(200ms);
  double slowest = 0;
  for (int i = 0; i < 12; ++i) {
    const auto t0 = Clock::now();
    const auto r = s.client->Get("/healthz");
    slowest = std::max(slowest, std::chrono::duration<double>(Clock::now() - t0).count());
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200);
    std::this_thread::sleep_for(250ms);
  }
  for (std::thread& t : threads) t.join();
  EXPECT_LT(slowest, 0.5) << "/healthz waited behind the slow clients";
  int refused = 0, timed_out = 0;
  for (const Trickler& t : tricklers) {
    ASSERT_GE(t.fd, 0);
    EXPECT_TRUE(t.closed) << t.reply;
    // Written straight to the socket, yet with the headers of every other answer.
    EXPECT_NE(t.reply.find("X-Content-Type-Options: nosniff\r\n"), std::string::npos) << t.reply;
    if (status_of(t.reply) == 429) {
      ++refused;
      EXPECT_NE(t.reply.find("too_many_connections"), std::string::npos) << t.reply;
      EXPECT_LT(t.closed_after, 1.0);
    } else {
      ++timed_out;
      EXPECT_EQ(status_of(t.reply), 408) << t.reply;
      EXPECT_NE(t.reply.find("request_timeout"), std::string::npos) << t.reply;
      EXPECT_GT(t.closed_after, 1.4);  // the header deadline, not anything sooner
      EXPECT_LT(t.closed_after, 3.0);
    }
  }
  EXPECT_EQ(refused, 8);
  EXPECT_EQ(timed_out, 4);

  // A body sent a byte at a time (0.2 s apart) is cut off at its deadline too.
  const int fd = connect_from("127.0.0.2", s.port);
  ASSERT_GE(fd, 0);
  const auto start = Clock::now();
  ASSERT_TRUE(
      send_all(fd,
               "POST /v1/jobs HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
               "Content-Length: 1000\r\n\r\n"));
  std::string reply;
  bool closed = false;
  for (int i = 0; i < 40 && !closed; ++i) {
    reply += read_until_closed(fd, 200ms, &closed);
    if (!closed && !send_all(fd, " ")) break;
  }
  if (!closed) reply += read_until_closed(fd, 3s, &closed);
  const double took = std::chrono::duration<double>(Clock::now() - start).count();
  ::close(fd);
  EXPECT_TRUE(closed);
  EXPECT_EQ(status_of(reply), 408) << reply;
  EXPECT_NE(reply.find("the request body did not arrive within 1.5 s"), std::string::npos) << reply;
  EXPECT_GT(took, 1.4);
  EXPECT_LT(took, 3.0);
}

// The limits `serve` takes are checked before it starts: exit 2 with the reason.
TEST(Cli, ServeRefusesLimitsThatCannotHold) {
  const auto dir = fresh_dir("serve-limits");
  CliResult r = run_cli(
      "serve --port 0 --store store --max-connections 8 --max-connections-per-client 8", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("below --max-connections"), std::string::npos) << r.err;
  r = run_cli("serve --port 0 --store store --max-stored-mib 1000", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--max-stored-mib"), std::string::npos) << r.err;
  // More streams than half the connection threads: refused, where it was silently 32.
  r = run_cli("serve --port 0 --store store --max-event-streams 100", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--max-event-streams: must be at most half of --max-connections (32 with "
                       "--max-connections 64)"),
            std::string::npos)
      << r.err;
  // A token of two lines: refused, where every request was then 401.
  {
    std::ofstream(dir / "token") << "abc\ndef\n";
    std::filesystem::permissions(dir / "token", std::filesystem::perms::owner_read |
                                                     std::filesystem::perms::owner_write);
  }
  r = run_cli("serve --port 0 --store store --token-file '" + (dir / "token").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--token-file: the token holds a space, a line break"), std::string::npos)
      << r.err;
}

// A blocking evaluator for the runner: its jobs stop after their second batch (the initial
// population and one iteration are checkpointed) and wait there, running, until released.
struct Gate {
  std::mutex mutex;
  std::condition_variable opened;
  bool open = false;
  void release() {
    {
      std::lock_guard<std::mutex> lock(mutex);
      open = true;
    }
    opened.notify_all();
  }
};
struct GatedEvaluator final : tune::BatchEvaluator {
  GatedEvaluator(std::shared_ptr<Gate> g) : gate(std::move(g)) {}
  std::vector<tune::TaskResult> run(const tune::SimulationBatch& batch) override {
    if (++batches > 2) {
      std::unique_lock<std::mutex> lock(gate->mutex);
      gate->opened.wait(lock, [&] { return gate->open; });
    }
    return inner.run(batch);
  }
  int concurrency() const override { return inner.concurrency(); }
  std::string name() const override { return inner.name(); }
  std::shared_ptr<Gate> gate;
  tune::TbbEvaluator inner{1};
  int batches = 0;
};
// Releases the gate however the test ends (declared after the service: destroyed before it).
struct ReleaseOnExit {
  std::shared_ptr<Gate> gate;
  ~ReleaseOnExit() { gate->release(); }
};

// A running job past its last iteration is "finishing" (the comparison and the noise floor still
// run), not at "ETA 0 s" (issue 41): the gate holds a one-iteration job at its comparison, and a
// longer one inside its iterations.
TEST(Service, AJobPastItsLastIterationIsFinishingNotDone) {
  auto gate = std::make_shared<Gate>();
  tune::ServiceOptions o;
  o.concurrent_jobs = 2;
  o.evaluator = [gate]() -> std::unique_ptr<tune::BatchEvaluator> {
    return std::make_unique<GatedEvaluator>(gate);
  };
  Service s(o);
  ReleaseOnExit release{gate};
  json short_one = long_job("one-iteration");
  short_one["tuning"]["algorithm"]["iterations"] = 1;
  const std::string a = s.submit(short_one)["id"], b = s.submit(long_job("many"))["id"];
  wait_running(s, a, 1);
  wait_running(s, b, 1);
  const json va = s.get("/v1/jobs/" + a), vb = s.get("/v1/jobs/" + b);
  EXPECT_EQ(va["progress"]["phase"], "finishing") << va.dump();
  EXPECT_EQ(va["progress"]["evaluations"], va["progress"]["total_evaluations"]) << va.dump();
  EXPECT_EQ(vb["progress"]["phase"], "tuning") << vb.dump();
  EXPECT_EQ(ftc::cli::eta_text(va), "  comparing controllers and measuring the noise floor");
  gate->release();
  EXPECT_EQ(s.wait_done(a)["status"], "succeeded");
  EXPECT_FALSE(s.get("/v1/jobs/" + a)["progress"].contains("phase"));  // only while running
}

// A running job's partial gains and trials come from what the run stored, made once per
// checkpoint, and nothing is simulated in a request: twenty requests alternating between two
// running jobs, each held at one iteration, build no evaluator (before, each job's first /gains
// compared its best so far in the request, seconds on a heavy job while a server thread waited),
// and every answer is the same bytes. The gains are the best trial's record, to the bit.
TEST(Service, RunningJobsGainsComeFromStoredResultsWithoutSimulating) {
  auto gate = std::make_shared<Gate>();
  std::atomic<int> made{0};
  tune::ServiceOptions o;
  o.concurrent_jobs = 2;
  o.evaluator = [gate, &made]() -> std::unique_ptr<tune::BatchEvaluator> {
    // The first two are the runner's (one per job); a request would make any other.
    if (made++ < 2) return std::make_unique<GatedEvaluator>(gate);
    return std::make_unique<tune::TbbEvaluator>(1);
  };
  Service s(o);
  ReleaseOnExit release{gate};
  const std::string a = s.submit(long_job("held-a"))["id"], b = s.submit(long_job("held-b"))["id"];
  wait_running(s, a, 1);
  wait_running(s, b, 1);
  ASSERT_EQ(made.load(), 2);
  std::map<std::string, std::string> gains, trials;
  for (int i = 0; i < 10; ++i)
    for (const std::string& id : {a, b}) {
      auto g = s.client->Get(("/v1/jobs/" + id + "/gains").c_str());
      ASSERT_TRUE(g);
      ASSERT_EQ(g->status, 200) << g->body;
      EXPECT_EQ(g->get_header_value("Ftctune-Partial"), "true");
      if (i == 0) gains[id] = g->body;
      EXPECT_EQ(g->body, gains[id]);
      auto t = s.client->Get(("/v1/jobs/" + id + "/trials").c_str());
      ASSERT_EQ(t->status, 200) << t->body;
      if (i == 0) trials[id] = t->body;
      EXPECT_EQ(t->body, trials[id]);
    }
  EXPECT_EQ(made.load(), 2);  // no evaluator made for a request
  const json g = json::parse(gains[a]);
  EXPECT_EQ(g["history"].size(), 2u);  // iterations 0 and 1
  EXPECT_EQ(g["optimizer"]["completed"], false);
  EXPECT_TRUE(g["baseline"]["objective"].is_null());  // not simulated
  EXPECT_FALSE(g.contains("noise_floor"));
  ASSERT_TRUE(g["warnings"].is_array());
  EXPECT_EQ(g["warnings"].back(), tune::kStoredBestWarning);
  // The objective is that of the trial whose parameters are the gains', as trials.csv has it.
  std::istringstream rows(trials[a]);
  std::string header, line;
  std::getline(rows, header);
  ASSERT_EQ(header.rfind("iteration,index,Kp,Ki,objective,", 0), 0u) << header;
  bool found = false;
  while (std::getline(rows, line)) {
    std::vector<std::string> f;
    std::istringstream cells(line);
    for (std::string c; std::getline(cells, c, ',');) f.push_back(c);
    ASSERT_GE(f.size(), 5u);
    if (std::stod(f[2]) == g["tuned"]["Kp"].get<double>() &&
        std::stod(f[3]) == g["tuned"]["Ki"].get<double>()) {
      EXPECT_EQ(std::stod(f[4]), g["objective"]["value"].get<double>()) << line;
      found = true;
    }
  }
  EXPECT_TRUE(found) << "no trial with the gains' parameters";
  EXPECT_EQ(g["controller"]["Kp"], g["tuned"]["Kp"]);
  // The loader refuses it: the run has not finished.
  try {
    (void)runtime::parse_gains(g, "running");
    ADD_FAILURE() << "the loader accepted a running job's gains";
  } catch (const InputError& e) {
    ASSERT_EQ(e.errors().size(), 1u) << e.what();  // the file is whole otherwise
    EXPECT_EQ(e.errors()[0].path, "/optimizer/completed");
  }
  gate->release();
  EXPECT_EQ(s.wait_done(a)["status"], "succeeded");
  EXPECT_EQ(s.wait_done(b)["status"], "succeeded");
}

// A cancel stops a running job before its next pack of simulations, not at the end of its
// iteration: a first iteration of 512 candidates on a 60 s scenario with 200 faults (`ftctune
// run` of this job took 15.1 s on two cores for its 1 037 simulations, its first iteration
// about half of that; here the job was cancelled 0.26 s after the cancel) ends cancelled within a
// few seconds, without an iteration and so without results. Before, the job ran the iteration out (the
// issue's job stayed running for 256 s after its cancel).
TEST(Service, ACancelStopsARunningJobBetweenPacks) {
  json job = short_table1_job();
  job["name"] = "heavy";
  job["scenarios"][0]["duration"] = 60;
  job["objective"]["window"] = {0, 60};
  json faults = json::array();
  for (int i = 0; i < 200; ++i)
    faults.push_back({{"actuator", 1 + i % 3},
                      {"type", "bias"},
                      {"onset", 0.1 * i},
                      {"offset", 0.001},
                      {"amplitude", 0.001},
                      {"frequency", 1}});
  job["scenarios"][0]["faults"] = faults;
  job["tuning"]["algorithm"]["population"] = 512;
  job["tuning"]["algorithm"]["iterations"] = 1;
  Service s;
  const std::string id = s.submit(job)["id"];
  json v = json::object();
  for (int i = 0; i < 2000 * FTC_TEST_SLOWDOWN && v.value("status", "") != "running"; ++i) {
    v = s.get("/v1/jobs/" + id);
    std::this_thread::sleep_for(5ms);
  }
  ASSERT_EQ(v["status"], "running") << v.dump();
  std::this_thread::sleep_for(500ms);  // its packs are under way
  const auto asked = std::chrono::steady_clock::now();
  ASSERT_EQ(s.client->Post(("/v1/jobs/" + id + "/cancel").c_str(), "", "application/json")->status,
            202);
  const json done = s.wait_done(id);
  const double took =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - asked).count();
  EXPECT_EQ(done["status"], "cancelled");
  EXPECT_TRUE(done["progress"]["iteration"].is_null()) << done.dump();  // no iteration ended
  EXPECT_LT(took, 5.0 * FTC_TEST_SLOWDOWN) << done.dump();
  expect_error(s.client->Get(("/v1/jobs/" + id + "/gains").c_str()), 409, "not_ready");
}

// Without a token, a request must name this machine's loopback in its Host header (a page of
// another site that reached the service through DNS rebinding names its own), and a request that
// changes something must not come from a page of another origin. With a token neither applies.
TEST(Service, WithoutATokenForeignHostsAndCrossOriginChangesAreRefused) {
  Service s;
  const std::string port = std::to_string(s.port);
  const auto request = [&](const std::string& method, const std::string& path,
                           const std::string& headers, const std::string& body = "") {
    return raw_request("127.0.0.1", s.port,
                       method + " " + path + " HTTP/1.1\r\n" + headers +
                           "Connection: close\r\nContent-Type: application/json\r\n"
                           "Content-Length: " +
                           std::to_string(body.size()) + "\r\n\r\n" + body);
  };
  for (const std::string& host :
       std::vector<std::string>{"evil.example:" + port, "evil.example", "localhost.evil.example",
                                "10.0.0.1:" + port, "[::2]:" + port}) {
    for (const char* path : {"/v1/jobs", "/", "/healthz"}) {
      const std::string reply = request("GET", path, "Host: " + host + "\r\n");
      EXPECT_EQ(status_of(reply), 403) << host << " " << path << "\n" << reply;
      EXPECT_NE(reply.find("forbidden_host"), std::string::npos) << reply;
    }
  }
  for (const std::string& host :
       std::vector<std::string>{"127.0.0.1:" + port, "localhost:" + port, "[::1]:" + port,
                                "LocalHost", "app.localhost:" + port, "127.1.2.3"})
    EXPECT_EQ(status_of(request("GET", "/v1/jobs", "Host: " + host + "\r\n")), 200) << host;
  EXPECT_EQ(status_of(request("GET", "/v1/jobs", "")), 200);  // no Host: not a browser's
  // Ambiguous Host headers are refused (RFC 9112): two of them (the check read the first),
  // and white space before a field name's colon (the check saw no Host at all).
  for (const std::string& headers :
       std::vector<std::string>{"Host: 127.0.0.1:" + port + "\r\nHost: evil.example\r\n",
                                "Host : evil.example\r\n", "Host\t: evil.example\r\n"}) {
    const std::string reply = request("GET", "/v1/jobs", headers);
    EXPECT_EQ(status_of(reply), 400) << headers << reply;
    EXPECT_NE(reply.find("bad_request"), std::string::npos) << reply;
  }

  // State-changing requests from another origin: refused, and nothing changes.
  const std::string job = tiny_job().dump();
  const std::string here = "Host: 127.0.0.1:" + port + "\r\n";
  for (const std::string& foreign : std::vector<std::string>{
           "Origin: http://evil.example\r\n", "Origin: null\r\n", "Origin: http://127.0.0.1:1\r\n",
           "Sec-Fetch-Site: cross-site\r\n",
        // the browser's word that the page is another site's outweighs a matching Origin
        "Origin: http://127.0.0.1:" + port + "\r\nSec-Fetch-Site: cross-site\r\n"}) {
    const std::string reply = request("POST", "/v1/jobs", here + foreign, job);
    EXPECT_EQ(status_of(reply), 403) << foreign << reply;
    EXPECT_NE(reply.find("cross_origin"), std::string::npos) << reply;
  }
  EXPECT_EQ(s.get("/v1/jobs")["total"], 0);
  // A read from another origin is served (the browser does not let that page see it: no CORS).
  EXPECT_EQ(status_of(request("GET", "/v1/jobs", here + "Origin: http://evil.example\r\n")), 200);
  // The dashboard's own origin, and a script's request without one, may submit.
  EXPECT_EQ(
      status_of(request(
          "POST", "/v1/jobs",
          here + "Origin: http://127.0.0.1:" + port + "\r\nSec-Fetch-Site: same-origin\r\n", job)),
      201);
  const std::string reply = request("POST", "/v1/jobs", here, job);
  ASSERT_EQ(status_of(reply), 201) << reply;
  const std::string id = json::parse(reply.substr(reply.find("\r\n\r\n") + 4))["id"];
  s.wait_done(id);
  EXPECT_EQ(
      status_of(request("DELETE", "/v1/jobs/" + id, here + "Origin: http://evil.example\r\n")),
      403);
  EXPECT_EQ(s.get("/v1/jobs")["total"], 2);

  // With a token, the token is the check (a page of another site cannot send it).
  tune::ServiceOptions o;
  o.token = "secret-token";
  Service t(o);
  EXPECT_EQ(
      status_of(raw_request("127.0.0.1", t.port,
                            "GET /v1/jobs HTTP/1.1\r\nHost: tuning.example.org\r\n"
                            "Authorization: Bearer secret-token\r\nConnection: close\r\n\r\n")),
      200);
}

// One client address other than loopback holds at most --max-event-streams-per-client streams
// (the hub's decision, with addresses a test cannot connect from); loopback clients, every local
// page sharing one address, count only against --max-event-streams and half their address's
// connections (below).
TEST(Service, EventStreamsAreCappedPerClientAddress) {
  tune::service_detail::EventHub hub(4, 2);
  using Refused = tune::service_detail::EventHub::Refused;
  Refused why = Refused::closed;
  std::list<tune::service_detail::EventHub::Stream> open;
  for (int i = 0; i < 2; ++i) open.push_back(*hub.open("10.0.0.1", &why));
  EXPECT_FALSE(hub.open("10.0.0.1", &why));
  EXPECT_EQ(why, Refused::client_full);
  // Another address is not held back by this one's streams, nor is loopback ("").
  open.push_back(*hub.open("10.0.0.2"));
  open.push_back(*hub.open(""));
  EXPECT_EQ(hub.open_streams(), 4u);
  EXPECT_FALSE(hub.open("", &why));
  EXPECT_EQ(why, Refused::full);
  // A closed stream frees its place, its client's too.
  open.erase(open.begin());
  EXPECT_EQ(hub.open_streams(), 3u);
  EXPECT_TRUE(hub.open("10.0.0.1"));

  // The service: three pages of this machine with a per-client cap of 2 all get their stream.
  tune::ServiceOptions o;
  o.max_event_streams_per_client = 2;
  Service s(o);
  const auto opened = [](EventClient& c) {
    return c.received().find(": ftctune events") != std::string::npos;
  };
  auto first = std::make_unique<EventClient>(s.port, "/v1/events");
  EventClient second(s.port, "/v1/events"), third(s.port, "/v1/events");
  ASSERT_TRUE(first->wait_for(opened, 10s));
  ASSERT_TRUE(second.wait_for(opened, 10s));
  ASSERT_TRUE(third.wait_for(opened, 10s));
  EXPECT_EQ(third.status, 200);
  // A closed page frees its place.
  first.reset();
  EXPECT_EQ(wait_health(s, [](const json& h) { return h["event_streams"] == 2; })["event_streams"],
            2);
  // A limit given to open() is this client's instead of the hub's.
  std::optional<tune::service_detail::EventHub::Stream> one = hub.open("10.0.0.3", &why, 1);
  EXPECT_TRUE(one);
  EXPECT_FALSE(hub.open("10.0.0.3", &why, 1));
  EXPECT_EQ(why, Refused::client_full);
}

// Streams hold connections: one address holds at most half of its --max-connections-per-client
// in streams, loopback too, so /healthz from that address is still answered. Before, 16 local
// pages took all 16 connections the address may hold, and /healthz got 429.
TEST(Service, EventStreamsLeaveTheirAddressConnectionsForOtherRequests) {
  tune::ServiceOptions o;
  o.max_connections = 64;
  o.max_connections_per_client = 8;  // at most 4 streams from loopback
  Service s(o);
  std::vector<std::unique_ptr<EventClient>> pages;
  for (int i = 0; i < 6; ++i) pages.push_back(std::make_unique<EventClient>(s.port, "/v1/events"));
  int opened = 0, refused = 0;
  for (auto& p : pages) {
    ASSERT_TRUE(p->wait_for(
        [](EventClient& c) {
          return c.ended.load() || c.received().find(": ftctune events") != std::string::npos;
        },
        10s));
    if (p->ended.load()) {
      EXPECT_EQ(p->status, 429);
      ++refused;
    } else {
      ++opened;
    }
  }
  EXPECT_EQ(opened, 4);
  EXPECT_EQ(refused, 2);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(s.get("/healthz")["status"], "ok");
}

// A stream for a job that does not exist is refused (404) without taking a slot (it was 200 and
// held one); a job's own stream ends once the job is deleted, its last event `deleted` (it stayed
// open, holding a connection thread for nothing).
TEST(Service, AJobsEventStreamEndsWithItsDeletionAndAnUnknownJobHasNone) {
  Service s;
  for (const char* path : {"/v1/events?job=0123456789abcdef", "/v1/events?job=",
                           "/v1/jobs/0123456789abcdef/events"})
    expect_error(s.client->Get(path), 404, "not_found");
  EXPECT_EQ(s.get("/healthz")["event_streams"], 0);
  const std::string id = s.submit(tiny_job())["id"];
  s.wait_done(id);
  {
    EventClient mine(s.port, "/v1/events?job=" + id), all(s.port, "/v1/events");
    for (EventClient* c : {&mine, &all})
      ASSERT_TRUE(c->wait_for(
          [](EventClient& e) { return e.received().find(": ftctune events") != std::string::npos; },
          10s));
    ASSERT_EQ(s.client->Delete(("/v1/jobs/" + id).c_str())->status, 200);
    ASSERT_TRUE(mine.wait_for([](EventClient& e) { return e.ended.load(); }, 10s))
        << mine.received();
    EXPECT_EQ(mine.status, 200);
    ASSERT_EQ(mine.events("deleted").size(), 1u) << mine.received();
    EXPECT_EQ(mine.events("deleted")[0]["id"], id);
    // A stream of every job goes on.
    ASSERT_TRUE(all.wait_for([](EventClient& e) { return !e.events("deleted").empty(); }, 10s));
    EXPECT_FALSE(all.ended.load());
  }
  expect_error(s.client->Get(("/v1/events?job=" + id).c_str()), 404, "not_found");
}

// Without a token, a page of another origin gets no event stream (each holds one of the few
// stream slots): 403 cross_origin, before any slot is taken.
TEST(Service, EventStreamsOfAForeignOriginAreRefused) {
  Service s;
  const std::string here = "Host: 127.0.0.1:" + std::to_string(s.port) + "\r\n";
  for (const std::string foreign :
       {"Origin: http://evil.example\r\n", "Origin: null\r\n", "Sec-Fetch-Site: cross-site\r\n"})
    for (const char* path : {"/v1/events", "/v1/events?job=0123456789abcdef"}) {
      const std::string reply = raw_request("127.0.0.1", s.port,
                                            std::string("GET ") + path + " HTTP/1.1\r\n" + here +
                                                foreign + "Connection: close\r\n\r\n");
      EXPECT_EQ(status_of(reply), 403) << foreign << path << "\n" << reply;
      EXPECT_NE(reply.find("cross_origin"), std::string::npos) << reply;
    }
  EXPECT_EQ(s.get("/healthz")["event_streams"], 0);
}

// `ftctune fetch --all`: a listing of the server's files whose entry has no string name, or a
// name a run does not write (a NUL in it stopped the fetch half-way, some files written; one
// leading out of the folder was skipped without a word), is bad input at its JSON path (exit 2),
// not a crash, and nothing is written.
TEST(Cli, FetchAllRefusesAListingWithoutAStringName) {
  const std::string id = "0123456789abcdef";
  httplib::Server fake;
  fake.Get("/v1/jobs/" + id, [&](const httplib::Request&, httplib::Response& res) {
    res.set_content(json{{"id", id}, {"name", "x"}, {"status", "succeeded"}}.dump(),
                    "application/json");
  });
  std::string listing;
  fake.Get("/v1/jobs/" + id + "/files", [&](const httplib::Request&, httplib::Response& res) {
    res.set_content(listing, "application/json");
  });
  fake.Get("/v1/jobs/" + id + "/files/history.csv",
           [&](const httplib::Request&, httplib::Response& res) {
             res.set_content("iteration\n", "text/csv");
           });
  const int port = fake.bind_to_any_port("127.0.0.1");
  ASSERT_GT(port, 0);
  std::thread serving([&] { fake.listen_after_bind(); });
  const auto dir = fresh_dir("fetch-bad-listing");
  const std::vector<std::string> bad_names = {
      "5", "\"a\\u0000b.csv\"", "\"../escape.csv\"", "\"/etc/x\"", "\".hidden\"",
      "\"trajectories//x.csv\"", "\"a\\\\b\"", "\"\"", "\"trajectories/../../x\""};
  for (const std::string& bad : bad_names) {
    listing = "{\"files\": [{\"name\": \"history.csv\"}, {\"name\": " + bad + "}]}";
    const CliResult r =
        run_cli("fetch " + id + " --all -o '" + (dir / "run" / "gains.json").string() +
                    "' --server http://127.0.0.1:" + std::to_string(port),
                dir);
    EXPECT_EQ(r.exit_code, 2) << bad << r.err;
    EXPECT_NE(r.err.find("/files/1/name"), std::string::npos) << bad << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "run")) << bad;
  }
  fake.stop();
  serving.join();
}

// `ftctune fetch` builds its default path from the server's name for the job; a name that is not
// one safe folder name (separators, "..", a leading dot) is not used: the files go under the
// job's id instead, and nothing lands outside out/.
TEST(Cli, FetchKeepsTheServersJobNameOutOfItsPaths) {
  const std::string id = "0123456789abcdef";
  std::string name;
  std::mutex name_mutex;
  httplib::Server fake;
  fake.Get("/v1/jobs/" + id, [&](const httplib::Request&, httplib::Response& res) {
    std::lock_guard<std::mutex> lock(name_mutex);
    res.set_content(json{{"id", id}, {"name", name}, {"status", "succeeded"}}.dump(),
                    "application/json");
  });
  fake.Get("/v1/jobs/" + id + "/gains", [&](const httplib::Request&, httplib::Response& res) {
    res.set_content("{\"optimizer\": {\"completed\": true}}\n", "application/json");
  });
  const int port = fake.bind_to_any_port("127.0.0.1");
  ASSERT_GT(port, 0);
  std::thread serving([&] { fake.listen_after_bind(); });
  const std::string server = " --server http://127.0.0.1:" + std::to_string(port);
  // `ftctune fetch ID` in `dir`, where its default output directory out/ is.
  const auto fetch_in = [&](const std::filesystem::path& dir) {
    const std::string cmd = "cd '" + dir.string() + "' && '" FTC_CLI "' fetch " + id + server +
                            " >'" + (dir / "stdout.txt").string() + "' 2>'" +
                            (dir / "stderr.txt").string() + "'";
    const int status = std::system(cmd.c_str());
    CliResult r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(dir / "stdout.txt");
    r.err = slurp(dir / "stderr.txt");
    std::filesystem::remove(dir / "stdout.txt");
    std::filesystem::remove(dir / "stderr.txt");
    return r;
  };
  const auto files_in = [](const std::filesystem::path& dir) {
    std::set<std::string> out;
    for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
      if (e.is_regular_file()) out.insert(std::filesystem::relative(e.path(), dir).string());
    return out;
  };
  for (const std::string hostile : {"../../escape", "..", ".hidden", "a/b", "/etc/x", "a\\b", ""}) {
    {
      std::lock_guard<std::mutex> lock(name_mutex);
      name = hostile;
    }
    const auto dir = fresh_dir("fetch-name") / "cwd";
    std::filesystem::create_directories(dir);
    const CliResult r = fetch_in(dir);
    EXPECT_EQ(r.exit_code, 0) << hostile << ": " << r.err;
    EXPECT_EQ(files_in(dir.parent_path()),
              std::set<std::string>{"cwd/out/" + id + "/service-01234567/gains.json"})
        << hostile;
    EXPECT_NE(r.err.find("not a safe folder name"), std::string::npos) << r.err;
  }
  {
    std::lock_guard<std::mutex> lock(name_mutex);
    name = "table1.v2";
  }
  const auto dir = fresh_dir("fetch-name-ok");
  const CliResult r = fetch_in(dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(files_in(dir), std::set<std::string>{"out/table1.v2/service-01234567/gains.json"});
  EXPECT_EQ(r.err.find("not a safe folder name"), std::string::npos) << r.err;
  fake.stop();
  serving.join();
}

// A job whose run wrote a front (two or more soft goals): the store keeps front.json and
// front.csv with the run's other files, /files lists and serves them, `fetch --all` brings them,
// and the report drawn from the stored files shows the front. The job runner stores every file of
// output_files(), as here.
TEST(Service, StoredFrontIsListedServedFetchedAndInTheReport) {
  const auto dir = fresh_dir("service-front");
  json job = tiny_job("front");
  job.erase("objective");
  job["goals"] = {{{"metric", "ise"}, {"window", {0, 0.05}}, {"minimize", true}},
                  {{"metric", "control_tv"}, {"minimize", true}}};
  std::string id, front_json, front_csv;
  {
    tune::JobStore store(dir / "store");
    tune::Submission sub;
    sub.job_json = job.dump();
    sub.name = "front";
    sub.iterations = 1;
    sub.total_evaluations = 4;
    id = store.submit(sub).record.id;
    ASSERT_EQ(store.claim_next()->id, id);
    tune::TbbEvaluator evaluator(2);
    const std::map<std::string, std::string> files =
        tune::output_files(tune::tune(tune::parse_job(job, "front"), evaluator));
    front_json = files.at("front.json");
    front_csv = files.at("front.csv");
    store.finish_succeeded(id, files);
  }
  tune::ServiceOptions o;
  o.store = dir / "store";
  Service s(o);
  std::set<std::string> names;
  const json listing = s.get("/v1/jobs/" + id + "/files");
  for (const json& f : listing["files"]) names.insert(f["name"].get<std::string>());
  EXPECT_TRUE(names.count("front.json"));
  EXPECT_TRUE(names.count("front.csv"));
  const auto served = s.client->Get(("/v1/jobs/" + id + "/files/front.json").c_str());
  ASSERT_TRUE(served);
  EXPECT_EQ(served->status, 200);
  EXPECT_EQ(served->body, front_json);
  EXPECT_EQ(served->get_header_value("Content-Type"), "application/json");
  EXPECT_EQ(s.client->Get(("/v1/jobs/" + id + "/files/front.csv").c_str())->body, front_csv);
  const auto report = s.client->Get(("/v1/jobs/" + id + "/report").c_str());
  ASSERT_EQ(report->status, 200) << report->body;
  EXPECT_NE(report->body.find("<h2>Pareto front</h2>"), std::string::npos);
  EXPECT_NE(report->body.find("alt=\"Hypervolume\""), std::string::npos);
  const auto out = fresh_dir("service-front-fetch");
  const CliResult r =
      run_cli("fetch " + id + " --all -o '" + (out / "run" / "gains.json").string() +
                  "' --server http://127.0.0.1:" + std::to_string(s.port),
              out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(slurp(out / "run" / "front.json"), front_json);
}

// GET /v1/metrics tells the dashboard the metrics a run records: the metrics record's fields in
// its order, each with its name, label (without Markdown's escapes), unit, scope, whether
// comparison.md tabulates it, and whether a job may name it as a goal or its objective (behind
// the token as the rest of the API: DashboardIsServedWithAStrictPolicy).
TEST(Service, MetricsListsTheMetricsRecord) {
  Service s;
  const json list = s.get("/v1/metrics")["metrics"];
  ASSERT_EQ(list.size(), sim::kMetricFieldCount);
  const char* scopes[] = {"window", "run", "fault"};
  for (std::size_t i = 0; i < list.size(); ++i) {
    const sim::MetricField& f = sim::kMetricFields[i];
    EXPECT_EQ(list[i]["name"], f.name);
    EXPECT_EQ(list[i]["label"], sim::plain_label(f));
    EXPECT_EQ(list[i]["unit"], f.unit);
    EXPECT_EQ(list[i]["scope"], scopes[static_cast<int>(f.scope)]);
    EXPECT_EQ(list[i]["in_tables"], f.in_tables);
    EXPECT_EQ(list[i]["goal"], f.goal);
    EXPECT_EQ(list[i]["objective"], f.objective);
  }
  EXPECT_EQ(list[3]["label"], "max |u_d|");  // "max \\|u_d\\|" in Markdown
  EXPECT_EQ(list[5]["scope"], "fault");
  const auto post = s.client->Post("/v1/metrics", "{}", "application/json");
  ASSERT_TRUE(post);
  EXPECT_EQ(post->status, 405);
}

// A two-goal job submitted to the service: its front.json and front.csv are those `ftctune run`
// writes, served with the run's other files.
TEST(Service, TwoGoalJobServesTheFrontTheRunWrites) {
  json job = tiny_job("two-goals");
  job.erase("objective");
  job["goals"] = {{{"metric", "ise"}, {"window", {0, 0.05}}, {"minimize", true}},
                  {{"metric", "control_tv"}, {"minimize", true}}};
  job["tuning"]["algorithm"]["population"] = 4;
  job["tuning"]["algorithm"]["iterations"] = 2;
  Service s;
  const std::string id = s.submit(job)["id"];
  const json done = s.wait_done(id);
  ASSERT_EQ(done["status"], "succeeded");
  // Its progress is the front's size, not a J of one corner of it (issue 41).
  const json front = json::parse(expected_file(job, "front.json"));
  EXPECT_TRUE(done["progress"]["best_fitness"].is_null()) << done.dump();
  EXPECT_EQ(done["progress"]["best"]["front"]["points"], front["points"].size()) << done.dump();
  const CliResult status = run_cli("status " + id + " --server http://127.0.0.1:" +
                                       std::to_string(s.port),
                                   s.dir);
  EXPECT_NE(status.out.find("  front of " + std::to_string(front["points"].size()) + " point"),
            std::string::npos)
      << status.out << status.err;
  EXPECT_EQ(status.out.find("best J"), std::string::npos) << status.out;
  for (const char* name : {"front.json", "front.csv", "history.csv"}) {
    const auto r = s.client->Get(("/v1/jobs/" + id + "/files/" + name).c_str());
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200) << name << ": " << r->body;
    EXPECT_EQ(r->body, expected_file(job, name)) << name;
  }
  // What its J measures, by which the jobs list groups it, and its gains file's warnings, which
  // the list's badge counts (issue 41).
  const json gains = s.get("/v1/jobs/" + id + "/gains");
  EXPECT_EQ(done["objective"], "front of ISE[0 s, 0.05 s] and control TV") << done.dump();
  EXPECT_EQ(done["warnings"], gains.value("warnings", json::array()).size()) << done.dump();
  EXPECT_EQ(s.get("/v1/jobs?limit=5")["jobs"][0]["objective"], done["objective"]);
  // Another point of the front, picked over HTTP (the dashboard's click), is the gains file
  // `ftctune pick` writes from the same run's files.
  const auto run = fresh_dir("service-pick");
  tune::TbbEvaluator evaluator(2);
  for (const auto& [name, content] :
       tune::output_files(tune::tune(tune::parse_job(job, "expected"), evaluator)))
    tune::write_file_atomic(run / name, content);
  const std::size_t last = front["points"].size() - 1;
  for (const std::string rule :
       {std::string("index:0"), "index:" + std::to_string(last), std::string("min:control_tv")})
    EXPECT_EQ(s.get("/v1/jobs/" + id + "/gains?pick=" + rule), tune::pick_gains(run, rule)) << rule;
  // A rule with '<=' goes URL-encoded, as a browser sends it.
  double most_tv = 0;
  for (const json& p : front["points"]) most_tv = std::max(most_tv, p["goals"][1].get<double>());
  const std::string limit = tune::detail::format_number(most_tv, "%.17g");
  EXPECT_EQ(s.get("/v1/jobs/" + id + "/gains?pick=limit%3Acontrol_tv%3C%3D" + limit),
            tune::pick_gains(run, "limit:control_tv<=" + limit));
  const auto nothing = s.client->Get(("/v1/jobs/" + id + "/gains?pick=index:99").c_str());
  ASSERT_TRUE(nothing);
  EXPECT_EQ(nothing->status, 400);
  EXPECT_EQ(
      json::parse(nothing->body)["error"]["message"],
      "pick=index:99: index 99 is not a point of the front (0.." + std::to_string(last) + ")");
  // The stored job, canonical: what the dashboard reads its parameters' scales from.
  EXPECT_EQ(s.get("/v1/jobs/" + id + "/job"), tune::to_json(tune::parse_job(job, "two-goals")));
}

// The held-out check of a front (issue 42): GET .../held-out?count=N&seed=S is the front.json
// `ftctune evaluate JOB --front RUN --count N --seed S` writes from the same run (its run named
// by the job, not the server's temporary directory), kept and served again; a bad count, a
// price above the server's budget and a job without a front are refused.
TEST(Service, HeldOutFrontIsWhatEvaluateWritesAndIsKept) {
  json job = ftc::testing::front_ensemble_job();
  job["tuning"]["algorithm"] = {{"type", "bat"}, {"population", 4}, {"iterations", 1}};
  Service s;
  const std::string id = s.submit(job)["id"];
  ASSERT_EQ(s.wait_done(id)["status"], "succeeded");
  const auto run = fresh_dir("service-held-out");
  tune::TbbEvaluator evaluator(2);
  for (const auto& [name, content] :
       tune::output_files(tune::tune(tune::parse_job(job, "expected"), evaluator)))
    tune::write_file_atomic(run / name, content);
  tune::EvaluateJobOptions o;
  o.front = run;
  o.count = 5;
  o.seed = 3;
  o.out = run / "held-out";
  o.figure = false;
  o.threads = 2;
  const tune::EvaluateJobResult r = tune::evaluate_job(tune::parse_job(job, "expected"), o);
  json expected = json::parse(slurp(r.out / "front.json"));
  ASSERT_TRUE(expected["held_out"].contains("run"));
  expected["held_out"]["run"] = "job " + id;
  const json held = s.get("/v1/jobs/" + id + "/held-out?count=5&seed=3");
  EXPECT_EQ(held, expected);
  EXPECT_EQ(held["held_out"]["count"], 5);
  // Kept: the same document again, and among the job's files (the dashboard draws it on open).
  EXPECT_EQ(s.get("/v1/jobs/" + id + "/held-out?count=5&seed=3"), held);
  EXPECT_EQ(s.get("/v1/jobs/" + id + "/files/held-out.json"), held);
  const auto refused = [&](const std::string& query, int status, const std::string& says) {
    const auto res = s.client->Get(("/v1/jobs/" + id + "/held-out" + query).c_str());
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, status) << query << ": " << res->body;
    EXPECT_NE(res->body.find(says), std::string::npos) << query << ": " << res->body;
  };
  refused("?count=0", 400, "count must be an integer in [1, 1000000], got");
  refused("?count=5&seed=x", 400, "seed must be an integer");
  refused("?count=1000000", 400, "times the server's budget");
  const std::string plain = s.submit(tiny_job("one-goal"))["id"];
  ASSERT_EQ(s.wait_done(plain)["status"], "succeeded");
  const auto none = s.client->Get(("/v1/jobs/" + plain + "/held-out").c_str());
  ASSERT_TRUE(none);
  EXPECT_EQ(none->status, 400);
  EXPECT_NE(none->body.find("has no front"), std::string::npos) << none->body;
  // A front tuned on every scenario it has (no ensemble) has no members to hold out.
  json listed = front_job();
  listed["tuning"]["algorithm"]["iterations"] = 1;
  const std::string own = s.submit(listed)["id"];
  ASSERT_EQ(s.wait_done(own)["status"], "succeeded");
  const auto mine = s.client->Get(("/v1/jobs/" + own + "/held-out").c_str());
  ASSERT_TRUE(mine);
  EXPECT_EQ(mine->status, 400);
  EXPECT_NE(mine->body.find("has no ensemble"), std::string::npos) << mine->body;
}

// A store written by a server from before the jobs list's measure and warnings columns opens,
// gains them, and lists its jobs with an unknown measure and no warning until they finish again.
TEST(JobStore, AStoreWithoutTheNewerColumnsGainsThem) {
  const auto dir = fresh_dir("store-columns");
  std::string id;
  {
    tune::JobStore store(dir / "store");
    tune::Submission sub;
    sub.job_json = tiny_job("old").dump();
    sub.name = "old";
    sub.objective = "ISE[0 s, 0.05 s]";
    sub.iterations = 1;
    sub.total_evaluations = 4;
    id = store.submit(sub).record.id;
  }
  {  // as an older server made it: without the two columns
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open((dir / "store" / "ftctune.db").c_str(), &db), SQLITE_OK);
    for (const char* sql :
         {"ALTER TABLE jobs DROP COLUMN objective", "ALTER TABLE jobs DROP COLUMN warnings"})
      EXPECT_EQ(sqlite3_exec(db, sql, nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
    sqlite3_close(db);
  }
  tune::JobStore store(dir / "store");
  const std::vector<tune::JobRecord> jobs = store.list(std::nullopt, 10, 0, "");
  ASSERT_EQ(jobs.size(), 1u);
  EXPECT_EQ(jobs[0].id, id);
  EXPECT_EQ(jobs[0].objective, "");
  EXPECT_EQ(jobs[0].warnings, -1);  // not counted
  ASSERT_EQ(store.claim_next()->id, id);
  store.finish_succeeded(id, {{"gains.json", "{}"}}, "", 3);
  EXPECT_EQ(store.get(id)->warnings, 3);
}

// A run whose loop fails (jobs/stuck-wheel-small-limits.json: it saturates, never settles and
// drifts off) succeeds with warnings: the job's view, the list and `status` count them as its
// gains file lists them (issue 41).
TEST(Service, ARunWithWarningsIsListedAsSucceededWithThem) {
  json job = json::parse(
      slurp(std::filesystem::path(FTC_SOURCE_DIR) / "jobs" / "stuck-wheel-small-limits.json"));
  job["tuning"]["algorithm"]["population"] = 4;
  job["tuning"]["algorithm"]["iterations"] = 1;
  Service s;
  const std::string id = s.submit(job)["id"];
  const json done = s.wait_done(id);
  ASSERT_EQ(done["status"], "succeeded");
  const std::size_t warned = s.get("/v1/jobs/" + id + "/gains")["warnings"].size();
  EXPECT_GE(warned, 2u);  // never settles, ends farther off than it started
  EXPECT_EQ(done["warnings"], warned);
  EXPECT_EQ(s.get("/v1/jobs")["jobs"][0]["warnings"], warned);
  const CliResult status =
      run_cli("status " + id + " --server http://127.0.0.1:" + std::to_string(s.port), s.dir);
  EXPECT_NE(status.out.find("succeeded with " + std::to_string(warned) + " warnings"),
            std::string::npos)
      << status.out;
}

// A job without a front has no other point to pick; its J is the objective's measure.
TEST(Service, PickingAPointOfAJobWithoutAFrontIsRefused) {
  Service s;
  const std::string id = s.submit(tiny_job("one-goal"))["id"];
  const json done = s.wait_done(id);
  ASSERT_EQ(done["status"], "succeeded");
  EXPECT_EQ(done["objective"], tune::fitness_label(tune::parse_job(tiny_job("one-goal"), "j")));
  const auto r = s.client->Get(("/v1/jobs/" + id + "/gains?pick=knee").c_str());
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400);
  EXPECT_NE(r->body.find("has no front (a job with two or more soft goals has one)"),
            std::string::npos)
      << r->body;
  EXPECT_EQ(s.client->Get("/v1/jobs/0123456789abcdef/job")->status, 404);
}

// Requests on a kept-alive connection (the dashboard's) are answered at once: with Nagle's
// algorithm on, a reply's last segment waited for the ACK of the one before, which the client
// delays, so every request after the first took about 40 ms (#44 item 10).
TEST(Service, KeptAliveRequestsAreAnsweredWithoutWaitingForAnAck) {
  Service s;
  httplib::Client keep("127.0.0.1", s.port);
  keep.set_keep_alive(true);
  keep.set_read_timeout(30, 0);
  ASSERT_TRUE(keep.Get("/healthz"));
  std::vector<double> ms;
  for (int i = 0; i < 15; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    auto r = keep.Get("/healthz");
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                     .count());
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200);
  }
  std::sort(ms.begin(), ms.end());
  // The median well under the 40 ms of a delayed ACK (a local request takes well under 1 ms).
  EXPECT_LT(ms[ms.size() / 2], 20.0 * FTC_TEST_SLOWDOWN) << "median " << ms[ms.size() / 2] << " ms";
}
