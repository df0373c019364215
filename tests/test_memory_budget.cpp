// The memory budget (tuner/run/memory_budget.cpp) against what a run really takes: the charge
// for a listed scenario covers its share of a run's peak, output documents included.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "ftc/tune/evaluators/batch_evaluator.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/memory_budget.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "peak_memory.hpp"
#include "short_job.hpp"

namespace {

using nlohmann::json;
using namespace ftc;

// A job of `n` listed scenarios of 20 ms, each with its own faults (as a scenarios file from
// `ftctune ensemble` gives them), two evaluations.
json listed_job(int n) {
  json j = ftc::testing::tiny_job("listed");
  const json base = j["scenarios"][0];
  j["scenarios"] = json::array();
  for (int i = 0; i < n; ++i) {
    json s = base;
    s["name"] = "member-" + std::to_string(i);
    s["duration"] = 0.02;
    s["faults"][0]["onset"] = 0.005 + 1e-6 * i;
    s["faults"][1]["onset"] = 0.01;
    j["scenarios"].push_back(s);
  }
  j["objective"]["window"] = {0, 0.01};
  j["tuning"]["algorithm"]["iterations"] = 0;
  return j;
}

// The bytes a child process's peak grows by while it reads `text` as a job, tunes it and makes
// every output file's contents (where a run peaks); negative when that failed.
double peak_growth(const std::string& text) {
  return 1024.0 * static_cast<double>(ftc::testing::peak_growth_kb([&text] {
           const tune::Job job = tune::parse_job_text(text, "listed.json");
           tune::SerialEvaluator serial;
           const tune::TuningOutcome r = tune::tune(job, serial);
           // A trajectory per scenario and controller: the files are whole.
           return tune::output_files(r).size() > 2 * job.scenarios.size();
         }));
}

}  // namespace

// Issue 29: a job is refused up front when its estimate is above the budget, so the estimate must
// not undercount. The listed scenarios' charge (kBytesPerScenario, kBytesPerScenarioController
// and the comparison's trajectories) against the growth of a run's peak from 300 to 2300 of them, with 2, 4 and 6
// controllers compared.
TEST(MemoryBudget, AListedScenarioTakesNoMoreThanItIsCharged) {
  if (const char* why = ftc::testing::why_no_peak()) GTEST_SKIP() << why;
  // With the job's and the tuned controller only, and with two and four compare entries besides
  // (Table 1's two, again under other labels).
  for (const std::size_t compared : {0u, 2u, 4u}) {
    json small_job = listed_job(300), large_job = listed_job(2300);
    const json table1 = small_job["compare"];
    for (json* j : {&small_job, &large_job}) {
      json list = json::array();
      for (std::size_t k = 0; k < compared; ++k) {
        json entry = table1[k % table1.size()];
        entry["label"] = "compared-" + std::to_string(k);
        list.push_back(entry);
      }
      (*j)["compare"] = list;
    }
    const double small = peak_growth(small_job.dump()), large = peak_growth(large_job.dump());
    ASSERT_GT(small, 0);
    ASSERT_GT(large, small);
    const double charged = tune::listed_scenario_bytes(tune::parse_job(large_job, "l")) -
                           tune::listed_scenario_bytes(tune::parse_job(small_job, "s"));
    const double taken = large - small;
    EXPECT_LE(taken, charged) << compared << " compared: a listed scenario took " << taken / 2000
                              << " bytes, charged " << charged / 2000;
    // And the charge is an estimate, not a blanket: within twice what they take.
    EXPECT_GE(taken, charged / 2) << compared << " compared: a listed scenario took "
                                  << taken / 2000 << " bytes, charged " << charged / 2000;
  }
}
