#pragma once
// The Pareto front of a run with two or more soft goals (RUN/front.json, written by `ftctune
// run`): read back, drawn as a pairwise scatter of the soft goals and as the hypervolume per
// iteration, and shown as a table in report.html. Private to tuner/report.
#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ftc/tune/report/report.hpp"
#include "report/figures.hpp"

namespace ftc::tune::report_detail {

inline constexpr const char* kFrontSchema = "ftctune.front/1";

struct FrontGoal {
  std::string metric;  // "ise", "control_tv", ...
  bool soft = false;
  double at_most = 0;  // a hard goal's limit
  std::string label;   // metric, window and aggregate ("CVaR0.9 of ISE[first fault, +4 s]")
  std::string unit;    // "rad²·s"
};

struct FrontPoint {
  std::vector<std::pair<std::string, double>> parameters;  // in front.json's order
  std::vector<double> goals;                               // every goal; +inf for null
  bool feasible = true;
  double violation = 0;
  std::vector<double> noise_floor;  // relative spread per goal; NaN where not measured
  long long trial = -1;             // row of trials.csv, -1 when not given
  // The run's own verdict: the earlier point this one lies within the noise floor of.
  std::optional<std::size_t> within_noise_of;
};

struct FrontCompared {
  std::string label, role;  // role "compare" (a compare entry) or "baseline" (the job's gains)
  std::vector<double> goals;
  bool feasible = true;
};

struct Front {
  std::vector<FrontGoal> goals;
  std::vector<std::size_t> soft;        // indices of the soft goals in `goals`
  std::vector<double> reference_point;  // per soft goal, in log10 of it
  double hypervolume = 0;
  std::optional<std::size_t> picked;
  std::string rule;  // how the picked point was chosen
  std::vector<FrontCompared> compared;
  std::vector<FrontPoint> points;
};

// The goal's label (metric, window and, over several scenarios, the aggregate) from its canonical
// JSON form, as objective_label() words an objective.
std::string goal_label(const nlohmann::json& goal, std::size_t scenarios);

// front.json of `file`, checked against the contract; InputError with the JSON path otherwise.
Front parse_front(const std::string& text, const std::string& file, std::size_t scenarios);

// RUN/front.json when there is one of this run (its job_sha256 is gains.json's): a front left
// by an earlier run of another job is not this run's. Each point's parameters are put in the
// order of `parameter_order` (the job's), those it does not name after them.
std::optional<Front> read_front(const std::filesystem::path& run_dir, const nlohmann::json& gains,
                                std::size_t scenarios,
                                const std::vector<std::string>& parameter_order = {});

// Whether the difference between points a and b is noise, not a trade-off: the run says so
// (one's within_noise_of names the other), or on every soft goal |u - v| <= max(f_u·|u|, f_v·|v|)
// with each point's own noise floor f (one not measured does not count; neither measured: not
// noise), the rule of the run's within_noise_of (ftc/tune/run/front.hpp), for any two points.
bool within_noise(const Front& front, std::size_t a, std::size_t b);

// Writes figures/front.gp (the pairwise scatter and the hypervolume over the iterations of
// RUN/history.csv) and runs it.
std::vector<Figure> draw_front_figures(const std::filesystem::path& run_dir, const Front& front,
                                       FigureFormat format);

}  // namespace ftc::tune::report_detail
