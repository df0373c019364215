#pragma once
// The Pareto front of a run with two or more soft goals (issue 26): the non-dominated feasible
// candidates among all the run's trials, whatever algorithm found them; its hypervolume; the
// point the run's gains file holds, and the rules `ftctune pick` chooses another by. One type for
// the run that makes it, the document it writes (front.json, front.csv: docs/usage.md, "Fronts")
// and every reader of that document (`ftctune pick`, report.html and its figures); the dashboard
// shows front.json as it is.
//
// Hypervolume: on log10 of each soft goal (values at or below 1e-300 count as 1e-300), against
// the reference point 0.1 decade beyond the worst value of each soft goal on the run's FINAL
// front. history.csv's per-iteration hypervolume (of the front of the trials up to that
// iteration) uses the same reference point, filled in after the run, so a resumed run gives the
// same bytes.
//
// Knee: with each soft goal's log10 normalised to [0, 1] over the front (0 its best point), the
// point farthest from the straight line through the two extremes of the first two soft goals
// (their best points); ties go to the smaller first goal. A front of one or two points: the
// first.
//
// Noise: every point of the front is re-evaluated on the R copies of the problem whose initial
// states are nudged (SPEC §14's noise floor, the same copies for every point, all points in one
// batch per copy); a goal's noise floor at a point is its relative spread over those runs,
// (max - min)/|value at the point|, none where that is undefined (a zero or non-finite value).
// Two points a and b of the front lie within the noise floor when on every soft goal
// |a - b| <= max(f_a·|a|, f_b·|b|), each point with its OWN floor f (a point without a floor on
// that goal does not count; neither with one: they are told apart). Of neighbouring points (in
// the front's order: by the first soft goal) the later one is flagged "within_noise_of" the first
// point of the run of such neighbours it ends (a chain a~b~c flags b and c with a's index, though
// c may be farther from a than its own floor: the chain is one design region, named by its first
// point). A point's "within_noise" partners are every other point it is no trade-off with: one
// whose within_noise_of names the other, or the two within the noise floor. This is the one rule
// (no_trade_off); report.html and the dashboard show the partners front.json lists. The flags are
// information only: flagged points stay in the front and its hypervolume, and every rule (the
// knee, min, limit, index) may pick one.
#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ftc/tune/job/job.hpp"
#include "ftc/tune/problem/problem.hpp"

namespace ftc::tune {

inline constexpr const char* kFrontSchema = "ftctune.front/1";
inline constexpr double kReferenceMarginDecades = 0.1;

// A goal of the job as the front shows it (front.json's goals carry the label and unit).
struct FrontGoal {
  std::string label;              // front_goal(): the metric's label, window and aggregate
  std::string unit;               // the metric's unit ("rad²·s", "command's unit")
  std::optional<double> at_most;  // a hard goal's limit; none: a soft goal
  bool soft() const { return !at_most; }
};

struct FrontPoint {
  Decision parameters;        // natural units, in the space's order
  std::vector<double> goals;  // every goal's value, in the job's goal order (+inf: diverged)
  double violation = 0.0;     // 0: on the front every point is feasible
  std::size_t trial = 0;      // row of trials.csv
  // Each goal's relative spread at this point under the noise-floor probe (none: undefined).
  std::vector<std::optional<double>> noise_floor;
  std::optional<std::size_t> within_noise_of;  // an earlier point it is not told apart from
  std::vector<std::size_t> within_noise;       // every point it is no trade-off with, ascending
  // A held-out front only (Front::held_out): the run's goal values of the point (`goals` are
  // the held-out ones), and whether the held-out values leave it off the front (infeasible, a
  // soft goal not finite, or dominated by another point's held-out values).
  std::vector<double> in_sample;
  bool dominated = false;
  // The label of the first feasible compared controller (Front::compared: a compare entry or the
  // job's own gains) whose soft goals dominate this point's: the point stays on the front (the
  // trials' front is the optimiser's), but a user gives up nothing by taking that controller
  // instead. None when no compared controller does.
  std::optional<std::string> dominated_by;
  bool feasible() const { return !(violation > 0); }
};

// Where a held-out front's values come from: `ftctune evaluate JOB --front RUN` simulates every
// point of RUN's front on the job's listed scenarios and its ensemble drawn with another seed.
struct FrontHeldOut {
  std::string run;          // the run directory whose front it is (its trials.csv, gains.json)
  std::uint64_t seed = 0;   // the held-out ensemble seed (0: a job without an ensemble)
  std::int64_t count = 0;   // held-out members
  double in_sample_hypervolume = 0.0;  // the run's
};

// A controller of the run's comparison other than the tuned one (a compare entry, or the job's
// own), with its goal values: the figures mark it beside the front.
struct FrontCompared {
  std::string label;
  std::string role;  // "compare" or "baseline" (the job's own controller)
  std::vector<double> goals;
  bool feasible = true;
};

struct Front {
  std::vector<FrontGoal> goals;    // one per goal of the job, in its order
  std::vector<std::size_t> soft;   // the soft goals' indices in the job's goals
  std::vector<FrontPoint> points;  // sorted by the first soft goal, ascending
  std::vector<double> reference;   // log10, one per soft goal
  double hypervolume = 0.0;
  std::size_t picked = 0;  // an index of points, unless there is none
  std::string rule = "knee";
  std::vector<FrontCompared> compared;
  // A held-out front: the run's points in the run's order (so an index names the same point in
  // both), each point's goals the held-out values; the hypervolume is of the points still on
  // the front, against the run's reference point, and the knee is picked among them.
  std::optional<FrontHeldOut> held_out;
};

// Goal k of the job as the front shows it: the metric's label in the metrics record, its window
// when it has one and, over several scenarios, the aggregate ("CVaR0.9 of ISE[first fault, +4 s]
// over 7 scenarios"); its unit without a leading "the " ("command's unit"); its limit.
FrontGoal front_goal(const Job& job, std::size_t k);

// The soft goals' log10 values of a goal vector (log_value of pareto_bat.hpp).
std::vector<double> log_soft_goals(const std::vector<double>& goals,
                                   const std::vector<std::size_t>& soft);
// Indices into `trials` (those of the first `count`) of the front: feasible, every soft goal
// finite, not dominated by another such trial; of trials with the same soft goals the first.
// Sorted by the first soft goal ascending (then the second, ..., then the trial index).
std::vector<std::size_t> front_trials(const Job& job, const std::vector<Trial>& trials,
                                      std::size_t count);
// The reference point of a front's log10 soft goals: each worst value + 0.1.
std::vector<double> reference_point(const std::vector<std::vector<double>>& log_points);
// The hypervolume of the front of the trials up to each iteration 0..last, against `reference`.
std::vector<double> hypervolume_history(const Job& job, const std::vector<Trial>& trials,
                                        const std::vector<double>& reference, int last);
// The front of a run's trials with its reference point and hypervolume, the knee picked.
Front make_front(const Job& job, const std::vector<Trial>& trials);
// Whether points a and b lie within the noise floor of one of them on every soft goal (rule
// above).
bool within_noise_floor(const Front& front, std::size_t a, std::size_t b);
// Whether points a and b are no trade-off: one's within_noise_of names the other, or they lie
// within the noise floor (the one rule, above).
bool no_trade_off(const Front& front, std::size_t a, std::size_t b);
// Records each point's noise floor (`spreads[i]`: point i's, per goal, relative), flags the
// points within the noise floor of their predecessor and lists each point's partners (rule
// above).
void apply_noise_floor(Front& front,
                       const std::vector<std::vector<std::optional<double>>>& spreads);
// Sets each point's dominated_by from front.compared (plain Pareto dominance on the soft goals:
// no worse on every one, better on one; an infeasible compared controller dominates nothing).
void mark_dominated_by_compared(Front& front);
// The warning gains.json carries when its point `i` is dominated by a compared controller ("" when
// it is not): "front point I is dominated by LABEL (...): ...", each soft goal's values and, where
// the controller is better, whether by more than the point's noise floor. is_dominated_warning
// tells such a warning among others (pick replaces the run's with its point's).
inline constexpr const char* kDominatedWarningPrefix = "front point ";
inline constexpr const char* kDominatedWarningVerb = " is dominated by ";
std::string dominated_warning(const Front& front, std::size_t i);
bool is_dominated_warning(std::string_view warning);

// The held-out front of a run's front: `goals[i]` are point i's goal values on the held-out
// scenarios; `compared` the job's compare entries and its own controller, held out alike.
Front held_out_front(const Job& job, Front run, FrontHeldOut where,
                     const std::vector<std::vector<double>>& goals,
                     std::vector<FrontCompared> compared);

// The sentence gains.json records as the rule that chose its point.
std::string front_rule_text(const Front& front);

// A rule of `ftctune pick`: knee | min:METRIC | limit:METRIC<=X | index:N. METRIC names a goal
// by its metric (the first goal of that metric). Returns the chosen point's index; InputError
// (source "pick", path "/rule") for a rule that names no goal or that no point meets. On a
// held-out front the knee, min and limit choose among the points not `dominated`.
std::size_t pick_point(const Job& job, const Front& front, const std::string& rule);

// front.json and front.csv of a run (docs/usage.md, "Fronts").
nlohmann::json front_document(const Job& job, const std::string& job_sha256, std::uint64_t seed,
                              const Front& front);
std::string front_csv(const Job& job, const Front& front);
// What `ftctune run` prints about a run's front (`out`: its directory): the number of points,
// the hypervolume, the point gains.json holds with its soft goals' values, and how to pick
// another; for an empty front, why it is empty. For a held-out front (`evaluate --front`): how
// many points stay on it, both hypervolumes, its knee's held-out and run values.
std::string front_summary(const Job& job, const Front& front, const std::filesystem::path& out);
// `ftctune pick`: the gains file of the point `rule` chooses on the front of the run in
// directory `run` (its job.json, front.json, gains.json and trials.csv), without simulating; or,
// for a directory holding a held-out front (`evaluate --front`), on the held-out values, with
// the gains from the run it names (its in-sample values checked against that run's trials.csv),
// the held-out values under goals.front.held_out, and a warning for each soft goal whose
// held-out value is worse than the in-sample one by more than the point's noise floor:
// the run's gains.json with that point's controller, tuned values, goals, objective and fitness
// (its trials.csv row), and the rule recorded under goals (rule, front). The run's noise floor is
// kept only when the point is the one it was measured at. InputError for a run without a front
// or a rule that picks nothing.
nlohmann::json pick_gains(const std::filesystem::path& run, const std::string& rule);

// The front back from front.json, the one reader of it: checked against the job (its goals and
// tuned parameters) and the format, an InputError (`source`, the JSON path) for a damaged one. A
// file written before the goals' label and unit and the points' within_noise partners (the same
// schema) is read with them made from the job by front_goal() and from its floors by the rule
// (no_trade_off), so it reads as the run would write it now.
Front front_from_json(const Job& job, const nlohmann::json& j,
                      const std::string& source = "front.json");
// RUN/front.json through front_from_json: none when there is no such file, or when `job_sha256`
// is given and the file's is another (a front left beside a re-run of another job); InputError
// naming the file when it cannot be read or is not JSON.
std::optional<Front> read_front(const std::filesystem::path& run, const Job& job,
                                const std::optional<std::string>& job_sha256 = std::nullopt);

}  // namespace ftc::tune
