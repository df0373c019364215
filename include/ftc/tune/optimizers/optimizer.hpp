#pragma once
// The optimiser seam. An optimiser maximises fitness over a box (SearchSpace), one generation at a
// time: initialize() evaluates the first population (iteration 0), iterate() one further
// generation. It sees the problem only as BatchFitness, the fitness (larger is better) of a batch
// of decision vectors by index, so how a batch is simulated (threads, SIMD lanes, other machines)
// is none of its business. All random numbers are drawn on the calling thread in a fixed order,
// so a run is determined by its settings and seed.
//
// Algorithms are registered by name (algorithms()): each owns its settings struct, their
// validation and JSON form, and the extra columns of its history rows. To add one, see
// tuner/optimizers/registry.cpp.
#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ftc/runtime/schema.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/tune/optimizers/rng.hpp"
#include "ftc/tune/optimizers/search_space.hpp"

namespace ftc::tune {

// What an optimiser of a Pareto front sees of one candidate (issue 26), as pagmo's problems give
// a multi-objective fitness: the values of the job's soft goals in the job's order, every one
// minimised (+inf where the candidate could not be evaluated or a goal is undefined), and the
// total normalised violation of its hard goals (0: feasible; +inf for a candidate that could not
// run under limits).
struct ObjectiveVector {
  std::vector<double> values;
  double violation = 0.0;
  bool feasible() const { return !(violation > 0); }
};

// What a front optimiser does with one candidate's objective vector F, as a rule on lower bounds
// (issue 42): its bat moves to it (may_move, and `bat` does not dominate F), and it is offered
// to an archive, which it enters unless it is infeasible or some point of `archive` dominates
// it. stops(L) says that neither can happen for any F at least L: then F's exact value changes
// no decision. Both tests are monotone: a point dominating L dominates every F at least L, and
// an infeasible L has an infeasible F. An archive point that left the archive since is dominated
// by one still in it (dominance is transitive), so the optimiser may pass the archive as it was
// when the batch began, as long as nothing else (a capacity limit) takes points out of it.
struct FrontCap {
  bool may_move = true;
  ObjectiveVector bat;                                          // read when may_move
  std::shared_ptr<const std::vector<ObjectiveVector>> archive;  // none: every candidate enters
  bool stops(const ObjectiveVector& lower) const;  // under pareto::dominates (pareto_bat.hpp)
};

// What an optimiser needs from the outside world: one fitness per decision vector, in order; a
// candidate that cannot be evaluated gets 0. Never throws for a candidate.
class BatchFitness {
 public:
  virtual ~BatchFitness() = default;
  virtual std::vector<double> operator()(const std::vector<Decision>& batch) = 0;
  // run_optimizer says which iteration the evaluations that follow belong to (0: the initial
  // population), for fitness functions that keep a record of every trial.
  virtual void begin_iteration(int /*iteration*/) {}
  // Capping (issue 27): the same batch, where the optimiser decides the same for every fitness
  // of candidate i below caps[i] (-inf: no cap, the candidate's value is needed). A fitness
  // function may stop evaluating a candidate once its fitness is known to lie below its cap and
  // return an upper bound on it that is below the cap instead. The default evaluates all.
  virtual std::vector<double> evaluate_capped(const std::vector<Decision>& batch,
                                              const std::vector<double>& /*caps*/) {
    return (*this)(batch);
  }

  // The multi-objective side of the seam. objectives() is the number of soft goals whose front is
  // searched: 0 for a problem of one objective, which has only the fitness above; >= 2 otherwise.
  virtual std::size_t objectives() const { return 0; }
  // The objective vectors of a batch, one per decision vector in order, each of objectives()
  // values. It evaluates the batch just as operator() does (same simulations, same record of
  // trials): an optimiser calls one or the other for a batch, never both. Never throws for a
  // candidate; std::logic_error when the problem has no front (objectives() < 2).
  virtual std::vector<ObjectiveVector> objective_vectors(const std::vector<Decision>& /*batch*/) {
    throw std::logic_error("this problem has one objective: it has no objective vectors");
  }
  // Capping of a front (issue 42): the same batch, where the optimiser decides the same for every
  // objective vector of candidate i that caps[i].stops() on (FrontCap). A fitness function may
  // stop evaluating a candidate once lower bounds L of its objective vector (every value and the
  // violation at most the candidate's) satisfy caps[i].stops(L), and return a vector that is at
  // least L instead. The default evaluates all.
  virtual std::vector<ObjectiveVector> objective_vectors_capped(
      const std::vector<Decision>& batch, const std::vector<FrontCap>& /*caps*/) {
    return objective_vectors(batch);
  }
};

// The cap that asks for a candidate's value.
inline constexpr double kNoCap = -std::numeric_limits<double>::infinity();

// A plain function of one decision vector, evaluated on the calling thread (tests, small
// problems, embedding).
class FunctionFitness final : public BatchFitness {
 public:
  explicit FunctionFitness(std::function<double(const Decision&)> f) : f_(std::move(f)) {}
  std::vector<double> operator()(const std::vector<Decision>& batch) override {
    std::vector<double> out;
    out.reserve(batch.size());
    for (const Decision& x : batch) out.push_back(f_(x));
    return out;
  }

 private:
  std::function<double(const Decision&)> f_;
};

// A function of one decision vector to its objective vector, evaluated on the calling thread
// (tests, small problems): a problem of `objectives` (>= 2) soft goals. Its scalar fitness, for
// an optimiser of one objective, is constrained_fitness(1/values[0], violation).
class FunctionObjectives final : public BatchFitness {
 public:
  FunctionObjectives(std::size_t objectives, std::function<ObjectiveVector(const Decision&)> f)
      : n_(objectives), f_(std::move(f)) {}
  std::size_t objectives() const override { return n_; }
  std::vector<ObjectiveVector> objective_vectors(const std::vector<Decision>& batch) override {
    std::vector<ObjectiveVector> out;
    out.reserve(batch.size());
    for (const Decision& x : batch) out.push_back(f_(x));
    return out;
  }
  std::vector<double> operator()(const std::vector<Decision>& batch) override;

 private:
  std::size_t n_;
  std::function<ObjectiveVector(const Decision&)> f_;
};

// The constraint rule of a job with hard goals (issue 26), as the one fitness every optimiser
// compares: a feasible candidate (total normalised violation V = 0) keeps its J = 1/objective
// >= 0; an infeasible one gets -V/(1 + V) in [-1, 0) (-1 for V = +inf). So any feasible
// candidate beats any infeasible one, and between infeasible ones less V wins, strictly while
// the violations differ by more than rounding (up to V ~ 1e7), for every optimiser that
// maximises J. Finite, so that checkpoints and pagmo keep it exactly.
inline double constrained_fitness(double fitness, double violation) {
  if (!(violation > 0)) return fitness;
  if (!(violation <= std::numeric_limits<double>::max())) return -1.0;
  return -(violation / (1.0 + violation));
}

struct HistoryRow {
  int iteration = 0;             // 0 = the initial population
  double best_fitness = 0.0;     // J(x*) after this iteration
  Decision best;                 // x*
  std::int64_t evaluations = 0;  // so far
  // The algorithm's own figures, named (the Bat algorithm's mean loudness and pulse rate).
  std::vector<std::pair<std::string, double>> extras;
};

struct OptimizationResult {
  Decision best;
  double best_fitness = 0.0;
  std::vector<HistoryRow> history;
  std::int64_t evaluations = 0;
  bool completed = false;  // false when the observer stopped the run early
};

class Optimizer {
 public:
  virtual ~Optimizer() = default;
  virtual void initialize(BatchFitness& fitness) = 0;
  virtual void iterate(BatchFitness& fitness) = 0;
  virtual int iteration() const = 0;   // completed iterations (0 after initialize)
  virtual int iterations() const = 0;  // T
  virtual const std::vector<HistoryRow>& history() const = 0;

  // The complete state after the last iteration, random-number engine included, as JSON with
  // exact (round-trip) doubles. restore() continues from it exactly as if never interrupted, and
  // throws InputError for a state of another algorithm or a damaged one.
  virtual nlohmann::json state() const = 0;
  virtual void restore(const nlohmann::json& state) = 0;
};

class AlgorithmSettings;
using AlgorithmPtr = std::shared_ptr<const AlgorithmSettings>;

// One algorithm's validated settings: immutable, shared by the copies of a job.
class AlgorithmSettings {
 public:
  virtual ~AlgorithmSettings() = default;
  virtual std::string type() const = 0;  // the job's tuning.algorithm.type
  // The resolved JSON form (every default filled in, "type" included); canonical.
  virtual nlohmann::json to_json() const = 0;
  virtual int population() const = 0;            // candidates per generation
  virtual int iterations() const = 0;            // generations after the initial one
  virtual std::int64_t evaluations() const = 0;  // the run's budget of candidate evaluations
  // The names of the extra history columns (HistoryRow::extras), in order.
  virtual std::vector<std::string> history_columns() const { return {}; }
  // Every bad setting, each named `path`/<setting> (settings built in code, not read from JSON).
  virtual std::vector<FieldError> validate(const std::string& path) const = 0;
  virtual std::unique_ptr<Optimizer> make(std::uint64_t seed, const SearchSpace& space) const = 0;
  // Whether the algorithm searches for a Pareto front: a job with two or more soft goals needs
  // one (Job::validate refuses the others), and runs the optimiser make_front() gives.
  virtual bool searches_front() const { return false; }
  // What the settings need of a front of `objectives` soft goals, each problem at `path`/...
  // (MOEA/D's grid weights need a population of C(H + M - 1, M - 1)): Job::validate asks, so
  // that `validate` refuses what the run would.
  virtual std::vector<FieldError> validate_front(std::size_t /*objectives*/,
                                                 const std::string& /*path*/) const {
    return {};
  }
  // The optimiser of the front of `objectives` (>= 2) soft goals: it calls
  // BatchFitness::objective_vectors. Only when searches_front().
  virtual std::unique_ptr<Optimizer> make_front(std::uint64_t /*seed*/, const SearchSpace& /*space*/,
                                                std::size_t /*objectives*/) const {
    throw std::logic_error("algorithm " + type() + " does not search for a Pareto front");
  }
  // The same settings with as many iterations as `budget` evaluations pay for, the initial
  // population included (so that algorithms can be compared at equal cost); null when the budget
  // does not reach the end of the first iteration after the initial population.
  virtual AlgorithmPtr with_budget(std::int64_t budget) const = 0;
};

struct AlgorithmInfo {
  std::string type;         // "bat", "random", "pagmo"
  std::string description;  // one line, for help and the schema
  // Reads a tuning.algorithm object strictly (type included), appending every problem with its
  // JSON path; returns the settings with defaults filled in (null when unusable).
  std::function<AlgorithmPtr(const nlohmann::json& j, const std::string& path,
                             std::vector<FieldError>& errors)>
      parse;
  // JSON Schema (draft 2020-12) of such an object.
  std::function<nlohmann::json()> schema;
};

const std::vector<AlgorithmInfo>& algorithms();
const AlgorithmInfo* find_algorithm(std::string_view type);
// Parses a tuning.algorithm object by its "type" (default "bat"); problems go to `errors`.
AlgorithmPtr parse_algorithm(const nlohmann::json& j, const std::string& path,
                             std::vector<FieldError>& errors);
// The settings of an algorithm as a program gives them (the JSON form of a settings object);
// throws InputError naming every bad field.
AlgorithmPtr make_algorithm(const nlohmann::json& settings);

// The settings of an algorithm whose options are a plain struct S (with `population` and
// `iterations`) described by a schema::Object<S>; `make` builds its optimiser.
template <class S>
class StructSettings final : public AlgorithmSettings {
 public:
  using Make =
      std::function<std::unique_ptr<Optimizer>(const S&, std::uint64_t, const SearchSpace&)>;
  StructSettings(std::string type, S settings, std::shared_ptr<const schema::Object<S>> shape,
                 Make make, std::vector<std::string> columns)
      : type_(std::move(type)),
        s_(std::move(settings)),
        shape_(std::move(shape)),
        make_(std::move(make)),
        columns_(std::move(columns)) {}

  std::string type() const override { return type_; }
  nlohmann::json to_json() const override {
    nlohmann::json j = shape_->write(s_);
    j["type"] = type_;
    return j;
  }
  int population() const override { return s_.population; }
  int iterations() const override { return s_.iterations; }
  std::int64_t evaluations() const override {
    return static_cast<std::int64_t>(s_.population) * (s_.iterations + 1);
  }
  std::vector<std::string> history_columns() const override { return columns_; }
  std::vector<FieldError> validate(const std::string& path) const override {
    std::vector<FieldError> errs;
    shape_->validate(s_, path, errs);
    return errs;
  }
  std::unique_ptr<Optimizer> make(std::uint64_t seed, const SearchSpace& space) const override {
    return make_(s_, seed, space);
  }
  AlgorithmPtr with_budget(std::int64_t budget) const override {
    const std::int64_t generations = budget / std::max(1, s_.population);
    if (generations < 2) return nullptr;
    S s = s_;
    s.iterations =
        static_cast<int>(std::min<std::int64_t>(generations - 1, std::numeric_limits<int>::max()));
    return std::make_shared<StructSettings<S>>(type_, std::move(s), shape_, make_, columns_);
  }
  const S& settings() const { return s_; }

 private:
  std::string type_;
  S s_;
  std::shared_ptr<const schema::Object<S>> shape_;
  Make make_;
  std::vector<std::string> columns_;
};

// The registry entry of such an algorithm.
template <class S>
AlgorithmInfo struct_algorithm(std::string type, std::string description,
                               std::shared_ptr<const schema::Object<S>> shape,
                               typename StructSettings<S>::Make make,
                               std::vector<std::string> columns = {}) {
  AlgorithmInfo info;
  info.type = type;
  info.description = description;
  info.parse = [type, shape, make, columns](const nlohmann::json& j, const std::string& path,
                                            std::vector<FieldError>& errs) -> AlgorithmPtr {
    S s;
    std::vector<FieldError> mine;
    shape->read_object(j, path, s, mine, {"type"});
    std::vector<FieldError> range;
    shape->validate(s, path, range);
    schema::detail::dedupe_append(mine, std::move(range));
    const bool ok = mine.empty();
    errs.insert(errs.end(), mine.begin(), mine.end());
    if (!ok) return nullptr;
    return std::make_shared<StructSettings<S>>(type, std::move(s), shape, make, columns);
  };
  info.schema = [type, description, shape] {
    nlohmann::json s = shape->object_schema({{"type", {{"const", type}}}}, {"type"});
    s["description"] = description;
    return s;
  };
  return info;
}

// The optimiser of a front for an algorithm registered for one objective: given the algorithm's
// parsed settings (of the registry entry it wraps), the seed, the space and the number of soft
// goals (>= 2).
using MakeFront = std::function<std::unique_ptr<Optimizer>(
    const AlgorithmSettings& settings, std::uint64_t seed, const SearchSpace& space,
    std::size_t objectives)>;
// The registry entry `info` whose settings also search for fronts, with `make_front`: parsing,
// validation, the JSON form, budgets and make() are info's own, unchanged.
AlgorithmInfo with_front(AlgorithmInfo info, MakeFront make_front);

// Called after every iteration (including 0); returning false stops the run. The optimizer is
// passed so that a caller can checkpoint its state().
using IterationObserver = std::function<bool(const HistoryRow&, const Optimizer&)>;

// Where an optimiser stands: its best, history and whether it ran every iteration.
OptimizationResult optimization_result(const Optimizer& optimizer);

// Runs to the last iteration or until the observer says stop. With `resume` (a state() saved
// earlier) it continues from there instead of initialising.
// A state that restore() refuses is an InputError with source "checkpoint" and the field's
// path, `state_path` (where the state sits in its document) in front.
OptimizationResult run_optimizer(Optimizer& optimizer, BatchFitness& fitness,
                                 const IterationObserver& observer = {},
                                 const nlohmann::json* resume = nullptr,
                                 const std::string& state_path = "");

// What the population optimisers here have in common: the search space, random engine,
// iteration and evaluation counters, the best point and the history, and the checkpoint of all
// that. A subclass adds its own population state to state() and restore().
class GenerationalOptimizer : public Optimizer {
 public:
  int iteration() const override { return t_; }
  int iterations() const override { return iterations_; }
  const std::vector<HistoryRow>& history() const override { return history_; }

 protected:
  GenerationalOptimizer(int iterations, std::uint64_t seed, const SearchSpace& space)
      : iterations_(iterations), space_(space), rng_(seed) {}

  // Evaluates a batch and counts it; throws std::logic_error when the fitness is of the wrong
  // size (a broken evaluator, not bad input).
  std::vector<double> evaluate(BatchFitness& fitness, const std::vector<Decision>& batch);
  // The same with a cap per candidate (BatchFitness::evaluate_capped).
  std::vector<double> evaluate(BatchFitness& fitness, const std::vector<Decision>& batch,
                               const std::vector<double>& caps);
  // The same for an optimiser of a front: the batch's objective vectors, each of
  // fitness.objectives() values.
  std::vector<ObjectiveVector> evaluate_objectives(BatchFitness& fitness,
                                                   const std::vector<Decision>& batch);
  // The same with a rule per candidate (BatchFitness::objective_vectors_capped).
  std::vector<ObjectiveVector> evaluate_objectives(BatchFitness& fitness,
                                                   const std::vector<Decision>& batch,
                                                   const std::vector<FrontCap>& caps);
  // Appends the history row of iteration t_ with the algorithm's extra figures.
  void record(std::vector<std::pair<std::string, double>> extras = {});
  // The common part of a checkpoint, tagged with the algorithm's name, and its inverse (which
  // refuses another algorithm's checkpoint).
  // restore_common checks every field (state_check.hpp): t within 0..T, the evaluations
  // `per_generation` × (t + 1) (when 0: at most `max_evaluations`), a sound engine state, one
  // history row per iteration, every point of the space's dimension (inside its bounds when
  // `bounded`). The state changes only when all of it is sound.
  nlohmann::json common_state(const char* algorithm) const;
  void restore_common(const nlohmann::json& state, const char* algorithm,
                      std::int64_t per_generation, std::int64_t max_evaluations, bool bounded);

  int iterations_;
  SearchSpace space_;
  Rng rng_;
  Decision best_;
  double best_fitness_ = 0.0;
  int t_ = -1;
  std::int64_t evaluations_ = 0;
  std::vector<HistoryRow> history_;
};

}  // namespace ftc::tune
