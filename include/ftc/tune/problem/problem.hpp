#pragma once
// A job as a tuning problem (SPEC §6): the decision vector names values of the controller fields
// listed under tuning.parameters; a candidate is simulated on every scenario of the job and
// scored by the job's objective, the metric in the window aggregated over the scenarios;
// fitness J = 1/objective, and J = 0 when a scenario diverged. The problem owns all of that:
// it holds its plant and its held scenarios (the listed ones), with their simulation options,
// as a SimulationSet, generates its ensemble's members when a block of tasks needs them (SPEC
// §12: member k depends on k and the seed only) and drops them after, builds the tasks and
// scores their results; evaluators only run the tasks, optimisers only see fitness. So a
// problem holds a few numbers per member (which scenarios count, and per candidate being
// scored its values), never the members themselves: memory by design (issue 29).
//
// Copyable (copies share the immutable plant) and immutable after construction, so any number
// of threads may simulate and score at once.
//
// For use inside another optimiser, objective(x) is the one call: the objective of the
// controller with the tuned fields set from x, simulated on the calling thread.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/metrics.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/tune/evaluators/batch_evaluator.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/optimizers/optimizer.hpp"
#include "ftc/tune/optimizers/search_space.hpp"

namespace ftc::tune {

// A candidate's score.
struct Evaluation {
  // The metrics of each held scenario (TuningProblem::held_scenarios(): the listed ones, or
  // every one of a problem given its scenarios), in order; empty when the caller did not ask to
  // keep them (TuningProblem::evaluate's keep_metrics).
  std::vector<sim::Metrics> scenarios;
  // The job's metric on every scenario (listed, then members), +inf for a diverged run: what
  // the summaries and the capping order read, 8 bytes a member.
  std::vector<double> values;
  double objective = 0.0;    // the aggregate; +inf when it takes a diverged run
  double fitness = 0.0;      // 1/objective; 0 when the objective is +inf
  bool diverged = false;     // some scenario diverged
  int diverged_count = 0;    // how many (counted or not)
  int diverged_counted = 0;  // how many of the counted ones
  // A job with goals: each goal's aggregate, in the job's order, and the total normalised
  // violation of its hard goals (fitness is then constrained_fitness(1/objective, violation)).
  std::vector<double> goals;
  double violation = 0.0;
  bool feasible() const { return !(violation > 0); }
  // Capping (issue 27): a candidate whose lower bound passed its cap before every scenario ran.
  // Its objective is then that lower bound (the objective is at least this), its fitness
  // fitness_upper_bound() of its bounds (the fitness is at most this), its diverged count that of
  // the scenarios that ran; `scenarios` and `values` are empty, and `goals` and `violation` of a
  // job with goals are lower bounds (a goal without one NaN).
  bool capped = false;
  std::size_t simulated = 0;  // scenarios simulated (all of them unless capped)
};

// A candidate over many scenarios at a glance (SPEC §15's aggregates): the job's metric over the
// counted scenarios, quantiles by nearest rank, cvar with the job's alpha (0.9 when it
// aggregates otherwise); +inf for a diverged run.
struct Summary {
  int scenarios = 0, counted = 0, unrecoverable = 0, diverged = 0;
  double mean = 0, median = 0, p90 = 0, p99 = 0, max = 0, cvar = 0;
  double objective = 0;  // the job's own aggregate
};
// A goal's value over the counted scenarios' values of its metric: its aggregate, the scenarios
// where the metric is undefined (NaN) left out; NaN when it is undefined on all of them (which no
// limit accepts). TuningProblem::score and `ftctune evaluate` aggregate with this.
double aggregate_goal(const GoalConfig& goal, std::vector<double> values);

// The summary of the counted values of a metric (+inf for a diverged run) under the job's
// objective; the caller fills in the counts of scenarios, unrecoverable and diverged ones.
Summary summarize_values(const ObjectiveConfig& objective, std::vector<double> counted);

// A candidate's score with what else its simulations gave.
struct CandidateOutcome {
  Evaluation evaluation;
  std::string error;  // non-empty when a simulation could not run (fitness is then 0)
  std::vector<sim::Trajectory> trajectories;  // per scenario, when recorded
  // Beside each recorded trajectory: whether that run left its model's validity (rigid_body's
  // Euler angles past ±85°); absent for a plant whose model holds everywhere.
  std::vector<std::optional<bool>> model_invalid;
};

double fitness_of(double objective);  // 1/objective; 0 for inf/NaN; +inf for 0

// Capping (issue 27): a lower bound of objective.aggregate_of(values) when only the values with
// known[i] are known, the others being any numbers >= 0 (every metric an objective takes is, and
// +inf for a diverged run): the aggregate of the values with each unknown one as 0. Every
// aggregate (mean in the given order, max, nearest-rank quantile, CVaR) grows with each value,
// and so do their sums and picks in floating point, which rounds monotonically; so the bound is
// at most the aggregate computed with the values known, to the last bit.
double aggregate_lower_bound(const ObjectiveConfig& objective, std::vector<double> values,
                             const std::vector<bool>& known);

// Capping with goals (issue 27): whether a goal's aggregate has a lower bound while members are
// unknown. Its metric must be defined (not NaN) on every member, so that the aggregate is over a
// count fixed in advance and aggregate_lower_bound() applies: the metrics record marks such a
// field `partial_lower_bound` (>= 0, +inf for a diverged run). A metric that is NaN on some
// members (no sample, no fault, no tail) unless the member diverges (+inf) leaves how many values
// the aggregate takes unknown until every member ran: such a goal contributes nothing to the
// bound.
bool goal_has_lower_bound(const GoalConfig& goal);

// Capping with goals: an upper bound of the constrained fitness (constrained_fitness) of a
// candidate whose objective is at least `objective` and whose hard goals' total violation is at
// least `violation` (both lower bounds, as aggregate_lower_bound gives them). Without violation:
// fitness_of(objective), which bounds a feasible candidate's 1/objective and exceeds every
// infeasible one's J < 0. With violation V > 0 the candidate is infeasible, J = -V'/(1 + V') for
// its true V' >= V; since V/(1 + V) rounds to within 2 ulp either way of the exact ratio, which
// grows with V (the rounded one does not always), the bound is -(V/(1 + V))·(1 - 2^-50), above
// every such J by a few ulp: a candidate within them of its cap is never capped. -1 (exact) for
// V = +inf.
double fitness_upper_bound(double objective, double violation);

// The order in which capping runs a candidate's scenarios: the counted ones hardest first by
// the values `reference` (one per scenario, e.g. the incumbent's; NaN as +inf) has on them,
// ties by index, then those not counted in index order. An empty reference: index order.
std::vector<std::size_t> hardest_first(std::span<const double> reference,
                                       const std::vector<bool>& counted);

// The scenarios of a capping round: each candidate still running gets a block of
// max(kCapBlock, ⌈kCapRoundTasks / running⌉) scenarios (so that a round keeps the threads and
// lanes busy), but at most ⌈S/4⌉ of its S (so that it is looked at at least four times). Fixed
// rules of the results only, so that where a candidate stops depends on no thread count, rank
// count or lane width.
inline constexpr std::size_t kCapBlock = 4;
inline constexpr std::size_t kCapRoundTasks = 64;
std::size_t capping_block(std::size_t scenarios, std::size_t running);

struct ObjectiveOptions {
  // What a diverged candidate's objective is: +inf when unset; an optimiser that cannot handle
  // infinities can ask for a large finite penalty (e.g. 1e30) instead.
  std::optional<double> diverged_penalty;
};

class TuningProblem {
 public:
  // Throws InputError when the job does not validate. A job without a tuning section is a
  // problem of dimension 0 (its own controller only: simulate, compare). The job's ensemble's
  // members follow its listed scenarios; each is generated here once, on the calling thread, to
  // be validated and classified (recoverable, counted), and again whenever it is simulated.
  explicit TuningProblem(Job job);
  // The same with these scenarios, all held, in place of the listed ones and the ensemble's
  // members (the ensemble's unrecoverable policy still applies): a slice of a large evaluation.
  TuningProblem(Job job, std::vector<sim::Scenario> scenarios, std::size_t listed);

  const Job& job() const { return *job_; }
  // Tells problems apart without comparing them: copies share it, every other problem (a
  // perturbed() one included) has its own. It is the identity of the problem's held set.
  std::uint64_t identity() const { return set_->identity(); }
  const sim::AnyPlant& plant() const { return set_->plant(); }
  // The search space in search coordinates: ln x for a parameter on a log scale, x otherwise.
  const SearchSpace& space() const { return space_; }

  // The scenarios: the job's listed ones, then its ensemble's members.
  std::size_t scenarios() const { return set_->size() + members_; }
  std::size_t listed_scenarios() const { return listed_; }
  // The scenarios the problem holds (the first ones); the others, its ensemble's members, it
  // generates when they are simulated.
  std::size_t held_scenarios() const { return set_->size(); }
  // Scenario i: a held one's copy, or the member generated (and perturbed) as it is simulated.
  sim::Scenario scenario(std::size_t i) const;
  // Whether gains can control the scenario once its faults have started (SPEC §12), and
  // whether it counts in the objective (unrecoverable ones are left out unless the ensemble
  // says include).
  bool recoverable(std::size_t i) const { return recoverable_[i]; }
  bool counted(std::size_t i) const { return counted_[i]; }
  int unrecoverable() const;  // how many scenarios are not recoverable
  int left_out() const;       // how many of them the objective leaves out

  // Parameter values from search coordinates (exp for log-scale ones, kept inside the bounds).
  Decision to_parameters(std::span<const double> y) const;
  // The job's controller with the tuned fields set from search coordinates y.
  sim::ControllerConfig controller_for(std::span<const double> y) const;
  // The job's controller with the tuned fields set to the values x (in space().names order).
  sim::ControllerConfig controller_with(std::span<const double> x) const;
  // The simulation options of a scenario: the objective window and the fault segments (before
  // the first onset, between onsets, after the last) as extra windows.
  sim::SimulationOptions simulation_options(std::size_t scenario,
                                            std::int64_t record_every = 0) const;
  // One scenario with one controller. Throws InputError for an invalid controller; a diverging
  // run is a result.
  sim::SimulationResult simulate(const sim::ControllerConfig& controller, std::size_t scenario,
                                 std::int64_t record_every = 0) const;

  // A goal's value on one scenario's metrics: the metric in the goal's window (which
  // simulation_options() asks for) or over the whole run; NaN where it is undefined (no fault).
  double goal_value(const GoalConfig& goal, const sim::Metrics& m, std::size_t scenario) const;
  // A candidate's score from its metrics on every scenario.
  Evaluation score(std::vector<sim::Metrics> per_scenario) const;
  Summary summarize(const Evaluation& e) const;
  // Simulates and scores controllers through an evaluator, one outcome per controller. The
  // tasks run in blocks of scenarios (kBlockTasks tasks, at least kMinBlockScenarios
  // scenarios), each block's members generated for it; each result is the same bits however
  // the tasks are split. Without keep_metrics the evaluations' `scenarios` stay empty.
  std::vector<CandidateOutcome> evaluate(std::span<const sim::ControllerConfig> controllers,
                                         BatchEvaluator& evaluator, std::int64_t record_every = 0,
                                         bool keep_metrics = true) const;
  static constexpr std::size_t kBlockTasks = 8192;
  static constexpr std::size_t kMinBlockScenarios = 256;
  // The same with capping (issue 27): the candidates' scenarios run in rounds, each candidate's
  // in `order` (a permutation of the scenarios), and after each round a candidate with a cap
  // (> kNoCap) stops once the upper bound of its fitness is below the cap: its outcome is then
  // capped (Evaluation::capped). The bound is fitness_upper_bound() of its objective's lower
  // bound and, for a job with goals, the total violation of its hard goals' lower bounds
  // (goal_has_lower_bound; the others count 0); a candidate whose simulation failed has its
  // exact fitness. A capped candidate's goals are their lower bounds (NaN where the goal has
  // none), its violation theirs. A candidate that runs to the end has exactly evaluate()'s
  // outcome.
  // Every decision is taken here, on the calling thread, from results by task index, so the
  // outcome depends on no evaluator, thread count, rank count or lane width.
  std::vector<CandidateOutcome> evaluate_capped(std::span<const sim::ControllerConfig> controllers,
                                                std::span<const double> caps,
                                                std::span<const std::size_t> order,
                                                BatchEvaluator& evaluator) const;
  // What that knows of a candidate after a round: lower bounds of its objective, of its hard
  // goals' total violation and of each goal (NaN for a goal without one), and the upper bound of
  // its fitness they give.
  struct PartialBounds {
    double objective = 0, fitness = 0, violation = 0;
    const std::vector<double>& goals;
  };
  // Whether candidate c stops on these bounds.
  using StopRule = std::function<bool(std::size_t c, const PartialBounds&)>;
  // The same with a rule in place of a cap (a front's, issue 42): candidate c, when may_stop[c],
  // stops after a round once stop(c, its bounds) holds. The caps above are the rule
  // "fitness bound below caps[c]".
  std::vector<CandidateOutcome> evaluate_capped(std::span<const sim::ControllerConfig> controllers,
                                                const std::vector<bool>& may_stop,
                                                const StopRule& stop,
                                                std::span<const std::size_t> order,
                                                BatchEvaluator& evaluator) const;

  // The objective (minimised) of the parameter values x (natural units, in space().names
  // order), simulated on the calling thread. Throws InputError, before simulating anything,
  // when x has the wrong size, is not finite or lies outside the tuning bounds.
  double objective(std::span<const double> x, const ObjectiveOptions& options = {}) const;

  // A copy whose scenarios start from initial states multiplied component by component by
  // 1 + eps (2u - 1), u from the SPEC §12 stream of member k with the given seed, drawn in
  // scenario order then component order: the noise-floor probe of SPEC §14. (A generated
  // member takes its draws where the stream stands after the scenarios before it.)
  TuningProblem perturbed(std::uint64_t seed, std::uint64_t k, double eps) const;
  // Whether some scenario's controller reads sensors that are not exact (ftc/sim/sensors.hpp).
  bool has_sensors() const;
  // A copy whose scenarios' sensor noise streams have their seeds moved on by `shift` (a
  // generated member's too): the noise floor's other sensor seeds (SPEC §18).
  TuningProblem sensor_reseeded(std::uint64_t shift) const;

 private:
  // What a candidate's scoring holds while its tasks' results come in, by scenario index.
  struct Tally;
  // A tally of n scenarios keeping the metrics of the first `keep`.
  Tally new_tally(std::size_t keep, std::size_t n) const;
  // Takes the result of scenario s (simulated as `scenario`, which a job with goals needs for
  // their windows) into the tally.
  void take(Tally& t, std::size_t s, TaskResult&& r, const sim::Scenario* scenario) const;
  // The candidate's evaluation from a tally with every scenario in; a failed candidate's (an
  // error) goals get +inf, as no record holds the windows they read.
  Evaluation finish(Tally&& t) const;
  // The set the tasks run on: the held set when they name held scenarios only, else a set of
  // just the scenarios they name (members generated here), the tasks' indices made the set's.
  struct Block {
    std::shared_ptr<const SimulationSet> set;
    std::vector<SimulationTask> tasks;
  };
  Block block_set(std::vector<SimulationTask> tasks) const;
  sim::Scenario member(std::size_t i) const;  // scenario i >= held_scenarios(), generated

  // The noise-floor probe's nudges, in the order they were applied.
  struct Perturbation {
    std::uint64_t seed = 0, k = 0;
    double eps = 0;
    std::uint64_t held_draws = 0;  // the draws the held scenarios took
  };

  std::shared_ptr<const Job> job_;
  std::shared_ptr<const SimulationSet> set_;  // the held scenarios
  std::size_t members_ = 0;                   // generated ones after them
  std::uint64_t member_seed_ = 0;
  std::vector<Perturbation> perturbations_;
  std::uint64_t sensor_shift_ = 0;  // sensor_reseeded(): added to the members' sensor seeds
  std::vector<bool> recoverable_, counted_;
  std::size_t listed_ = 0;
  SearchSpace space_;
  std::vector<Scale> scales_;                            // one per coordinate
  std::vector<double sim::ControllerConfig::*> fields_;  // one per coordinate
};

// The number of soft goals of a job that searches for a Pareto front (two or more), else 0.
std::size_t front_objectives(const Job& job);
// A candidate's objective vector (BatchFitness::objective_vectors): its soft goals' values in the
// job's order, an undefined one (NaN) as +inf, and its hard goals' total violation.
ObjectiveVector objective_vector(const Job& job, const Evaluation& e);
// The optimiser a run of the problem uses: the algorithm's optimiser of fronts for a job with two
// or more soft goals (InputError when the algorithm has none), its usual one otherwise.
std::unique_ptr<Optimizer> make_optimizer(const TuningProblem& problem,
                                          const AlgorithmSettings& algorithm, std::uint64_t seed);

// One evaluated candidate, as trials.csv lists it.
struct Trial {
  int iteration = 0;     // of the optimiser (0: the initial population)
  int index = 0;         // in evaluation order within the iteration
  Decision parameters;   // in natural units, in space().names order
  double objective = 0;  // the job's aggregate
  double fitness = 0;
  int diverged = 0;                         // scenarios that diverged
  std::vector<double> scenario_objectives;  // per listed scenario (empty with an ensemble)
  bool accepted = false;                    // became the run's best so far when evaluated
  std::vector<double> goals;                // a job with goals: each goal's value
  double violation = 0;                     // and the hard goals' total normalised violation
  // Capping (issue 27): the candidate was stopped after `simulated` of its scenarios, because
  // its objective (at least `objective`, its lower bound then) could change no decision;
  // fitness is then an upper bound (fitness_upper_bound), scenario_objectives empty, and goals
  // and violation lower bounds (NaN for a goal without one).
  bool capped = false;
  std::size_t simulated = 0;  // only for a capped trial
  // The cache (issue 43): a candidate whose parameters have the same bits as an earlier trial's
  // is not simulated again; its row takes that trial's results, which simulating it would give
  // to the last bit (a trial's results are a function of its parameters). It is never accepted
  // (its fitness was already there to beat).
  bool cached = false;
};
// How many of the trials the cache served.
std::int64_t cached_trials(const std::vector<Trial>& trials);

// The problem as an optimiser sees it: the fitness of a batch of decision vectors, simulated
// through an evaluator. Counts the simulations it ran and keeps a record of every trial.
class ProblemFitness final : public BatchFitness {
 public:
  ProblemFitness(const TuningProblem& problem, BatchEvaluator& evaluator)
      : problem_(problem), evaluator_(evaluator) {}
  std::vector<double> operator()(const std::vector<Decision>& batch) override;
  // With capping on (the default), runs the candidates with caps through
  // TuningProblem::evaluate_capped, each one's scenarios hardest first for the incumbent (the
  // best trial so far, uncapped by construction) as it was when the batch began. A job of one
  // soft goal and hard goals is capped on the bounds of its goals. Capped trials are recorded
  // so.
  std::vector<double> evaluate_capped(const std::vector<Decision>& batch,
                                      const std::vector<double>& caps) override;
  // A job of a front (issue 42) is capped on its optimiser's rules (FrontCap): the Pareto Bat's
  // through objective_vectors_capped; an optimiser of one objective run on it (random search)
  // through the caps above, where a candidate also stops only if it cannot join the run's
  // front (of every uncapped trial so far): its violation's bound is above 0, or a point of
  // that front dominates its bounds; so front.json and the hypervolumes, built from every
  // uncapped trial, keep their bytes. Either way a front's candidate stops only if it cannot
  // be trials.csv's best so far.
  std::vector<ObjectiveVector> objective_vectors_capped(const std::vector<Decision>& batch,
                                                        const std::vector<FrontCap>& caps) override;
  void set_capping(bool on) { capping_ = on; }
  bool capping() const { return capping_; }
  // The cache (issue 43), on by default: a candidate whose parameter values have the same bits
  // as an earlier uncapped trial's takes that trial's results (Trial::cached), and candidates of
  // one batch with the same bits are simulated once. The optimiser gets the fitness it would
  // have got (a capped candidate's bound aside, which may stop elsewhere: no decision reads it),
  // so the gains, history, front and optimiser states are the same bytes either way. With
  // capping, the duplicates of a batch are simulated once with the least of their caps: capped
  // then, each would have been. The cache is an index into the trials, which the run keeps
  // anyway: a few dozen bytes a distinct trial. Set before resume_trials(), which rebuilds it.
  void set_cache(bool on) { cache_ = on; }
  bool cache() const { return cache_; }
  std::int64_t cached() const { return cached_trials(trials_); }  // trials the cache served
  // A job with two or more soft goals: their values and the violation of its hard goals.
  std::size_t objectives() const override;
  std::vector<ObjectiveVector> objective_vectors(const std::vector<Decision>& batch) override;
  void begin_iteration(int iteration) override {
    iteration_ = iteration;
    index_ = 0;
  }
  std::int64_t simulations() const { return simulations_; }
  const std::vector<Trial>& trials() const { return trials_; }
  // Continues the record of a run resumed from a checkpoint: the trials before it come first,
  // and "best so far" counts them, as in the run that was interrupted.
  void resume_trials(std::vector<Trial> before);

 private:
  // The scenarios' order for capping: hardest first for the incumbent.
  std::vector<std::size_t> capping_order();
  // Simulates a batch with caps (scalar ones, or a front optimiser's rules) and records it.
  std::vector<double> run_capped(const std::vector<Decision>& batch,
                                 const std::vector<double>* caps,
                                 const std::vector<FrontCap>* front_caps,
                                 std::vector<ObjectiveVector>* vectors);
  // A job of a front: the run's front gains an uncapped trial's vector unless a member
  // dominates it or has its values.
  void offer_to_front(const ObjectiveVector& o);
  // Simulates and scores a batch, recording its trials: the fitness of each candidate, and its
  // objective vector appended to `vectors` when given.
  std::vector<double> run(const std::vector<Decision>& batch,
                          std::vector<ObjectiveVector>* vectors);

  const TuningProblem& problem_;
  BatchEvaluator& evaluator_;
  std::int64_t simulations_ = 0;
  int iteration_ = 0, index_ = 0;
  double best_ = -2.0;  // best fitness so far; J ≥ -1, so the first trial is accepted
  std::vector<Trial> trials_;
  bool capping_ = true;
  // The incumbent's value per scenario (the job's metric), for the order of capped runs; empty
  // until a trial is accepted (or, after a resume, until the incumbent is simulated again).
  std::vector<double> incumbent_;
  // Which candidates of a batch are simulated, and where the others take their results from.
  struct Served {
    std::vector<Decision> parameters;   // per candidate, in values
    std::vector<std::size_t> simulate;  // the candidates simulated, in batch order
    // Per candidate not simulated: the trial it copies, an index into trials_ as they will be
    // once the batch is recorded (candidate j of the batch is trials_[first + j]).
    std::vector<std::optional<std::size_t>> source;
    std::size_t first = 0;  // trials_.size() when the batch was served
  };
  Served serve(const std::vector<Decision>& batch) const;
  // Records a batch's trials: the simulated candidates' outcomes (in s.simulate order) and the
  // others' copies.
  std::vector<double> record(const Served& s, std::vector<CandidateOutcome> out,
                             std::vector<ObjectiveVector>* vectors = nullptr);
  void index_trial(std::size_t i);  // makes trials_[i] (uncapped) one the cache serves from

  // A job of a front: the non-dominated objective vectors of the feasible uncapped trials with
  // finite goals (one per distinct vector), shared with the caps of a batch.
  std::shared_ptr<const std::vector<ObjectiveVector>> front_ =
      std::make_shared<const std::vector<ObjectiveVector>>();
  bool cache_ = true;
  // Uncapped trials by a hash of their parameters' bits (trials_ indices; the first of equal
  // parameters only).
  std::unordered_multimap<std::uint64_t, std::size_t> by_parameters_;
};

}  // namespace ftc::tune
