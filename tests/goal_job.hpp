#pragma once
// A job with goals for the capping tests (issue 27): the short ensemble job (11 members)
// scored by a soft CVaR of the post-fault ISE under hard goals on the largest control TV and
// the median peak command (metrics with a lower bound), and, with `unbounded`, on the mean
// steady-state error (a metric without one) at a limit no candidate breaks.
#include <nlohmann/json.hpp>

#include "short_job.hpp"

namespace ftc::testing {

inline nlohmann::json goal_ensemble_job(double tv_limit, double peak_limit, bool unbounded) {
  nlohmann::json j = short_ensemble_job();
  j["ensemble"]["count"] = 11;
  j.erase("objective");
  j["goals"] = {{{"metric", "ise"},
                 {"window", {0, 4}},
                 {"window_from", "first_fault"},
                 {"aggregate", "cvar"},
                 {"alpha", 0.8},
                 {"minimize", true}},
                {{"metric", "control_tv"}, {"aggregate", "max"}, {"at_most", tv_limit}},
                {{"metric", "peak_command"}, {"aggregate", "quantile"}, {"q", 0.5},
                 {"at_most", peak_limit}}};
  if (unbounded)
    j["goals"].push_back({{"metric", "steady_state_error"}, {"tail", 1.0}, {"at_most", 1e300}});
  return j;
}

// A front (issue 42) on the same ensemble: post-fault ISE (CVaR) against the median control TV,
// under a limit on the peak command that some candidates break.
inline nlohmann::json front_ensemble_job() {
  nlohmann::json j = goal_ensemble_job(1000, 30, false);
  j["name"] = "front-ensemble";
  j["goals"][1] = {
      {"metric", "control_tv"}, {"aggregate", "quantile"}, {"q", 0.5}, {"minimize", true}};
  j["goals"][2] = {{"metric", "peak_command"}, {"aggregate", "max"}, {"at_most", 30}};
  return j;
}

}  // namespace ftc::testing
