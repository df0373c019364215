// Proves that the simulation loop does not allocate: a run of 30 s makes exactly as many heap
// allocations as a run of 1 s (all of them before the loop), so memory does not grow with the
// duration either.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "ftc/sim/controller.hpp"
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
long allocations_for(ControllerType type, double duration) {
  const Spacecraft plant;
  Scenario s = Scenario::paper();
  s.duration = duration;
  auto c = make_controller(ControllerConfig::table1(type), plant, s.sample_time);
  const long before = g_allocations.load();
  const SimulationResult r = simulate(plant, *c, s);
  const long after = g_allocations.load();
  EXPECT_FALSE(r.metrics.diverged);
  return after - before;
}
}  // namespace

class AllocationFree : public ::testing::TestWithParam<ControllerType> {};

TEST_P(AllocationFree, LoopAllocatesNothing) {
  const long short_run = allocations_for(GetParam(), 1.0);
  const long long_run = allocations_for(GetParam(), 30.0);
  EXPECT_EQ(short_run, long_run) << "allocations grow with the number of samples";
  EXPECT_LT(short_run, 100) << "setup (validation, metrics storage) should stay small";
}

INSTANTIATE_TEST_SUITE_P(Simulation, AllocationFree, ::testing::ValuesIn(kAllControllerTypes),
                         [](const ::testing::TestParamInfo<ControllerType>& p) {
                           return std::string(to_string(p.param));
                         });
