// One 30 s simulation of the paper's scenario (30 000 samples) per controller, one thread.
// Run: build/tests/ftc_bench
#include <benchmark/benchmark.h>

#include "ftc/sim/controller.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/sim/spacecraft.hpp"

using namespace ftc::sim;

static void BM_PaperScenario(benchmark::State& state) {
  const auto type = static_cast<ControllerType>(state.range(0));
  const Spacecraft plant;
  const Scenario s = Scenario::paper();
  auto c = make_controller(ControllerConfig::table1(type), plant, s.sample_time);
  double ise = 0;
  for (auto _ : state) {
    const SimulationResult r = simulate(plant, *c, s);
    ise += r.metrics.errors.ise;
  }
  benchmark::DoNotOptimize(ise);
  state.SetLabel(to_string(type));
  state.counters["ns_per_sample"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * s.samples(),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_PaperScenario)->DenseRange(0, 3)->Unit(benchmark::kMillisecond);

// The same through the plant registry, as the tuner simulates (AnyPlant::simulate).
static void BM_PaperScenarioTuner(benchmark::State& state) {
  const auto type = static_cast<ControllerType>(state.range(0));
  const auto plant = make_plant(PlantSpec{});
  const Scenario s = Scenario::paper();
  const ControllerConfig c = ControllerConfig::table1(type);
  double ise = 0;
  for (auto _ : state) ise += plant->simulate(c, s).metrics.errors.ise;
  benchmark::DoNotOptimize(ise);
  state.SetLabel(to_string(type));
  state.counters["ns_per_sample"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * s.samples(),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_PaperScenarioTuner)->DenseRange(0, 3)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
