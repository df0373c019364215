// libFuzzer target: the text of a gains file, read as flight software reads it
// (runtime::parse_gains), then what it does with gains the loader accepted: build the plant they
// were tuned on and the controller, and run a few samples of closed loop. The loader's checks
// must be the ones the controller and the plant need: a file it accepts is never refused later.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "ftc/runtime/gains.hpp"
#include "ftc/runtime/json_reader.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/scenario.hpp"
#include "ftc/sim/spacecraft.hpp"
#include "fuzz.hpp"
#include "json_mutator.hpp"

using namespace ftc;

namespace {

// Ten samples from the plant's default initial state, without faults: enough to step every
// part of the controller.
sim::Scenario short_run(const runtime::Gains& g, const sim::PlantKind& kind) {
  sim::Scenario s;
  s.name = "fuzz";
  s.sample_time = g.sample_time;
  s.duration = 10 * g.sample_time;
  s.initial_state = kind.default_initial_state;
  return s;
}

}  // namespace

FTC_FUZZ_JSON_INPUT()

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  fuzz::input_errors_only([&] {
    const runtime::Gains g = runtime::parse_gains(json_io::parse_json_text(text, "fuzz"), "fuzz");
    fuzz::remember_accepted(text);
    fuzz::nothing_escapes("accepted gains", [&] {
      runtime::check_plant(g, g.plant);
      runtime::check_sample_time(g, g.sample_time);
      const std::unique_ptr<sim::AnyPlant> plant = sim::make_plant(g.plant);
      if (g.plant.model == "spacecraft") {  // the flight path of examples/runtime
        const sim::Spacecraft spacecraft(sim::spacecraft_params(g.plant));
        auto c = runtime::make_controller(g, spacecraft, g.sample_time);
        c->reset();
        (void)c->step(0.0, sim::Vec3(0.1, -0.1, 0.2), sim::Vec3(0.01, 0, -0.01), sim::Vec3::Zero());
      }
      const sim::Scenario s = short_run(g, plant->kind());
      // A sample time the loader accepts may still make no valid 10-sample run (the scenario's
      // own limits); that says nothing about the gains.
      if (!s.validate("", plant->axes(), plant->actuators()).empty()) return;
      (void)plant->simulate(g.controller, s);
    });
  });
  return 0;
}
