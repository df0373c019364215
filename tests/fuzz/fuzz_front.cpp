// libFuzzer target: front.json as `ftctune pick` and `ftctune report` read it (front_from_json),
// for a fixed job of two soft goals and a hard one, the run's or a held-out front (issue 44: the
// file carries authority, since pick turns a point of it into deployable gains). A bad document
// must be an InputError; one it accepts must write back to a document it reads again to the same
// bytes, and every rule of pick must choose a point of it or refuse with an InputError.
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "ftc/runtime/json_reader.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/run/front.hpp"
#include "fuzz.hpp"
#include "short_job.hpp"
#include "json_mutator.hpp"

using namespace ftc;
using namespace ftc::tune;
using nlohmann::json;

namespace {

// The front tests' job (short_job.hpp): the committed seeds are fronts of its runs (a held-out
// one too).
const Job& front_job() {
  static const Job job = parse_job(testing::front_job(), "front-short");
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
