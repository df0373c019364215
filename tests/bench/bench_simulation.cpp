// One 30 s simulation of the paper's scenario (30 000 samples) per controller, one thread.
// Run: build/tests/ftc_bench
#include <benchmark/benchmark.h>

#include "ftc/sim/controller.hpp"
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

BENCHMARK_MAIN();
