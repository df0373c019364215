// libFuzzer target: the text of a scenarios file (ftctune.scenarios/1, what `ftctune ensemble`
// writes) named by a job ("scenarios": {"file": ...}). Bad input is an InputError; a file the job
// accepts gives scenarios that validate against the plant, whose recoverability can be judged,
// and a job that writes out and reads back the same.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "ftc/sim/plants.hpp"
#include "ftc/tune/job/job.hpp"
#include "fuzz.hpp"
#include "json_mutator.hpp"

using namespace ftc;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

// The job that names the file: a spacecraft with no scenarios of its own.
const json& naming_job() {
  static const json j = json::parse(R"({
    "schema": "ftctune.job/1", "name": "fuzz-scenarios",
    "plant": {"model": "spacecraft", "inertia": [20, 17, 15], "orbital_rate": 0.0011},
    "scenarios": {"file": "members.json"},
    "controller": {"type": "pi_fosmc", "c1": 10, "c2": 9, "alpha2": 0.5625,
                   "switching_gain": 20, "theta": 1000, "Kp": 20, "Ki": 5},
    "objective": {"metric": "ise"}})");
  return j;
}

const fs::path& scratch() { return fuzz::scratch_dir("scenarios"); }

}  // namespace

FTC_FUZZ_JSON_INPUT()

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  {
    std::ofstream out(scratch() / "members.json", std::ios::binary | std::ios::trunc);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
  }
  fuzz::input_errors_only([&] {
    const tune::Job job = tune::parse_job(naming_job(), "fuzz", scratch());
    fuzz::remember_accepted(text);
    fuzz::nothing_escapes("scenarios of an accepted file", [&] {
      const std::unique_ptr<sim::AnyPlant> plant = sim::make_plant(job.plant);
      for (const sim::Scenario& s : job.scenarios) {
        if (!s.validate("", plant->axes(), plant->actuators()).empty())
          fuzz::finding("an accepted scenario " + s.name + " does not validate");
        (void)plant->recoverable(s);
      }
      // Written out (inline) and read again: the same job.
      const json written = tune::to_json(job);
      tune::Job again;
      try {
        again = tune::parse_job(written, "written back");
      } catch (const InputError& e) {
        fuzz::finding(std::string("an accepted job does not read back: ") + e.what());
      }
      if (tune::to_json(again) != written) fuzz::finding("an accepted job reads back changed");
    });
  });
  return 0;
}
