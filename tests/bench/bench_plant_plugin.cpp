// The example plant plugin (examples/plant-plugin) against the same plant compiled into this
// program: a full pack of PI-FOSMC candidates on the example job's scenario, per instruction set,
// through AnyPlant::simulate_pack, one thread. ns_per_sample is per sample and per candidate.
// The two run in one process, interleaved (--benchmark_enable_random_interleaving).
// Run: build/tests/ftc_bench_plugin --benchmark_enable_random_interleaving=true
//        --benchmark_repetitions=10 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "../examples/plant-plugin/pendulum.hpp"
#include "ftc/runtime/controller_json.hpp"
#include "ftc/runtime/json_reader.hpp"
#include "ftc/runtime/scenario_json.hpp"
#include "ftc/sim/isa.hpp"
#include "ftc/sim/plant_plugin.hpp"
#include "plants/plugin_entry.hpp"

using namespace ftc::sim;

namespace {

// 0: compiled in, 1: the plugin.
std::unique_ptr<AnyPlant> plant(int which) {
  if (which == 0) {
    const PlantKind k = plugin::kind_of<pendulum::Pendulum>(pendulum::kind(), pendulum::build);
    return k.make(k.defaults());
  }
  const PlantKind& k =
      *load_plant_plugin(FTC_PLUGIN_DIR "/ftctune_plant_reaction_wheel_pendulum.so").kind;
  return k.make(k.defaults());
}

void BM_Pendulum(benchmark::State& state) {
  const auto isa = static_cast<Isa>(state.range(1));
  bool supported = false;
  for (const Isa i : supported_isas()) supported = supported || i == isa;
  if (!supported) {
    state.SkipWithError("instruction set not supported here");
    return;
  }
  const std::unique_ptr<AnyPlant> p = plant(static_cast<int>(state.range(0)));
  // The example job's scenario and controller, from its file; the lanes' candidates differ in Kp,
  // Ki and the switching gain, as a tuning batch's do.
  const nlohmann::json job = ftc::json_io::parse_json_text(
      *ftc::json_io::read_file(FTC_SOURCE_DIR "/examples/plant-plugin/job.json"), "job.json");
  const Scenario s = ftc::runtime::scenario_from_json(job["scenarios"][0], "job.json");
  std::vector<ftc::FieldError> errors_in_job;
  const ControllerConfig own =
      ftc::runtime::parse_controller(job["controller"], "/controller", errors_in_job);
  const int width = lane_width(isa);
  std::vector<ControllerConfig> c(width, own);
  for (int l = 0; l < width; ++l) {
    c[l].Kp = own.Kp + l;
    c[l].Ki = own.Ki + 0.5 * l;
    c[l].switching_gain = own.switching_gain + 0.25 * l;
  }
  const SimulationOptions o;
  std::vector<PackTask> tasks;
  for (const ControllerConfig& cc : c) tasks.push_back({&cc, &s, &o});
  std::vector<SimulationResult> results(tasks.size());
  std::vector<std::string> errors(tasks.size());
  for (auto _ : state) {
    p->simulate_pack(tasks, results, errors, isa);
    benchmark::DoNotOptimize(results.data());
  }
  state.SetLabel(std::string(state.range(0) == 0 ? "compiled in " : "plugin ") + to_string(isa));
  state.counters["ns_per_sample"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * static_cast<double>(s.samples()) * width,
      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_Pendulum)
    ->ArgsProduct({{0, 1},
                   {static_cast<int>(Isa::scalar), static_cast<int>(Isa::sse2),
                    static_cast<int>(Isa::avx2), static_cast<int>(Isa::avx512)}})
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
