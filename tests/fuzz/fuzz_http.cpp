// libFuzzer target: one HTTP request to the service's API, handled in process by
// Api::handle (the token check, the body read under its limit, the routes) against a store that
// holds a job in each state. The input is the request as text:
//
//   METHOD TARGET
//   Name: value          headers, up to an empty line
//
//   body
//
// where TARGET may name the stored jobs as {queued}, {running}, {succeeded}, {failed} and
// {cancelled} (their ids are random). A request that changed the store (a 2xx to a method with
// a body) puts the store back as it was, so every input meets the same state and a finding
// replays from its file alone.
//
// Findings: an exception out of the handler (the server would answer 500 internal_error), any
// 5xx, a response labelled application/json that is not JSON, an error without its code and
// message.
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <string>
#include <string_view>
#include <system_error>

#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "ftc/tune/service/job_store.hpp"
#include "ftc/tune/service/service.hpp"
#include "fuzz.hpp"
#include "json_mutator.hpp"
#include "service/api.hpp"
#include "service/job_runner.hpp"
#include "short_job.hpp"

using namespace ftc;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

constexpr const char* kToken = "fuzz-token";
// Small, so that bodies above it fit in an input.
constexpr std::size_t kMaxBody = 2048;

class Fixture {
 public:
  Fixture() {
    spdlog::set_level(spdlog::level::off);
    // tmpfs when there is one: the store syncs every submission.
    const fs::path base = fs::is_directory("/dev/shm") && access("/dev/shm", W_OK) == 0
                              ? fs::path("/dev/shm")
                              : fs::temp_directory_path();
    root_ = base / ("ftctune-fuzz-http-" + std::to_string(getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
    make_template(root_ / "template");
    options_.token = kToken;
    options_.max_body_bytes = kMaxBody;
    reset();
  }
  ~Fixture() {
    api_.reset();
    runner_.reset();
    store_.reset();
    std::error_code ec;
    fs::remove_all(root_, ec);
  }

  tune::service_detail::Api& api() { return *api_; }
  const std::map<std::string, std::string>& ids() const { return ids_; }

  // The live store, a copy of the template again.
  void reset() {
    api_.reset();
    runner_.reset();
    store_.reset();
    const fs::path live = root_ / "live";
    fs::remove_all(live);
    fs::copy(root_ / "template", live);
    store_ = std::make_unique<tune::JobStore>(live);
    // Never started: a submission only wakes it.
    runner_ = std::make_unique<tune::service_detail::JobRunner>(
        *store_,
        tune::service_detail::RunnerOptions{1, options_.store_retry_seconds,
                                            options_.max_stored_bytes, options_.trajectory_rows},
        [] { return std::make_unique<tune::TbbEvaluator>(1); });
    api_ = std::make_unique<tune::service_detail::Api>(options_, *store_, *runner_);
  }

 private:
  void make_template(const fs::path& dir) {
    const tune::Job job = tune::parse_job(ftc::testing::tiny_job(), "tiny");
    tune::TbbEvaluator evaluator(1);
    const std::map<std::string, std::string> files = tune::output_files(tune::tune(job, evaluator));
    tune::JobStore store(dir);
    tune::Submission s;
    s.job_json = tune::to_json(job).dump();
    s.name = job.name;
    s.iterations = job.tuning->algorithm->iterations();
    s.total_evaluations = job.tuning->algorithm->evaluations();
    const auto submit = [&](const char* name) {
      ids_["{" + std::string(name) + "}"] = store.submit(s).record.id;
      return ids_["{" + std::string(name) + "}"];
    };
    // claim_next takes the oldest queued job: each is claimed as soon as it is submitted.
    submit("succeeded");
    store.claim_next();
    store.finish_succeeded(ids_["{succeeded}"], files);
    // Drawn already, so that GET .../report does not run gnuplot.
    store.put_artifact(ids_["{succeeded}"], "report.html", "<!doctype html><title>tiny</title>");
    submit("failed");
    store.claim_next();
    store.finish_failed(ids_["{failed}"], "it failed");
    store.request_cancel(submit("cancelled"));
    submit("running");
    store.claim_next();
    submit("queued");
  }

  fs::path root_;
  tune::ServiceOptions options_;
  std::map<std::string, std::string> ids_;
  std::unique_ptr<tune::JobStore> store_;
  std::unique_ptr<tune::service_detail::JobRunner> runner_;
  std::unique_ptr<tune::service_detail::Api> api_;
};

Fixture& fixture() {
  static Fixture f;
  return f;
}

std::string_view next_line(std::string_view& in) {
  const std::size_t n = in.find('\n');
  std::string_view line = in.substr(0, n);
  in.remove_prefix(n == std::string_view::npos ? in.size() : n + 1);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  return line;
}

std::string with_ids(std::string target) {
  for (const auto& [placeholder, id] : fixture().ids())
    for (std::size_t at; (at = target.find(placeholder)) != std::string::npos;)
      target.replace(at, placeholder.size(), id);
  return target;
}

// The request as cpp-httplib hands it to a handler; nullopt for what the library answers itself
// (a malformed request line or header, a method it has no route for).
std::optional<httplib::Request> parse_request(std::string_view in, std::string& body,
                                              bool& has_body) {
  const std::string_view line = next_line(in);
  const std::size_t space = line.find(' ');
  if (space == std::string_view::npos) return std::nullopt;
  httplib::Request req;
  req.method = std::string(line.substr(0, space));
  static const std::string_view kWithBody[] = {"POST", "PUT", "PATCH", "DELETE"};
  static const std::string_view kWithout[] = {"GET", "HEAD", "OPTIONS"};
  has_body =
      std::find(std::begin(kWithBody), std::end(kWithBody), req.method) != std::end(kWithBody);
  if (!has_body &&
      std::find(std::begin(kWithout), std::end(kWithout), req.method) == std::end(kWithout))
    return std::nullopt;
  req.target = with_ids(std::string(line.substr(space + 1)));
  const std::size_t query = req.target.find('?');
  req.path = httplib::detail::decode_url(req.target.substr(0, query), false);
  if (query != std::string::npos)
    httplib::detail::parse_query_text(req.target.substr(query + 1), req.params);
  for (std::string_view h; !(h = next_line(in)).empty();) {
    const std::size_t colon = h.find(':');
    if (colon == std::string_view::npos || colon == 0) return std::nullopt;
    std::string_view value = h.substr(colon + 1);
    while (!value.empty() && (value.front() == ' ' || value.front() == '\t'))
      value.remove_prefix(1);
    req.headers.emplace(std::string(h.substr(0, colon)), std::string(value));
  }
  req.remote_addr = "127.0.0.1";
  body.assign(in);
  return req;
}

// Hands out the body the way the library does: with a Content-Length, that many bytes (and a
// failed read when the connection ends before them, or when the length is above the limit,
// which the library does not read); chunked, all of it; neither, nothing.
httplib::ContentReader body_reader(const httplib::Request& req, const std::string& body) {
  const auto reader = [&req, &body](const httplib::ContentReceiver& receive) {
    std::size_t n = 0;
    bool complete = true;
    if (req.get_header_value("Transfer-Encoding") == "chunked") {
      n = body.size();
    } else if (req.has_header("Content-Length")) {
      const std::string length = req.get_header_value("Content-Length");
      std::uint64_t declared = 0;
      const auto [end, ec] =
          std::from_chars(length.data(), length.data() + length.size(), declared);
      if (ec != std::errc() || declared > kMaxBody) return false;
      n = std::min<std::size_t>(declared, body.size());
      complete = declared <= body.size();
    }
    // In pieces, as they come off a socket.
    for (std::size_t at = 0; at < n; at += 1000)
      if (!receive(body.data() + at, std::min<std::size_t>(1000, n - at))) return false;
    return complete;
  };
  return httplib::ContentReader(reader, [](const httplib::MultipartContentHeader&,
                                           const httplib::ContentReceiver&) { return false; });
}

void check_response(const httplib::Request& req, const httplib::Response& res) {
  const std::string request = req.method + " " + req.target;
  if (res.status >= 500)
    fuzz::finding(request + " answered " + std::to_string(res.status) + ": " + res.body);
  if (res.get_header_value("Content-Type").rfind("application/json", 0) != 0) return;
  const json body = json::parse(res.body, nullptr, false);
  if (body.is_discarded()) fuzz::finding(request + " answered JSON that does not parse");
  if (res.status >= 400 &&
      !(body.contains("error") && body["error"].contains("code") &&
        body["error"]["code"].is_string() && body["error"]["message"].is_string()))
    fuzz::finding(request + " answered " + std::to_string(res.status) +
                  " without an error code and message: " + res.body);
}

}  // namespace

// The body mutated as a JSON document (fuzz::mutate_json), half the time that of a request
// answered 2xx; a Content-Length that matched the body is kept matching, or the handler would
// mostly see truncated bodies.
extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size,
                                               std::size_t max_size, unsigned int seed) {
  std::minstd_rand rng(seed);
  size = fuzz::from_accepted(data, size, max_size, rng);
  seed = static_cast<unsigned int>(rng());
  const std::string before(reinterpret_cast<const char*>(data), size);
  const std::size_t blank = before.find("\n\n");
  if (blank == std::string::npos) return LLVMFuzzerMutate(data, size, max_size);
  const std::size_t offset = blank + 2;
  const std::size_t n = fuzz::mutate_json(data, size, max_size, seed, offset);
  std::string after(reinterpret_cast<const char*>(data), n);
  const std::string length = "Content-Length: ";
  const std::size_t at = after.find(length);
  if (after.compare(0, offset, before, 0, offset) != 0 || at == std::string::npos || at > blank)
    return n;
  const std::size_t end = after.find('\n', at);
  if (after.substr(at + length.size(), end - at - length.size()) != std::to_string(size - offset))
    return n;
  after.replace(at + length.size(), end - at - length.size(), std::to_string(n - offset));
  if (after.size() > max_size) return n;
  std::memcpy(data, after.data(), after.size());
  return after.size();
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fixture();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string body;
  bool has_body = false;
  const std::optional<httplib::Request> req =
      parse_request(std::string_view(reinterpret_cast<const char*>(data), size), body, has_body);
  if (!req) return 0;
  httplib::Response res;
  fuzz::nothing_escapes(req->method.c_str(), [&] {
    if (has_body) {
      const httplib::ContentReader reader = body_reader(*req, body);
      fixture().api().handle(*req, res, &reader);
    } else {
      fixture().api().handle(*req, res, nullptr);
    }
  });
  check_response(*req, res);
  if (res.status >= 200 && res.status < 300)
    fuzz::remember_accepted(std::string_view(reinterpret_cast<const char*>(data), size));
  if (has_body && res.status >= 200 && res.status < 300) fixture().reset();
  return 0;
}
