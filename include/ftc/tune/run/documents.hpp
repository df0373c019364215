#pragma once
// The files a tuning run writes (the CLI and the service write exactly these bytes): the gains
// file, the history, the comparison of controllers and their trajectories, and the metrics of a
// single simulation (`ftctune simulate`).
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "ftc/sim/metrics.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/tune/run/tuning_run.hpp"

namespace ftc::tune {

inline constexpr const char* kGainsSchema = "ftctune.gains/1";

// A metric measured as `measure` says, in words: `metric` as the caller words it, its window when
// `windowed`, and over n > 1 scenarios the aggregate ("CVaR0.9 of ISE[first fault, +8 s] over 101
// scenarios"). The one wording of the objective's, the goals' and the front's labels.
std::string measure_label(std::size_t n, const std::string& metric, const ObjectiveConfig& measure,
                          bool windowed);
// What the objective's value is, in words: the metric's label, the window and the aggregate, e.g.
// "CVaR0.9 of ISE[first fault, +8 s] over 101 scenarios" or "ISE[0 s, 30 s]" (one scenario).
// Every place that shows the value labels it with this (run's summary, comparison.md,
// report.html, the figures).
std::string objective_label(const Job& job);
// What a run's fitness J measures, in words, so that only values of the same measure are set side
// by side (the service's jobs list groups by it): objective_label without goals; with goals, the
// one soft goal's measure (its hard goals constrain which J are feasible, not what J is); with two
// or more soft goals, "front of " and each soft goal's measure, joined by " and ".
std::string fitness_label(const Job& job);
// Goal k of the job in words, as comparison.md's goals table heads it: measure_label with the
// metric's name in capitals, its window when it has one, the aggregate over several scenarios
// (`scenarios` of them, default the job's), then "minimized" or "<= limit".
std::string goal_label(const Job& job, std::size_t k, std::size_t scenarios = 0);
// A candidate's goals as gains.json, comparison.json and evaluation.json give them: "goals" (each
// goal of the job with its "value" and, for a hard goal, its "violation"), "total_violation" and
// "feasible". `values` in the job's goal order (missing ones are NaN).
nlohmann::json goals_json(const Job& job, const std::vector<double>& values, double violation);

// The file of a compared controller's trajectory, relative to the run directory.
std::string trajectory_file(const TuningOutcome& r, std::size_t controller, std::size_t scenario);

// gains.json. Of an outcome without a comparison (a running job's best so far, as the service
// serves it): the best's objective, fitness and goals as its trial recorded them, the baseline's
// controller without a score (null), no noise floor, and kStoredBestWarning among the warnings;
// optimizer.completed is false then, so the gains loader refuses the file.
nlohmann::json gains_document(const TuningOutcome& r);
inline constexpr const char* kStoredBestWarning =
    "the run has not finished: these are the best gains of its iterations so far, with the values "
    "its trials recorded; the comparison with the job's own controller and the noise floor are "
    "made when it finishes";
std::string history_csv(const TuningOutcome& r);
// trials.csv: one row per evaluated candidate: iteration, index, the tuned parameters, objective,
// fitness, diverged (scenarios), accepted (became the best so far), and per listed scenario its
// objective (a job with an ensemble lists only the aggregate: `ftctune simulate --set` gives any
// candidate's members).
std::string trials_csv(const TuningOutcome& r);
nlohmann::json comparison_document(const TuningOutcome& r);
std::string comparison_markdown(const TuningOutcome& r);

// CSV of a recorded trajectory: time, x1..x2n, ud1..udm (commanded), u1..um (applied).
std::string trajectory_csv(const sim::Trajectory& trajectory);
// Metrics of one scenario as written to metrics.json and comparison.json; ise/iae/itae in the
// objective window, infinite values as null.
nlohmann::json metrics_json(const sim::Metrics& m);
// comparison.md's table of one scenario: a row per (label, metrics), the columns of the metrics
// record (ftc/sim/metrics_record.hpp), values as format_number writes them.
std::string metrics_markdown_table(
    const std::vector<std::pair<std::string, const sim::Metrics*>>& rows);
// A controller's summary over many scenarios (SPEC §15's aggregates, with the counts).
nlohmann::json summary_json(const Summary& s);
// A label as a file name: lower-case letters and digits, other runs of characters as one '-'.
std::string label_slug(const std::string& label);

// The result files of a completed run, path → content: gains.json, history.csv, job.json
// (the resolved job), comparison.json, comparison.md and trajectories/<scenario>/<NN>-<label>.csv
// (one per compared controller, listed in comparison.json).
std::map<std::string, std::string> output_files(const TuningOutcome& r);
// The run.json fields both `ftctune run` and the service write: threads, wall seconds,
// simulations, peak memory of the process, seed, generator. Callers add where and when.
nlohmann::json run_metadata(const TuningOutcome& r, double wall_seconds);
// What `ftctune run` prints at the end of a run, from its documents (gains.json,
// comparison.json, run.json): the tuned values in the job's order (the controller table's), the
// objective against the job's own controller's, the scenarios, the noise floor and the cost.
// `submit --wait` prints the same for a run of the service (`where`: " on the server").
std::string run_summary(const nlohmann::json& gains, const nlohmann::json& comparison,
                        const nlohmann::json& run, const std::string& where = "");

// Writes output_files() into `dir`, each atomically, gains.json last (so a directory with a
// gains.json holds the rest of its run); returns their names in the order written.
std::vector<std::string> write_outputs(const TuningOutcome& r, const std::filesystem::path& dir);
// The same for files output_files() has already rendered.
std::vector<std::string> write_output_files(const std::map<std::string, std::string>& files,
                                            const std::filesystem::path& dir);

}  // namespace ftc::tune
