#pragma once
// The Pareto front of a run with two or more soft goals (issue 26): the non-dominated feasible
// candidates among all the run's trials, whatever algorithm found them; its hypervolume; the
// point the run's gains file holds, and the rules `ftctune pick` chooses another by. The
// documents front.json and front.csv follow /work/s34/front-format.md (docs/usage.md).
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
// Two neighbouring points a and b of the front (in its order: by the first soft goal) are not a
// trade-off when on every soft goal |a - b| <= max(f_a·|a|, f_b·|b|), each point with its OWN
// floor f (a point without a floor on that goal does not count; neither with one: they are told
// apart). The later one is then flagged "within_noise_of" the first point of the run of such
// neighbours it ends (a chain a~b~c flags b and c with a's index, though c may be farther from a
// than its own floor: the chain is one design region, named by its first point). The flag is
// information only: flagged points stay in the front and its hypervolume, and every rule (the
// knee, min, limit, index) may pick one.
#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ftc/tune/job/job.hpp"
#include "ftc/tune/problem/problem.hpp"

namespace ftc::tune {

inline constexpr const char* kFrontSchema = "ftctune.front/1";
inline constexpr double kReferenceMarginDecades = 0.1;

struct FrontPoint {
  Decision parameters;        // natural units, in the space's order
  std::vector<double> goals;  // every goal's value, in the job's goal order
  double violation = 0.0;     // 0: on the front every point is feasible
  std::size_t trial = 0;      // row of trials.csv
  // Each goal's relative spread at this point under the noise-floor probe (none: undefined).
  std::vector<std::optional<double>> noise_floor;
  std::optional<std::size_t> within_noise_of;  // an earlier point it is not told apart from
};

struct Front {
  std::vector<std::size_t> soft;   // the soft goals' indices in the job's goals
  std::vector<FrontPoint> points;  // sorted by the first soft goal, ascending
  std::vector<double> reference;   // log10, one per soft goal
  double hypervolume = 0.0;
  std::size_t picked = 0;
  std::string rule = "knee";
};

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
// Records each point's noise floor (`spreads[i]`: point i's, per goal, relative) and flags the
// points within the noise floor of their predecessor (rule above).
void apply_noise_floor(Front& front,
                       const std::vector<std::vector<std::optional<double>>>& spreads);

// The sentence gains.json records as the rule that chose its point.
std::string front_rule_text(const Front& front);

// A rule of `ftctune pick`: knee | min:METRIC | limit:METRIC<=X | index:N. METRIC names a goal
// by its metric (the first goal of that metric). Returns the chosen point's index; InputError
// (source "pick", path "/rule") for a rule that names no goal or that no point meets.
std::size_t pick_point(const Job& job, const Front& front, const std::string& rule);

// front.json and front.csv of a run (front-format.md); `compared` is the comparison's part.
nlohmann::json front_document(const Job& job, const std::string& job_sha256, std::uint64_t seed,
                              const Front& front, const nlohmann::json& compared);
std::string front_csv(const Job& job, const Front& front);
// `ftctune pick`: the gains file of the point `rule` chooses on the front of the run in
// directory `run` (its job.json, front.json, gains.json and trials.csv), without simulating:
// the run's gains.json with that point's controller, tuned values, goals, objective and fitness
// (its trials.csv row), and the rule recorded under goals (rule, front). The run's noise floor is
// kept only when the point is the one it was measured at. InputError for a run without a front
// or a rule that picks nothing.
nlohmann::json pick_gains(const std::filesystem::path& run, const std::string& rule);

// The front back from front.json (InputError naming the field for a damaged one).
Front front_from_json(const Job& job, const nlohmann::json& j);

}  // namespace ftc::tune
