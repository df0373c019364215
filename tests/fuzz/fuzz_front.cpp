// libFuzzer target: front.json as `ftctune pick` and `ftctune report` read it (front_from_json),
// for a fixed job of two soft goals and a hard one, the run's or a held-out front (issue 44: the
// file carries authority, since pick turns a point of it into deployable gains). A bad document
// must be an InputError; one it accepts must write back to a document it reads again to the same
// bytes, and every rule of pick must choose a point of it or refuse with an InputError.
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "ftc/runtime/json_reader.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/run/front.hpp"
#include "fuzz.hpp"
#include "json_mutator.hpp"

using namespace ftc;
using namespace ftc::tune;
using nlohmann::json;

namespace {

// The job of tests/test_front.cpp's front_job(): Table 1, 5 s, goals ISE over [0, 5], control
// TV, peak command at most 1e6; Kp and the switching gain (log) tuned. The committed seeds are
// fronts of its runs (a held-out one too).
const Job& front_job() {
  static const Job job = [] {
    std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/table1.json");
    json j = json::parse(in);
    j["name"] = "front-short";
    j["scenarios"][0]["duration"] = 5;
    j["scenarios"][0]["faults"][0]["onset"] = 2;
    j["scenarios"][0]["faults"][1]["onset"] = 3.5;
    j.erase("objective");
    j["goals"] = {{{"metric", "ise"}, {"window", {0, 5}}, {"minimize", true}},
                  {{"metric", "control_tv"}, {"minimize", true}},
                  {{"metric", "peak_command"}, {"at_most", 1e6}}};
    j["tuning"]["parameters"] = {{"Kp", {1, 50}},
                                 {"switching_gain", {{"bounds", {2, 200}}, {"scale", "log"}}}};
    j["tuning"]["algorithm"] = {{"type", "bat"}, {"population", 4}, {"iterations", 3}};
    return parse_job(j, "front-short");
  }();
  return job;
}

}  // namespace

FTC_FUZZ_JSON_INPUT()

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const Job& job = front_job();
  fuzz::input_errors_only([&] {
    const json doc = json_io::parse_json_text(text, "fuzz");
    const Front front = front_from_json(job, doc, "fuzz");
    fuzz::remember_accepted(text);
    fuzz::nothing_escapes("an accepted front written back", [&] {
      const json again = front_document(job, "sha", 1, front);
      const json twice = front_document(job, "sha", 1, front_from_json(job, again, "again"));
      if (again != twice) fuzz::finding("a front read back from its own document differs");
    });
    for (const char* rule : {"knee", "min:ise", "min:control_tv", "limit:control_tv<=100",
                             "index:0", "index:1"}) {
      fuzz::input_errors_only([&] {
        const std::size_t i = pick_point(job, front, rule);
        if (i >= front.points.size())
          fuzz::finding(std::string("rule ") + rule + " chose point " + std::to_string(i) +
                        " of " + std::to_string(front.points.size()));
      });
    }
  });
  return 0;
}
