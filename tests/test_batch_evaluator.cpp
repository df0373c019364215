// The evaluator seam on its own: tasks over a SimulationSet, built without any TuningProblem,
// give on every evaluator what sim::simulate gives their scenario and controller, to the bit.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "ftc/sim/controller.hpp"
#include "ftc/sim/controllers.hpp"
#include "ftc/sim/metrics_record.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/sim/spacecraft.hpp"
#include "ftc/tune/evaluators/batch_evaluator.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"

namespace {

using namespace ftc;

// The metrics record as bytes (every field the record has, NaN and -0.0 told apart).
std::vector<char> record_bytes(const sim::Metrics& m) {
  std::vector<char> b;
  sim::append_metrics_wire(b, m);
  return b;
}

// Three scenarios in two loop shapes (two groups of packs): the paper's faults, a shorter one
// at 2 ms with saturation, and one without faults.
tune::SimulationSet spacecraft_set() {
  std::vector<sim::Scenario> scenarios(3, sim::Scenario::paper());
  scenarios[0].name = "faults";
  scenarios[0].duration = 24.0;
  scenarios[1].name = "slow";
  scenarios[1].duration = 12.0;
  scenarios[1].sample_time = 2e-3;
  scenarios[1].saturation = 30.0;
  scenarios[2].name = "healthy";
  scenarios[2].duration = 24.0;
  scenarios[2].faults.clear();
  std::vector<sim::SimulationOptions> options(3);
  options[0].window = {10.0, std::numeric_limits<double>::infinity()};
  options[0].extra_windows = {{0.0, 10.0}, {10.0, 20.0}, {20.0, 24.0}};
  options[1].extra_windows = {{0.0, 12.0}};
  options[2].window = {5.0, 24.0};
  return tune::SimulationSet({"spacecraft", {}}, std::move(scenarios), std::move(options));
}

TEST(BatchEvaluator, RunsTasksWithoutAProblemToTheBitsOfSimulate) {
  const tune::SimulationSet set = spacecraft_set();
  std::vector<sim::ControllerConfig> candidates;
  for (sim::ControllerType type : sim::kAllControllerTypes) {
    sim::ControllerConfig c;
    c.type = type;
    candidates.push_back(c);
  }
  candidates[0].c1 = 7.5;
  candidates[0].Kp = 12.0;
  sim::ControllerConfig invalid;
  invalid.theta = -1.0;
  candidates.push_back(invalid);
  // Every (candidate, scenario) pair, scenario-major (so packs mix controllers), the first
  // scenario's recorded.
  std::vector<tune::SimulationTask> tasks;
  for (std::size_t s = 0; s < set.size(); ++s)
    for (std::size_t c = 0; c < candidates.size(); ++c) tasks.push_back({c, s, s == 0});
  const tune::SimulationBatch batch{set, candidates, tasks, 250};

  const sim::Spacecraft plant;  // the spec's defaults
  tune::SerialEvaluator serial;
  tune::TbbEvaluator tbb(2);
  for (tune::BatchEvaluator* evaluator :
       {static_cast<tune::BatchEvaluator*>(&serial), static_cast<tune::BatchEvaluator*>(&tbb)}) {
    const std::vector<tune::TaskResult> got = evaluator->run(batch);
    ASSERT_EQ(got.size(), tasks.size());
    for (std::size_t k = 0; k < tasks.size(); ++k) {
      const tune::SimulationTask& t = tasks[k];
      const sim::Scenario& scenario = set.scenario(t.scenario);
      const std::string what = evaluator->name() + ", task " + std::to_string(k) + " (" +
                               sim::to_string(candidates[t.candidate].type) + " on " +
                               scenario.name + ")";
      if (t.candidate + 1 == candidates.size()) {  // the invalid controller
        EXPECT_NE(got[k].error.find("theta"), std::string::npos) << what << ": " << got[k].error;
        continue;
      }
      ASSERT_EQ(got[k].error, "") << what;
      sim::SimulationOptions options = set.options(t.scenario);
      options.record_every = t.record ? batch.record_every : 0;
      auto controller = sim::make_controller(candidates[t.candidate], plant, scenario.sample_time);
      const sim::SimulationResult want = sim::simulate(plant, *controller, scenario, options);
      EXPECT_EQ(record_bytes(got[k].metrics), record_bytes(want.metrics)) << what;
      const std::vector<double>& a = got[k].trajectory.values;
      const std::vector<double>& b = want.trajectory.values;
      ASSERT_EQ(a.size(), b.size()) << what;
      EXPECT_EQ(a.empty(), !t.record) << what;
      if (!a.empty()) {
        EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)), 0) << what;
      }
    }
  }
}

// Tasks come candidate by candidate (as TuningProblem::tasks and the capping rounds make them);
// packs take them scenario by scenario, so that candidates on one ensemble member share its
// inputs' tables: every task once, the scenarios in order, each scenario's candidates in order.
TEST(BatchEvaluator, PacksHoldEachScenariosCandidatesTogether) {
  std::vector<sim::Scenario> scenarios(5, sim::Scenario::paper());
  for (std::size_t s = 0; s < scenarios.size(); ++s) {
    scenarios[s].name = "member" + std::to_string(s);
    scenarios[s].faults[0].onset = 5.0 + static_cast<double>(s);
  }
  const tune::SimulationSet set({"spacecraft", {}}, std::move(scenarios),
                                std::vector<sim::SimulationOptions>(5));
  const std::vector<sim::ControllerConfig> candidates(3);
  std::vector<tune::SimulationTask> tasks;
  for (std::size_t c = 0; c < candidates.size(); ++c)
    for (std::size_t s = 1; s < set.size(); ++s) tasks.push_back({c, s, false});
  const tune::SimulationBatch batch{set, candidates, tasks, 0};
  const std::size_t width = static_cast<std::size_t>(set.plant().pack_width());
  for (int workers : {1, 2, 16}) {
    std::vector<std::pair<std::size_t, std::size_t>> order;  // (scenario, candidate)
    for (const std::vector<std::size_t>& pack : tune::plan_packs(batch, workers)) {
      EXPECT_GE(pack.size(), 1u);
      EXPECT_LE(pack.size(), width);
      for (std::size_t k : pack) order.emplace_back(tasks[k].scenario, tasks[k].candidate);
    }
    ASSERT_EQ(order.size(), tasks.size()) << workers << " workers";
    for (std::size_t i = 0; i < order.size(); ++i)
      EXPECT_EQ(order[i], std::make_pair(1 + i / candidates.size(), i % candidates.size()))
          << workers << " workers, task " << i;
  }
}

TEST(BatchEvaluator, SetsRefuseScenariosWithoutOptionsAndKnowTheirPlant) {
  EXPECT_THROW(tune::SimulationSet({"spacecraft", {}}, {sim::Scenario::paper()}, {}),
               std::invalid_argument);
  EXPECT_THROW(tune::SimulationSet({"submarine", {}}, {}, {}), InputError);
  const tune::SimulationSet set = spacecraft_set();
  EXPECT_EQ(set.plant().actuators(), 4);
  EXPECT_EQ(set.plant_spec().model, "spacecraft");
  const tune::SimulationSet other =
      set.with_scenarios({sim::Scenario::paper()}, {sim::SimulationOptions{}});
  EXPECT_EQ(other.size(), 1u);
  EXPECT_NE(other.identity(), set.identity());
  EXPECT_EQ(&other.plant(), &set.plant());  // the plant is shared, not built again
}

}  // namespace
