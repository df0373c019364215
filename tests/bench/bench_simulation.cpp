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
#include "ftc/sim/vehicles.hpp"

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
// A full pack of W candidates of one controller type on `plant` through AnyPlant::simulate_pack
// on one instruction set.
static void run_lanes(benchmark::State& state, const PlantSpec& spec, const Scenario& s) {
  const auto type = static_cast<ControllerType>(state.range(0));
  const auto isa = static_cast<Isa>(state.range(1));
  bool supported = false;
  for (Isa i : supported_isas()) supported = supported || i == isa;
  if (!supported) {
    state.SkipWithError("instruction set not supported on this CPU");
    return;
  }
  const int width = lane_width(isa);
  const auto plant = make_plant(spec);
  const SimulationOptions options;
  std::vector<ControllerConfig> configs(width);
  std::vector<PackTask> tasks(width);
  for (int l = 0; l < width; ++l) {
    ControllerConfig& c = configs[l];
    c = ControllerConfig::table1(type);
    c.Kp *= 1.0 + 0.01 * l;
    c.switching_gain *= 1.0 - 0.01 * l;
    tasks[l] = {&c, &s, &options};
  }
  std::vector<SimulationResult> results(width);
  std::vector<std::string> errors(width);
  double ise = 0;
  for (auto _ : state) {
    plant->simulate_pack(tasks, results, errors, isa);
    ise += results[0].metrics.errors.ise;
  }
  benchmark::DoNotOptimize(ise);
  state.SetLabel(spec.model + " " + to_string(type) + " " + to_string(isa));
  state.counters["ns_per_sample"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * s.samples() * width,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

static void BM_Lanes(benchmark::State& state) {
  run_lanes(state, PlantSpec{}, Scenario::paper());
}

// The arm under the paper's kind of load: 30 s at 1 ms, a sinusoidal disturbance on both
// joints, a loss of effectiveness and a stuck actuator.
static Scenario arm_scenario() {
  Scenario s;
  s.name = "arm";
  s.duration = 30.0;
  s.initial_state = {0.5, -0.4, 0.0, 0.0};
  s.disturbance = {{1, Shape::sin, 0.2, 1.0, 0.0}, {2, Shape::cos, 0.2, 2.0, 0.0}};
  Fault loe;
  loe.actuator = 1;
  loe.type = FaultType::loss_of_effectiveness;
  loe.onset = 10.0;
  loe.fraction = 0.3;
  Fault stuck;
  stuck.actuator = 3;
  stuck.type = FaultType::stuck;
  stuck.onset = 20.0;
  stuck.value = 0.2;
  s.faults = {loe, stuck};
  return s;
}

static void BM_ArmLanes(benchmark::State& state) {
  PlantSpec spec;
  spec.model = "manipulator";
  run_lanes(state, spec, arm_scenario());
}

BENCHMARK(BM_Lanes)
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1, 2, 3}})
    ->Unit(benchmark::kMillisecond)
    ->Threads(1)
    ->Threads(2)
    ->UseRealTime();

// The hexarotor about hover: 30 s at 1 ms, a disturbance on roll and yaw, a loss of
// effectiveness of rotor 1 and a thrust bias on rotor 4.
static Scenario hexarotor_scenario() {
  Scenario s;
  s.name = "hover";
  s.duration = 30.0;
  s.initial_state = {0.2, -0.15, 0.1, 0.0, 0.0, 0.0};
  s.disturbance = {{1, Shape::sin, 0.2, 1.0, 0.0}, {3, Shape::cos, 0.1, 2.0, 0.0}};
  Fault loe;
  loe.actuator = 1;
  loe.type = FaultType::loss_of_effectiveness;
  loe.onset = 10.0;
  loe.fraction = 0.4;
  Fault bias;
  bias.actuator = 4;
  bias.type = FaultType::bias;
  bias.onset = 20.0;
  bias.offset = 0.5;
  s.faults = {loe, bias};
  return s;
}

static void BM_HexarotorLanes(benchmark::State& state) {
  PlantSpec spec;
  spec.model = "hexarotor";
  run_lanes(state, spec, hexarotor_scenario());
}

BENCHMARK(BM_HexarotorLanes)
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1, 2, 3}})
    ->Unit(benchmark::kMillisecond)
    ->Threads(1)
    ->Threads(2)
    ->UseRealTime();

// Your vehicle (SPEC §17) against the spacecraft on the same scenario: a rigid body with a full
// inertia tensor of the spacecraft's size and four pyramid wheels, with the 3-2-1 Euler
// kinematics (W and Ẇ each sample); and a quad_x multirotor about hover on the hexarotor's
// scenario. Issue 38 asks each to cost at most 1.5 times the spacecraft per sample.
static void BM_RigidBodyLanes(benchmark::State& state) {
  RigidBodySpec body;
  body.inertia = {20, 0.5, -0.3, 0.5, 17, 0.4, -0.3, 0.4, 15};
  PlantSpec spec;
  spec.model = "rigid_body";
  spec.values = to_values(body);
  run_lanes(state, spec, Scenario::paper());
}

static void BM_QuadXLanes(benchmark::State& state) {
  PlantSpec spec;
  spec.model = "multirotor";
  spec.values = to_values(MultirotorSpec{});
  run_lanes(state, spec, hexarotor_scenario());
}

BENCHMARK(BM_RigidBodyLanes)
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1, 2, 3}})
    ->Unit(benchmark::kMillisecond)
    ->Threads(1)
    ->UseRealTime();

BENCHMARK(BM_QuadXLanes)
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1, 2, 3}})
    ->Unit(benchmark::kMillisecond)
    ->Threads(1)
    ->UseRealTime();

BENCHMARK(BM_ArmLanes)
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1, 2, 3}})
    ->Unit(benchmark::kMillisecond)
    ->Threads(1)
    ->Threads(2)
    ->UseRealTime();

// The paper's scenario with the actuator model on (docs/model.md: a 20 ms lag and 200 per s rate
// limit): what the model costs against BM_Lanes.
static void BM_ActuatorLanes(benchmark::State& state) {
  Scenario s = Scenario::paper();
  ActuatorModel m;
  m.time_constant = 0.02;
  m.rate_limit = 200.0;
  s.actuator = m;
  run_lanes(state, PlantSpec{}, s);
}

BENCHMARK(BM_ActuatorLanes)
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1, 2, 3}})
    ->Unit(benchmark::kMillisecond)
    ->Threads(1)
    ->UseRealTime();

// The paper's scenario with realistic MEMS-gyro sensors (SPEC §18): attitude and rate noise, a
// bias and its random walk, quantisation, a one-sample delay and the acceleration differentiated
// from the rates through a 5 ms low-pass. Issue 39 asks for at most 25 % more than BM_Lanes per
// sample and candidate; BM_RigidBodySensorLanes against BM_RigidBodyLanes adds the model terms
// at the measured Euler angles.
static Scenario with_sensors(Scenario s) {
  SensorModel m;
  m.angle.noise = 1e-4;
  m.angle.quantization = 1e-5;
  m.rate.noise = 1e-3;
  m.rate.bias = {2e-3};
  m.rate.bias_walk = 1e-4;
  m.rate.quantization = 1e-5;
  m.delay = 1;
  m.acceleration = {AccelerationSource::differentiated, 0.005};
  s.sensors = m;
  return s;
}

static void BM_SensorLanes(benchmark::State& state) {
  run_lanes(state, PlantSpec{}, with_sensors(Scenario::paper()));
}

static void BM_RigidBodySensorLanes(benchmark::State& state) {
  RigidBodySpec body;
  body.inertia = {20, 0.5, -0.3, 0.5, 17, 0.4, -0.3, 0.4, 15};
  PlantSpec spec;
  spec.model = "rigid_body";
  spec.values = to_values(body);
  run_lanes(state, spec, with_sensors(Scenario::paper()));
}

BENCHMARK(BM_SensorLanes)
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1, 2, 3}})
    ->Unit(benchmark::kMillisecond)
    ->Threads(1)
    ->UseRealTime();

BENCHMARK(BM_RigidBodySensorLanes)
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1, 2, 3}})
    ->Unit(benchmark::kMillisecond)
    ->Threads(1)
    ->UseRealTime();

BENCHMARK_MAIN();
