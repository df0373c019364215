// Proves that the simulation loop does not allocate: a run of 30 s makes exactly as many heap
// allocations as a run of 1 s (all of them before the loop), so memory does not grow with the
// duration either.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "ftc/sim/controller.hpp"
#include "ftc/sim/hexarotor.hpp"
#include "ftc/sim/manipulator.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/sim/spacecraft.hpp"

namespace {
std::atomic<long> g_allocations{0};
}

void* operator new(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

using namespace ftc::sim;

namespace {
template <class P>
long allocations_for(const P& plant, Scenario s, ControllerType type, double duration) {
  s.duration = duration;
  auto c = make_controller(ControllerConfig::table1(type), plant, s.sample_time);
  const long before = g_allocations.load();
  const SimulationResult r = simulate(plant, *c, s);
  const long after = g_allocations.load();
  EXPECT_FALSE(r.metrics.diverged);
  return after - before;
}

// The same through the plant registry: one lane of the plant's batch kernel (AnyPlant::simulate).
long kernel_allocations_for(const std::string& model, Scenario s, ControllerType type,
                            double duration) {
  PlantSpec spec;
  spec.model = model;
  const auto plant = make_plant(spec);
  s.duration = duration;
  const ControllerConfig c = ControllerConfig::table1(type);
  const long before = g_allocations.load();
  const SimulationResult r = plant->simulate(c, s);
  const long after = g_allocations.load();
  EXPECT_EQ(r.samples, s.samples());
  return after - before;
}

// The arm, whose G changes with the state: the loop evaluates it at every RK4 stage and the
// controllers form G⁺ every sample.
Scenario arm_scenario() {
  Scenario s;
  s.initial_state = {0.5, -0.4, 0.0, 0.0};
  s.disturbance = {{1, Shape::sin, 0.2, 1.0, 0.0}};
  Fault loe;
  loe.actuator = 1;
  loe.type = FaultType::loss_of_effectiveness;
  loe.onset = 0.5;
  loe.fraction = 0.3;
  s.faults = {loe};
  return s;
}
}  // namespace

class AllocationFree : public ::testing::TestWithParam<ControllerType> {};

TEST_P(AllocationFree, LoopAllocatesNothing) {
  const Spacecraft plant;
  const long short_run = allocations_for(plant, Scenario::paper(), GetParam(), 1.0);
  const long long_run = allocations_for(plant, Scenario::paper(), GetParam(), 30.0);
  EXPECT_EQ(short_run, long_run) << "allocations grow with the number of samples";
  EXPECT_LT(short_run, 100) << "setup (validation, metrics storage) should stay small";
}

TEST_P(AllocationFree, ManipulatorLoopAllocatesNothing) {
  const Manipulator plant;
  const long short_run = allocations_for(plant, arm_scenario(), GetParam(), 1.0);
  const long long_run = allocations_for(plant, arm_scenario(), GetParam(), 30.0);
  EXPECT_EQ(short_run, long_run) << "allocations grow with the number of samples";
  EXPECT_LT(short_run, 100) << "setup (validation, metrics storage) should stay small";
}

// The hexarotor about hover: a 30 % loss of effectiveness of rotor 1.
Scenario hexarotor_scenario() {
  Scenario s;
  s.initial_state = {0.2, -0.15, 0.1, 0.0, 0.0, 0.0};
  s.disturbance = {{1, Shape::sin, 0.2, 1.0, 0.0}};
  Fault loe;
  loe.actuator = 1;
  loe.type = FaultType::loss_of_effectiveness;
  loe.onset = 0.5;
  loe.fraction = 0.3;
  s.faults = {loe};
  return s;
}

TEST_P(AllocationFree, KernelsAllocateNothingPerSample) {
  // With sensors (SPEC §18): the noise comes from a table drawn once per scenario and the delayed
  // measurements from a ring sized once per pack.
  Scenario sensed = Scenario::paper();
  sensed.sensors = SensorModel{};
  sensed.sensors->rate.noise = 1e-3;
  sensed.sensors->delay = 3;
  sensed.sensors->acceleration.source = AccelerationSource::differentiated;
  const std::pair<const char*, Scenario> plants[] = {{"spacecraft", Scenario::paper()},
                                                     {"spacecraft", sensed},
                                                     {"manipulator", arm_scenario()},
                                                     {"hexarotor", hexarotor_scenario()},
                                                     {"rigid_body", hexarotor_scenario()},
                                                     {"multirotor", hexarotor_scenario()}};
  for (const auto& [model, s] : plants) {
    kernel_allocations_for(model, s, GetParam(), 0.1);  // first use: sig^a tables, ISA choice
    const long short_run = kernel_allocations_for(model, s, GetParam(), 1.0);
    const long long_run = kernel_allocations_for(model, s, GetParam(), 30.0);
    EXPECT_EQ(short_run, long_run) << model << ": allocations grow with the number of samples";
    EXPECT_LT(short_run, 100) << model << ": setup should stay small";
  }
}

INSTANTIATE_TEST_SUITE_P(Simulation, AllocationFree, ::testing::ValuesIn(kAllControllerTypes),
                         [](const ::testing::TestParamInfo<ControllerType>& p) {
                           return std::string(to_string(p.param));
                         });
