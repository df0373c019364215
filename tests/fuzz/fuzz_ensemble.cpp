// libFuzzer target: a job with an ensemble, expanded into scenarios (at most kMembers of them, so
// that an input stays fast whatever count it asks for). Checked on every accepted job:
//  - member k is the same whether drawn alone or in the sequence (SPEC §12: any order, any
//    thread);
//  - the members, written as `ftctune ensemble` writes them (an ftctune.scenarios/1 file with
//    their recoverability), are a scenarios file the same job can name instead of its ensemble,
//    and read back as the same scenarios.
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ftc/sim/plants.hpp"
#include "ftc/tune/job/ensemble.hpp"
#include "ftc/tune/job/job.hpp"
#include "fuzz.hpp"
#include "json_mutator.hpp"

using namespace ftc;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

constexpr std::int64_t kMembers = 8;

const fs::path& scratch() { return fuzz::scratch_dir("ensemble"); }

}  // namespace

FTC_FUZZ_JSON_INPUT()

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  fuzz::input_errors_only([&] {
    const tune::Job job = tune::parse_job_text(text, "fuzz");
    if (!job.ensemble) return;
    fuzz::remember_accepted(text);
    fuzz::nothing_escapes("expanding an accepted ensemble", [&] {
      const std::int64_t count = std::min(job.ensemble->count, kMembers);
      const std::vector<sim::Scenario> members = tune::expand_ensemble(job, std::nullopt, count);
      if (static_cast<std::int64_t>(members.size()) != count)
        fuzz::finding("expand_ensemble gave " + std::to_string(members.size()) + " members, not " +
                      std::to_string(count));
      json listed = json::array();
      const std::unique_ptr<sim::AnyPlant> plant = sim::make_plant(job.plant);
      for (std::int64_t k = count - 1; k >= 0; --k) {
        const json alone = tune::to_json(tune::ensemble_member(job, job.ensemble->seed, k));
        if (alone != tune::to_json(members[static_cast<std::size_t>(k)]))
          fuzz::finding("member " + std::to_string(k) + " drawn alone differs from the sequence's");
      }
      for (const sim::Scenario& m : members) {
        json j = tune::to_json(m);
        j["recoverable"] = plant->recoverable(m);
        listed.push_back(std::move(j));
      }
      const json file = {{"schema", tune::kScenariosSchema},
                         {"job", job.name},
                         {"seed", job.ensemble->seed},
                         {"scenarios", listed}};
      std::ofstream(scratch() / "members.json") << file.dump(2);
      json named = tune::to_json(job);
      named.erase("ensemble");
      named["scenarios"] = {{"file", "members.json"}};
      tune::Job again;
      try {
        again = tune::parse_job(named, "job naming its members", scratch());
      } catch (const InputError& e) {
        fuzz::finding(std::string("the members of an accepted ensemble are refused as a "
                                  "scenarios file: ") +
                      e.what());
      }
      if (again.scenarios.size() != members.size())
        fuzz::finding("the members file read back holds " + std::to_string(again.scenarios.size()) +
                      " scenarios, not " + std::to_string(members.size()));
      for (std::size_t k = 0; k < members.size(); ++k)
        if (tune::to_json(again.scenarios[k]) != tune::to_json(members[k]))
          fuzz::finding("member " + std::to_string(k) + " reads back from its file changed");
    });
  });
  return 0;
}
