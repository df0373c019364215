// One 30 s simulation of the paper's scenario (30 000 samples) per controller, one thread; and
// the batch simulator's packs, per controller and instruction set, on one thread and on all.
// Run: build/tests/ftc_bench (--benchmark_filter=Lanes for the packs only)
#include <benchmark/benchmark.h>

#include <vector>

#include "checks.hpp"
#include "ftc/sim/controller.hpp"
#include "ftc/sim/isa.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/sim/spacecraft.hpp"
#include "plants/spacecraft_pack.hpp"

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

// A full pack of W candidates (Kp and K differ from lane to lane, as in a tuning batch) on the
// paper's scenario, through the kernel of one instruction set. ns_per_sample is per sample and
// per candidate: the figure the SIMD targets are stated in. With ->Threads(2) each thread runs
// its own packs (both cores busy).
static void BM_Lanes(benchmark::State& state) {
  const auto type = static_cast<ControllerType>(state.range(0));
  const auto isa = static_cast<Isa>(state.range(1));
  bool supported = false;
  for (Isa i : supported_isas()) supported = supported || i == isa;
  if (!supported) {
    state.SkipWithError("instruction set not supported on this CPU");
    return;
  }
  const int width = lane_width(isa);
  const Spacecraft plant;
  const Scenario s = Scenario::paper();
  const SimulationOptions options;
  std::vector<SimulationResult> results(width);
  std::vector<detail::SpacecraftLane> lanes(width);
  for (int l = 0; l < width; ++l) {
    ControllerConfig c = ControllerConfig::table1(type);
    c.Kp *= 1.0 + 0.01 * l;
    c.switching_gain *= 1.0 - 0.01 * l;
    lanes[l].config = detail::checked_config(c, s.sample_time);
    lanes[l].scenario = &s;
    lanes[l].options = &options;
    lanes[l].truth = lanes[l].model = plant.f_constants();
    lanes[l].result = &results[l];
  }
  const Mat34 G = plant.G(State::Zero());
  const Mat43 Gp = plant.G_pinv(State::Zero());
  double ise = 0;
  for (auto _ : state) {
    detail::run_spacecraft_lanes(lanes, G, Gp, isa);
    ise += results[0].metrics.errors.ise;
  }
  benchmark::DoNotOptimize(ise);
  state.SetLabel(std::string(to_string(type)) + " " + to_string(isa));
  state.counters["ns_per_sample"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * s.samples() * width,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_Lanes)
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1, 2, 3}})
    ->Unit(benchmark::kMillisecond)
    ->Threads(1)
    ->Threads(2)
    ->UseRealTime();

BENCHMARK_MAIN();
