// libFuzzer target: the text of a job file, read as `ftctune validate` and a service submission
// read it (parse_job_text validates), then what they do with an accepted job: its cost, and its
// canonical JSON, which the service stores and its worker reads again. Reading that back must
// give the same job: a job the API accepted and its worker refused would fail only after queueing.
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "ftc/tune/job/job.hpp"
#include "fuzz.hpp"
#include "json_mutator.hpp"

using namespace ftc;

FTC_FUZZ_JSON_INPUT()

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  fuzz::input_errors_only([&] {
    // No base directory, as for the service: a job naming a scenarios file is refused.
    const tune::Job job = tune::parse_job_text(text, "fuzz");
    fuzz::remember_accepted(text);
    fuzz::nothing_escapes("an accepted job", [&] {
      (void)job.steps_per_evaluation();
      (void)job.scenario_count();
      if (job.tuning) (void)job.tuning->algorithm->evaluations();
      const std::string stored = tune::to_json(job).dump();
      const std::string again = tune::to_json(tune::parse_job_text(stored, "stored")).dump();
      if (again != stored)
        fuzz::finding("the stored form of an accepted job reads back as another job:\n" + stored +
                      "\n" + again);
    });
  });
  return 0;
}
