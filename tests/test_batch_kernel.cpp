// The batch simulator (sim_core/lanes/closed_loop.hpp): every lane of a pack, on every
// instruction set this CPU runs, gives the bits of the same simulation run alone in scalar code,
// whatever its neighbours do (other gains, other scenarios, divergence, partial packs), for
// every registered plant.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "checks.hpp"
#include "ftc/sim/hexarotor.hpp"
#include "ftc/sim/isa.hpp"
#include "ftc/sim/manipulator.hpp"
#include "ftc/sim/metrics_record.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/spacecraft.hpp"
#include "same_bits.hpp"

using namespace ftc::sim;

namespace {

// The paper's scenario shortened to 12 s with the faults at 2 s and 5 s: both faults and the
// chaotic stretch after them, at a fifth of the cost.
Scenario short_paper() {
  Scenario s = Scenario::paper();
  s.duration = 12.0;
  s.faults[0].onset = 2.0;
  s.faults[1].onset = 5.0;
  return s;
}

struct Task {
  ControllerConfig config;
  Scenario scenario;
  SimulationOptions options;
};

// Runs the tasks as lanes of packs on `isa` (all of them in as few packs as fit), on the plant
// of `spec` (the spacecraft by default).
std::vector<SimulationResult> run(const std::vector<Task>& tasks, Isa isa,
                                  const PlantSpec& spec = {}) {
  const auto plant = make_plant(spec);
  std::vector<PackTask> pack;
  for (const Task& t : tasks) pack.push_back({&t.config, &t.scenario, &t.options});
  std::vector<SimulationResult> results(tasks.size());
  std::vector<std::string> errors(tasks.size());
  plant->simulate_pack(pack, results, errors, isa);
  for (const std::string& e : errors) EXPECT_EQ(e, "");
  return results;
}

// Each task alone, in scalar code.
std::vector<SimulationResult> run_alone(const std::vector<Task>& tasks, const PlantSpec& spec = {}) {
  std::vector<SimulationResult> out;
  for (const Task& t : tasks) out.push_back(run({t}, Isa::scalar, spec)[0]);
  return out;
}

using ftc::testing::same_bits;

void expect_same(const SimulationResult& a, const SimulationResult& b, const std::string& what) {
  const auto eq = [&](double x, double y, const char* field) {
    EXPECT_TRUE(same_bits(x, y)) << what << ": " << field << " " << x << " vs " << y;
  };
  EXPECT_EQ(a.samples, b.samples) << what;
  ASSERT_EQ(a.final_state.size(), b.final_state.size()) << what;
  for (std::size_t i = 0; i < a.final_state.size(); ++i)
    eq(a.final_state[i], b.final_state[i], "final_state");
  const Metrics &m = a.metrics, &n = b.metrics;
  // Every field of the metrics record (ftc/sim/metrics_record.hpp), so a field added to it is
  // compared too: the kernel's copy-out into PackFinal's slots and the host's read-back.
  ASSERT_EQ(m.extra.size(), n.extra.size()) << what;
  for (const ftc::sim::MetricField& f : ftc::sim::kMetricFields) {
    const std::string name(f.name);
    switch (f.scope) {
      case ftc::sim::MetricScope::window:
        eq(m.errors.*f.in_window, n.errors.*f.in_window, name.c_str());
        for (std::size_t i = 0; i < m.extra.size(); ++i)
          eq(m.extra[i].*f.in_window, n.extra[i].*f.in_window, ("extra " + name).c_str());
        break;
      case ftc::sim::MetricScope::run:
        eq(m.*f.per_run, n.*f.per_run, name.c_str());
        break;
      case ftc::sim::MetricScope::fault:
        ASSERT_EQ((m.*f.per_fault).size(), (n.*f.per_fault).size()) << what << " " << name;
        for (std::size_t i = 0; i < (m.*f.per_fault).size(); ++i)
          eq((m.*f.per_fault)[i], (n.*f.per_fault)[i], name.c_str());
        break;
    }
  }
  EXPECT_EQ(m.diverged, n.diverged) << what;
  eq(m.diverged_at, n.diverged_at, "diverged_at");
  ASSERT_EQ(a.trajectory.values.size(), b.trajectory.values.size()) << what;
  // Bit for bit (NaN and -0.0 included); memcmp may not be given the null data() of an empty
  // vector, even for 0 bytes (UBSan's find).
  if (!a.trajectory.values.empty()) {
    EXPECT_EQ(std::memcmp(a.trajectory.values.data(), b.trajectory.values.data(),
                          a.trajectory.values.size() * sizeof(double)),
              0)
        << what << ": trajectory";
  }
}

// Lanes of one controller type with gains that differ lane by lane, among them one that
// diverges (for the laws with Kp and Ki) and, for NFTSMC, exponents of their own.
std::vector<Task> varied(ControllerType type, int n) {
  std::vector<Task> tasks;
  const Scenario s = short_paper();
  SimulationOptions o;
  o.extra_windows = {{0.0, 2.0}, {2.0, 5.0}, {5.0, 12.0}};
  for (int l = 0; l < n; ++l) {
    ControllerConfig c = ControllerConfig::table1(type);
    c.switching_gain *= 1.0 + 0.1 * l;
    c.c1 *= 1.0 + 0.05 * l;
    c.Kp = 1.0 + 6.0 * l;
    c.Ki = 50.0 - 5.0 * l;
    c.alpha = 1.4 + 0.02 * l;
    c.sigma1 *= 1.0 + 0.05 * l;
    if (l == 1 &&
        (type == ControllerType::pi_fosmc || type == ControllerType::adaptive_neural_pi_fosmc)) {
      c.Kp = 0.01;  // with Ki = 45: diverges within a fraction of a second
      c.Ki = 45.0;
    }
    tasks.push_back({c, s, o});
  }
  return tasks;
}

}  // namespace

TEST(BatchKernel, EveryLaneGivesTheScalarBitsOnEveryInstructionSet) {
  for (ControllerType type : kAllControllerTypes)
    for (Isa isa : supported_isas()) {
      const int w = lane_width(isa);
      // A full pack, and one lane more (a partial pack after it).
      const std::vector<Task> tasks = varied(type, w + 1);
      const std::vector<SimulationResult> want = run_alone(tasks);
      const std::vector<SimulationResult> got = run(tasks, isa);
      for (std::size_t i = 0; i < tasks.size(); ++i)
        expect_same(
            got[i], want[i],
            std::string(to_string(type)) + " on " + to_string(isa) + ", lane " + std::to_string(i));
      if (type == ControllerType::pi_fosmc) {
        EXPECT_TRUE(want[1].metrics.diverged) << "the test needs a diverging lane";
        EXPECT_FALSE(want[0].metrics.diverged);
      }
    }
}

TEST(BatchKernel, PartialPacksGiveTheScalarBits) {
  for (Isa isa : supported_isas())
    for (int n : {1, 3, 5}) {
      const std::vector<Task> tasks = varied(ControllerType::pi_fosmc, n);
      const std::vector<SimulationResult> want = run_alone(tasks);
      const std::vector<SimulationResult> got = run(tasks, isa);
      for (int i = 0; i < n; ++i)
        expect_same(got[i], want[i],
                    std::string(to_string(isa)) + ", " + std::to_string(n) + " lanes, lane " +
                        std::to_string(i));
    }
}

// Ensemble members in one pack: other fault onsets and types, disturbances, initial states,
// saturation and true inertia (model mismatch), with the same duration and sample time. Six of
// the eight keep the base's disturbance (the host computes it once for them, lane_host.hpp's
// Dist), two have their own; one bias fault starts after the run's end (its cosine is never
// tabulated).
TEST(BatchKernel, LanesOfDifferentScenariosGiveTheScalarBits) {
  std::vector<Task> tasks;
  for (int l = 0; l < 8; ++l) {
    Scenario s = short_paper();
    s.name = "member" + std::to_string(l);
    s.faults[0].onset = 1.0 + 0.7 * l;
    s.faults[1].onset = 9.0 - 0.5 * l;
    if (l % 3 == 1) {
      s.faults[1].type = FaultType::stuck;
      s.faults[1].value = 0.5;
    }
    if (l % 2 == 1) s.faults[0].profile = {FaultProfileType::incipient, 0.5 + l};
    if (l % 4 == 3)
      for (DisturbanceTerm& d : s.disturbance) d.amplitude *= 1.0 + 0.1 * l;
    if (l == 6) s.faults[0].onset = 20.0;
    s.initial_state[0] += 0.01 * l;
    if (l % 4 == 2) s.saturation = 12.0;
    if (l % 3 == 0)
      s.set_true_value("inertia", {20.0 * (1.0 + 0.02 * l), 17.0, 15.0 * (1.0 - 0.02 * l)});
    SimulationOptions o;
    o.window = {s.faults[0].onset, s.duration};
    tasks.push_back({ControllerConfig::table1(ControllerType::pi_fosmc), s, o});
  }
  const std::vector<SimulationResult> want = run_alone(tasks);
  for (Isa isa : supported_isas()) {
    const std::vector<SimulationResult> got = run(tasks, isa);
    for (std::size_t i = 0; i < tasks.size(); ++i)
      expect_same(got[i], want[i], std::string(to_string(isa)) + ", member " + std::to_string(i));
  }
}

// A pack's metrics in any number of windows and fault onsets are accumulated in the lanes
// (lanes/metric_lanes.hpp's MetricLanes: the kernel once kept 8 of each and left more to a second
// accumulator on the host): 13 windows and 11 faults, lanes with fewer of either beside them, give
// the scalar bits on every instruction set, and the windows that tile the run add up to its ISE.
TEST(BatchKernel, ManyWindowsAndFaultsAreMeasuredInTheLanes) {
  std::vector<Task> tasks = varied(ControllerType::pi_fosmc, 8);
  for (std::size_t l = 0; l < tasks.size(); ++l) {
    Task& t = tasks[l];
    t.options.extra_windows.clear();
    const int windows = l % 2 == 0 ? 12 : 3;  // extra windows tiling [0, 12)
    for (int w = 0; w < windows; ++w)
      t.options.extra_windows.push_back({12.0 * w / windows, 12.0 * (w + 1) / windows});
    const int faults = l % 3 == 0 ? 11 : 2;
    t.scenario.faults.resize(2);
    for (int f = 2; f < faults; ++f) {
      Fault loe;
      loe.actuator = 1 + f % 4;
      loe.type = FaultType::loss_of_effectiveness;
      loe.onset = 2.5 + 0.8 * f;
      loe.fraction = 0.01 * f;
      t.scenario.faults.push_back(loe);
    }
    t.options.metrics.settling_threshold = 0.05;
    t.options.metrics.steady_state_tail = 2.0;
  }
  const std::vector<SimulationResult> want = run_alone(tasks);
  for (Isa isa : supported_isas()) {
    const std::vector<SimulationResult> got = run(tasks, isa);
    for (std::size_t i = 0; i < tasks.size(); ++i)
      expect_same(got[i], want[i], std::string(to_string(isa)) + ", lane " + std::to_string(i));
  }
  const Metrics& m = want[0].metrics;
  ASSERT_EQ(m.extra.size(), 12u);
  ASSERT_EQ(m.peak_error_after_fault.size(), 11u);
  ASSERT_FALSE(m.diverged);
  double ise = 0.0;
  for (const ErrorIntegrals& e : m.extra) ise += e.ise;
  EXPECT_NEAR(ise, m.errors.ise, 1e-12 * m.errors.ise);
  // Each fault's peak error from its onset on: a later onset sees no larger peak.
  for (std::size_t f = 3; f < 11; ++f)
    EXPECT_LE(m.peak_error_after_fault[f], m.peak_error_after_fault[f - 1]) << f;
}

// A bias fault's cosine is tabulated only from the block of its onset on (exogenous_inputs.hpp's
// ExogenousInputs, blocks of 16 RK4 steps: 16 samples here). Onsets inside a block, exactly on a
// block's boundary and past the run's end: every lane on every instruction set gives the scalar
// bits, and the recorded applied command carries the bias's closed form from the onset's sample
// on (a table started a block late would leave its cosine unset there).
TEST(BatchKernel, BiasOnsetInsideABlockOnItsBoundaryAndPastTheEnd) {
  const Scenario base = short_paper();
  const double Ts = base.sample_time;
  ASSERT_EQ(base.substeps, 1);
  ASSERT_EQ(base.faults[0].type, FaultType::bias);
  ASSERT_EQ(base.faults[0].actuator, 1);
  ASSERT_FALSE(base.saturation.has_value());
  // Block 125 spans samples 2000..2015; its first instant is formed as k·Ts, as here.
  const std::vector<double> onsets = {static_cast<double>(2007) * Ts + 0.5 * Ts,  // mid-step
                                      static_cast<double>(2011) * Ts,  // a sample inside it
                                      static_cast<double>(2000) * Ts,  // its boundary
                                      base.duration + 0.5};            // never
  // The scenarios share their disturbance (the pack's tables of Δ(t) and of the faults apart),
  // or each has its own (one table per scenario, lane_host.hpp's Group::kOwn).
  for (const bool own_disturbance : {false, true}) {
    std::vector<Task> tasks;
    for (std::size_t i = 0; i < onsets.size(); ++i) {
      Scenario s = base;
      s.name = "bias" + std::to_string(i);
      s.faults[0].onset = onsets[i];
      s.faults[0].phase = 0.3 * static_cast<double>(i);
      if (own_disturbance)
        for (DisturbanceTerm& d : s.disturbance) d.amplitude *= 1.0 + 0.1 * static_cast<double>(i);
      SimulationOptions o;
      o.record_every = 1;
      tasks.push_back({ControllerConfig::table1(ControllerType::pi_fosmc), s, o});
    }
    const std::vector<SimulationResult> want = run_alone(tasks);
    for (Isa isa : supported_isas()) {
      const std::vector<SimulationResult> got = run(tasks, isa);
      for (std::size_t i = 0; i < tasks.size(); ++i)
        expect_same(got[i], want[i],
                    std::string(to_string(isa)) + ", onset " + std::to_string(i) +
                        (own_disturbance ? ", own disturbance" : ""));
    }
    constexpr int M = 4;  // the spacecraft's reaction wheels
    for (std::size_t i = 0; i < tasks.size(); ++i) {
      const Trajectory& tr = want[i].trajectory;
      ASSERT_EQ(tr.actuators, M);
      const FaultSet faults(tasks[i].scenario.faults, tasks[i].scenario.saturation);
      ASSERT_EQ(tr.rows(), static_cast<std::size_t>(base.samples()));
      // Actuator 1's applied command less its command, from a block before block 125 to the end
      // of the one after it.
      int biased = 0;
      for (std::int64_t k = 1984; k < 2048; ++k) {
        const std::size_t row = static_cast<std::size_t>(k);
        const double t = tr.t(row);
        const double offset = tr.u(row)[0] - tr.u_d(row)[0];
        const double expected = faults.effect<M>(t).offset[0];
        EXPECT_NEAR(offset, expected, 1e-9) << "onset " << i << ", sample " << k;
        if (expected != 0.0) ++biased;
      }
      EXPECT_EQ(biased, i == 3 ? 0 : 2048 - static_cast<int>(std::ceil(onsets[i] / Ts - 1e-9)))
          << "onset " << i;
    }
  }
}

TEST(BatchKernel, RecordedTrajectoriesAreTheScalarOnes) {
  std::vector<Task> tasks = varied(ControllerType::fosmc, 6);
  for (Task& t : tasks) t.options.record_every = 50;
  tasks[2].options.record_every = 0;  // lanes that record and lanes that do not
  const std::vector<SimulationResult> want = run_alone(tasks);
  ASSERT_EQ(want[0].trajectory.rows(), 12000u / 50u);
  for (Isa isa : supported_isas()) {
    const std::vector<SimulationResult> got = run(tasks, isa);
    for (std::size_t i = 0; i < tasks.size(); ++i)
      expect_same(got[i], want[i], std::string(to_string(isa)) + ", lane " + std::to_string(i));
  }
}

// The public entry point: simulate_pack gives what simulate gives, task by task, and an
// invalid task gets its error without disturbing the others.
TEST(BatchKernel, SimulatePackMatchesSimulateAndReportsBadTasks) {
  const auto plant = make_plant(PlantSpec{});
  const std::vector<Task> tasks = varied(ControllerType::pi_fosmc, 5);
  std::vector<PackTask> pack;
  for (const Task& t : tasks) pack.push_back({&t.config, &t.scenario, &t.options});
  ControllerConfig bad = tasks[0].config;
  bad.theta = -1.0;
  pack.push_back({&bad, &tasks[0].scenario, &tasks[0].options});
  std::vector<SimulationResult> results(pack.size());
  std::vector<std::string> errors(pack.size());
  plant->simulate_pack(pack, results, errors);
  for (std::size_t i = 0; i < tasks.size(); ++i) {
    EXPECT_TRUE(errors[i].empty()) << errors[i];
    expect_same(results[i], plant->simulate(tasks[i].config, tasks[i].scenario, tasks[i].options),
                "task " + std::to_string(i));
  }
  EXPECT_NE(errors.back().find("theta"), std::string::npos) << errors.back();
}

namespace {

PlantSpec arm_spec() {
  PlantSpec spec;
  spec.model = "manipulator";
  return spec;
}

// The arm (G and G⁺ depend on the state) through the same kernel: varied gains, a diverging
// lane, a loss of effectiveness and a stuck actuator, a disturbance on both joints.
std::vector<Task> varied_arm(ControllerType type, int n) {
  std::vector<Task> tasks;
  Scenario s;
  s.name = "arm";
  s.duration = 4.0;
  s.initial_state = {0.5, -0.4, 0.0, 0.0};
  s.disturbance = {{1, Shape::sin, 0.2, 1.0, 0.0}, {2, Shape::cos, 0.2, 2.0, 0.0}};
  Fault loe;
  loe.actuator = 1;
  loe.type = FaultType::loss_of_effectiveness;
  loe.onset = 1.0;
  loe.fraction = 0.3;
  Fault stuck;
  stuck.actuator = 3;
  stuck.type = FaultType::stuck;
  stuck.onset = 2.5;
  stuck.value = 0.2;
  s.faults = {loe, stuck};
  SimulationOptions o;
  o.extra_windows = {{0.0, 1.0}, {1.0, 4.0}};
  for (int l = 0; l < n; ++l) {
    ControllerConfig c = ControllerConfig::table1(type);
    c.switching_gain *= 1.0 + 0.1 * l;
    c.c1 *= 1.0 + 0.05 * l;
    c.Kp = 1.0 + 6.0 * l;
    c.Ki = 50.0 - 5.0 * l;
    if (l == 1 &&
        (type == ControllerType::pi_fosmc || type == ControllerType::adaptive_neural_pi_fosmc)) {
      c.Kp = 0.01;
      c.Ki = 45.0;
    }
    Scenario sl = s;
    if (l % 2 == 1) sl.saturation = 20.0;
    if (l % 3 == 2) sl.initial_state[1] += 0.1 * l;
    tasks.push_back({c, sl, o});
  }
  return tasks;
}

}  // namespace

TEST(BatchKernel, EveryArmLaneGivesTheScalarBitsOnEveryInstructionSet) {
  for (ControllerType type : kAllControllerTypes)
    for (Isa isa : supported_isas()) {
      const std::vector<Task> tasks = varied_arm(type, lane_width(isa) + 1);
      const std::vector<SimulationResult> want = run_alone(tasks, arm_spec());
      const std::vector<SimulationResult> got = run(tasks, isa, arm_spec());
      for (std::size_t i = 0; i < tasks.size(); ++i)
        expect_same(got[i], want[i],
                    std::string("arm, ") + to_string(type) + " on " + to_string(isa) +
                        ", lane " + std::to_string(i));
    }
}

// Recorded trajectories of the arm, lanes that record among lanes that do not, as alone.
TEST(BatchKernel, ArmTrajectoriesAreTheScalarOnes) {
  std::vector<Task> tasks = varied_arm(ControllerType::fosmc, 5);
  for (std::size_t i = 0; i < tasks.size(); ++i) tasks[i].options.record_every = i == 2 ? 0 : 25;
  const std::vector<SimulationResult> want = run_alone(tasks, arm_spec());
  ASSERT_EQ(want[0].trajectory.rows(), 4000u / 25u);
  for (Isa isa : supported_isas()) {
    const std::vector<SimulationResult> got = run(tasks, isa, arm_spec());
    for (std::size_t i = 0; i < tasks.size(); ++i)
      expect_same(got[i], want[i], std::string("arm, ") + to_string(isa) + ", lane " +
                                       std::to_string(i));
  }
}

// The arm's lane is the loop a Controller object runs in (sim::simulate with the class's f and
// G from the same angle trackers): the runtime controller replays a tuning run's lane.
TEST(BatchKernel, ArmLaneIsTheControllerLoop) {
  const Manipulator arm;
  const auto any = make_plant(arm_spec());
  for (ControllerType type : kAllControllerTypes) {
    const Task t = varied_arm(type, 1)[0];
    auto c = make_controller(t.config, arm, t.scenario.sample_time);
    expect_same(any->simulate(t.config, t.scenario, t.options), simulate(arm, *c, t.scenario, t.options),
                std::string("arm, ") + to_string(type));
  }
}

TEST(BatchKernel, InstructionSetsAreNamedAndOrdered) {
  const std::vector<Isa> isas = supported_isas();
  ASSERT_FALSE(isas.empty());
  EXPECT_EQ(isas.front(), Isa::scalar);
  // Widest last (the one active_isa() chooses), whichever vector copies the build has
  // (FTC_VECTOR_KERNELS: the sanitizer build has avx2 alone).
  for (std::size_t i = 1; i < isas.size(); ++i)
    EXPECT_GT(lane_width(isas[i]), lane_width(isas[i - 1]));
  EXPECT_EQ(lane_width(Isa::sse2), 2);
  EXPECT_EQ(lane_width(Isa::avx512), 8);
  EXPECT_STREQ(to_string(Isa::avx512), "avx512");
  EXPECT_EQ(lane_width(Isa::avx2), 4);
}

// The window metrics of issue 26 in lanes: lanes with a settling threshold and a steady-state
// tail among lanes without, saturated lanes and a diverging one; every lane on every instruction
// set gives the bits of the Controller loop (sim::simulate: the same loop with the controller as
// its law).
TEST(BatchKernel, WindowMetricsInLanesAreTheControllerLoops) {
  const Spacecraft sc;
  std::vector<Task> tasks = varied(ControllerType::pi_fosmc, 9);
  for (std::size_t l = 0; l < tasks.size(); ++l) {
    if (l % 2 == 0) tasks[l].options.metrics.settling_threshold = 0.02;
    if (l % 3 != 1) tasks[l].options.metrics.steady_state_tail = 3.0;
    // Lane 1 diverges. (The limit acts before the faults as well as after: below about 8 the
    // bias of up to 20 on actuator 1 holds a command at its limit all through [5, 12).)
    if (l % 2 == 1 && l != 1) tasks[l].scenario.saturation = 10.0;
  }
  std::vector<SimulationResult> want;
  for (const Task& t : tasks) {
    auto c = make_controller(t.config, sc, t.scenario.sample_time);
    want.push_back(simulate(sc, *c, t.scenario, t.options));
  }
  // The test means something: settled, unsettled and saturated lanes, tails, a diverged lane.
  int settled = 0, saturated = 0, tails = 0;
  for (const SimulationResult& r : want) {
    const ErrorIntegrals& e = r.metrics.extra.back();  // [5, 12): after the second fault
    settled += std::isfinite(e.settling_time) && e.settling_time > 0 ? 1 : 0;
    saturated += e.saturation_fraction > 0 && e.saturation_fraction < 1 ? 1 : 0;
    tails += std::isfinite(e.steady_state_error) ? 1 : 0;
    EXPECT_GT(e.control_energy, 0.0);
    EXPECT_GT(e.peak_command, 0.0);
  }
  EXPECT_GE(settled, 2);
  EXPECT_GE(saturated, 2);
  EXPECT_GE(tails, 4);
  EXPECT_TRUE(want[1].metrics.diverged);
  EXPECT_EQ(want[1].metrics.errors.settling_time, std::numeric_limits<double>::infinity());
  EXPECT_TRUE(std::isnan(want[3].metrics.errors.settling_time));  // no threshold
  EXPECT_TRUE(std::isnan(want[4].metrics.errors.steady_state_error));  // no tail
  for (Isa isa : supported_isas()) {
    const std::vector<SimulationResult> got = run(tasks, isa);
    for (std::size_t i = 0; i < tasks.size(); ++i)
      expect_same(got[i], want[i], std::string(to_string(isa)) + ", lane " + std::to_string(i));
  }
}

namespace {

// The actuator models of docs/model.md in turn: a lag, a rate limit, both, and none.
std::optional<ActuatorModel> actuator_of(std::size_t l, double tau, double rate) {
  ActuatorModel m;
  switch (l % 4) {
    case 0:
      m.time_constant = tau;
      return m;
    case 1:
      m.rate_limit = rate;
      return m;
    case 2:
      m.time_constant = tau;
      m.rate_limit = rate;
      return m;
    default:
      return std::nullopt;
  }
}

// Every lane on every instruction set against the Controller loop of the plant class `plant`.
template <class P>
void expect_lanes_are_the_controller_loop(const P& plant, const PlantSpec& spec,
                                          const std::vector<Task>& tasks, const std::string& what) {
  std::vector<SimulationResult> want;
  for (const Task& t : tasks) {
    auto c = make_controller(t.config, plant, t.scenario.sample_time);
    want.push_back(simulate(plant, *c, t.scenario, t.options));
  }
  for (Isa isa : supported_isas()) {
    const std::vector<SimulationResult> got = run(tasks, isa, spec);
    for (std::size_t i = 0; i < tasks.size(); ++i)
      expect_same(got[i], want[i], what + " on " + to_string(isa) + ", lane " + std::to_string(i));
  }
}

}  // namespace

// The actuator model in lanes: on every plant (the hexarotor's about its operating point), lanes
// with a lag, a rate limit, both and none, saturated lanes, a diverging one and recorded ones,
// give the bits of the Controller loop on every instruction set; and the model changes the run.
TEST(BatchKernel, ActuatorModelInLanesIsTheControllerLoops) {
  {
    std::vector<Task> tasks = varied(ControllerType::pi_fosmc, 9);
    for (std::size_t l = 0; l < tasks.size(); ++l) {
      tasks[l].scenario.actuator = actuator_of(l, 0.02, 200.0);
      if (l % 3 == 2) tasks[l].scenario.saturation = 6.0;
      tasks[l].options.record_every = l % 2 == 0 ? 40 : 0;
    }
    tasks[1].scenario.actuator = actuator_of(0, 0.02, 200.0);  // a lag on the diverging lane
    expect_lanes_are_the_controller_loop(Spacecraft(), PlantSpec{}, tasks, "spacecraft");
    const auto any = make_plant(PlantSpec{});
    Task off = tasks[0];
    off.scenario.actuator.reset();
    const double with = any->simulate(tasks[0].config, tasks[0].scenario, tasks[0].options)
                            .metrics.errors.ise;
    const double without = any->simulate(off.config, off.scenario, off.options).metrics.errors.ise;
    EXPECT_TRUE(std::isfinite(with));
    EXPECT_NE(with, without);
    EXPECT_TRUE(
        any->simulate(tasks[1].config, tasks[1].scenario, tasks[1].options).metrics.diverged);
  }
  {
    std::vector<Task> tasks = varied_arm(ControllerType::fosmc, 6);
    for (std::size_t l = 0; l < tasks.size(); ++l) {
      tasks[l].scenario.actuator = actuator_of(l, 0.01, 100.0);
      tasks[l].options.record_every = l % 2 == 0 ? 25 : 0;
    }
    expect_lanes_are_the_controller_loop(Manipulator(), arm_spec(), tasks, "arm");
  }
  {
    PlantSpec spec;
    spec.model = "hexarotor";
    Scenario s;
    s.name = "hover";
    s.duration = 3.0;
    s.initial_state = {0.2, -0.15, 0.1, 0.0, 0.0, 0.0};
    s.disturbance = {{1, Shape::sin, 0.2, 1.0, 0.0}, {3, Shape::cos, 0.1, 2.0, 0.0}};
    Fault loss;
    loss.actuator = 3;
    loss.type = FaultType::loss_of_effectiveness;
    loss.fraction = 0.5;
    loss.onset = 1.0;
    s.faults = {loss};
    std::vector<Task> tasks;
    for (std::size_t l = 0; l < 6; ++l) {
      ControllerConfig c = ControllerConfig::table1(ControllerType::pi_fosmc);
      c.Kp = 1.0 + l;
      c.Ki = 50.0;
      Scenario sl = s;
      sl.actuator = actuator_of(l, 0.02, 50.0);
      if (l == 4) sl.saturation = 2.0;
      SimulationOptions o;
      o.record_every = l % 2 == 0 ? 30 : 0;
      tasks.push_back({c, sl, o});
    }
    expect_lanes_are_the_controller_loop(Hexarotor(), spec, tasks, "hexarotor");
  }
}
