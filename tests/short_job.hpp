#pragma once
// A shortened copy of the Table 1 job for fast end-to-end tests: 5 s with the faults at 2 s
// and 3.5 s, 3 bats × 2 iterations.
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

namespace ftc::testing {

inline nlohmann::json short_table1_job() {
  std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/table1.json");
  nlohmann::json j = nlohmann::json::parse(in);
  j["name"] = "table1-short";
  j["scenarios"][0]["duration"] = 5;
  j["scenarios"][0]["faults"][0]["onset"] = 2;
  j["scenarios"][0]["faults"][1]["onset"] = 3.5;
  j["objective"]["window"] = {0, 5};
  j["tuning"]["algorithm"]["population"] = 3;
  j["tuning"]["algorithm"]["iterations"] = 2;
  return j;
}

}  // namespace ftc::testing
