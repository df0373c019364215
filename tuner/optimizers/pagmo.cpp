// The pagmo adapter (include/ftc/tune/optimizers/pagmo.hpp). Each supported algorithm is a
// settings struct described by a schema::Object (so job files are read strictly and the JSON
// Schema lists every setting), the rules its sizes must meet, and how to build the pagmo
// algorithm from it. The settings travel as their resolved JSON, which is also what the gains
// file records.
//
// How a run is stepped one generation at a time. pagmo's evolve() runs all its generations in one
// call, and in pagmo 2.18 a chain of one-generation calls is not the same run for every
// algorithm: `memory` keeps PSO's velocities but restarts the particles from their own bests
// (pagmo issue #486, fixed after 2.18), the bee colony's trial counters and the schedules of GWO
// and IHS live inside one call. So generation g is computed by replaying the whole run: a fresh
// algorithm (same settings, same seed, all `generations`) evolves a fresh population (same
// seed), every evaluation already made is answered from the run's log of fitness values, the new
// ones go to the BatchFitness, and the replay is cut off by an exception at the first evaluation
// of generation g + 1. The result is exactly pagmo's uninterrupted run, and the checkpoint is the
// log. The cost is pagmo's own bookkeeping, replayed: quadratic in the generations, measured
// (trivial fitness) at 0.18 ms per evaluation for sea's 990 generations and 1.2 ms for 9 990,
// 0.016 ms for pso_gen's 99; a simulation of the Table 1 job takes milliseconds.
#include "ftc/tune/optimizers/pagmo.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <memory>
#include <pagmo/algorithm.hpp>
#include <pagmo/algorithms/bee_colony.hpp>
#include <pagmo/algorithms/cmaes.hpp>
#include <pagmo/algorithms/de.hpp>
#include <pagmo/algorithms/de1220.hpp>
#include <pagmo/algorithms/gaco.hpp>
#include <pagmo/algorithms/gwo.hpp>
#include <pagmo/algorithms/ihs.hpp>
#include <pagmo/algorithms/maco.hpp>
#include <pagmo/algorithms/moead.hpp>
#include <pagmo/algorithms/nsga2.hpp>
#include <pagmo/algorithms/nspso.hpp>
#include <pagmo/algorithms/pso.hpp>
#include <pagmo/algorithms/pso_gen.hpp>
#include <pagmo/algorithms/sade.hpp>
#include <pagmo/algorithms/sea.hpp>
#include <pagmo/algorithms/sga.hpp>
#include <pagmo/algorithms/xnes.hpp>
#include <pagmo/batch_evaluators/member_bfe.hpp>
#include <pagmo/bfe.hpp>
#include <pagmo/population.hpp>
#include <pagmo/problem.hpp>
#include <pagmo/types.hpp>
#include <pagmo/utils/hypervolume.hpp>
#include <stdexcept>

#include "ftc/runtime/json_reader.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/tune/optimizers/pareto_bat.hpp"
#include "ftc/tune/optimizers/state_check.hpp"
#include "optimizers/pagmo_plugin.hpp"

namespace ftc::tune {

namespace {

// Thrown out of pagmo's evolve() at the first evaluation past the generation being computed.
struct GenerationEnd {};
// Thrown when a replay of a checkpoint needs an evaluation the checkpoint does not have.
struct LogExhausted {};

// Whether candidate a is the better history point: feasible first, then (between infeasible ones)
// the smaller violation, then the smaller first soft goal (NaN as +inf); ties keep the earlier.
bool better_point(const ObjectiveVector& a, const ObjectiveVector& b) {
  if (a.feasible() != b.feasible()) return a.feasible();
  const auto v = [](double x) {
    return std::isnan(x) ? std::numeric_limits<double>::infinity() : x;
  };
  if (!a.feasible() && v(a.violation) != v(b.violation)) return v(a.violation) < v(b.violation);
  return v(a.values[0]) < v(b.values[0]);
}

// The fitness J of a point as the one-objective history row reads it: the constraint rule of its
// first soft goal (1/f1) and its violation.
double point_fitness(const ObjectiveVector& o) {
  const double f = o.values[0];
  const double J = !std::isfinite(f) || f < 0 ? 0.0
                   : f == 0                   ? std::numeric_limits<double>::infinity()
                                              : 1.0 / f;
  return constrained_fitness(J, o.violation);
}

// What a replayed run logs per evaluation, and how that becomes pagmo's objectives. One
// objective: the fitness J of each candidate. A front: each candidate's objective vector (its
// soft goals and the violation of its hard goals).
template <class Value>
struct LogOf;

template <>
struct LogOf<double> {
  static constexpr const char* key = "fitness_log";
  static constexpr const char* problem_name = "ftctune tuning problem";
  static std::vector<double> evaluate(BatchFitness& fitness, const std::vector<Decision>& batch,
                                      std::size_t /*objectives*/) {
    std::vector<double> J = fitness(batch);
    if (J.size() != batch.size()) throw std::logic_error("fitness returned a wrong-sized batch");
    return J;
  }
  // The objective f = 1/J. 1/inf = 0 for a zero objective; an infeasible candidate's J in
  // [-1, 0) (constrained_fitness) goes above every other, decreasing in J, so pagmo's
  // minimisation orders candidates as the constraint rule does.
  static void objectives_of(double J, std::size_t /*objectives*/, std::vector<double>& out) {
    out.push_back(J > 0 ? 1.0 / J : J == 0 ? kDivergedObjective : kDivergedObjective * (2.0 - J));
  }
  static bool better(double a, double b) { return a > b; }
  static double fitness_of(double J) { return J; }
  static nlohmann::json to_json(double J) { return json_io::json_number(J); }
  static double from_json(const nlohmann::json& j, const std::string& path,
                          std::size_t /*objectives*/) {
    return state_check::fitness(j, path);
  }
  // This generation's candidates: the mean objective of those that did not diverge, and how
  // many did.
  static std::vector<std::pair<std::string, double>> generation(const double* first,
                                                                const double* last) {
    double sum = 0.0;
    int finite = 0, diverged = 0;
    for (const double* J = first; J != last; ++J) {
      if (*J > 0) {
        sum += 1.0 / *J;
        ++finite;
      } else {
        ++diverged;
      }
    }
    return {{"generation_mean_objective",
             finite ? sum / finite : std::numeric_limits<double>::quiet_NaN()},
            {"generation_diverged", static_cast<double>(diverged)}};
  }
};

template <>
struct LogOf<ObjectiveVector> {
  static constexpr const char* key = "objective_log";
  static constexpr const char* problem_name = "ftctune tuning problem (front)";
  static std::vector<ObjectiveVector> evaluate(BatchFitness& fitness,
                                               const std::vector<Decision>& batch,
                                               std::size_t objectives) {
    std::vector<ObjectiveVector> F = fitness.objective_vectors(batch);
    if (F.size() != batch.size())
      throw std::logic_error("objective vectors of a wrong-sized batch");
    for (const ObjectiveVector& f : F)
      if (f.values.size() != objectives)
        throw std::logic_error("an objective vector of the wrong size");
    return F;
  }
  // Per soft goal: log10 of the goal (the space the front's hypervolume is measured in, so that
  // goals decades apart weigh alike; values at or below kLogFloor count as it; pareto::log_value,
  // ftctune's log as the Pareto Bat's, not libm's),
  // kDivergedObjective for one that is not finite. An infeasible candidate gets
  // kDivergedObjective·(2 + V/(1 + V)) in every coordinate: any feasible candidate dominates it,
  // of two infeasible ones the smaller violation V dominates, and equal violations do not
  // dominate each other. That is constrained domination (Deb et al. 2002), written into the
  // objectives of an unconstrained problem.
  static void objectives_of(const ObjectiveVector& o, std::size_t objectives,
                            std::vector<double>& out) {
    if (!o.feasible()) {
      const double V = o.violation;
      const double rank = std::isfinite(V) ? V / (1.0 + V) : 1.0;
      out.insert(out.end(), objectives, kDivergedObjective * (2.0 + rank));
      return;
    }
    for (std::size_t k = 0; k < objectives; ++k) {
      const double v = o.values[k];
      out.push_back(std::isfinite(v) ? pareto::log_value(v) : kDivergedObjective);
    }
  }
  static bool better(const ObjectiveVector& a, const ObjectiveVector& b) {
    return better_point(a, b);
  }
  static double fitness_of(const ObjectiveVector& o) { return point_fitness(o); }
  static nlohmann::json to_json(const ObjectiveVector& o) {
    nlohmann::json row = nlohmann::json::array();
    for (double v : o.values) row.push_back(json_io::json_number(v));
    row.push_back(json_io::json_number(o.violation));
    return row;
  }
  static ObjectiveVector from_json(const nlohmann::json& j, const std::string& p,
                                   std::size_t objectives) {
    namespace sc = state_check;
    const nlohmann::json& row = sc::array(j, p, objectives + 1);
    ObjectiveVector o;
    for (std::size_t k = 0; k < objectives; ++k)
      o.values.push_back(sc::fitness(row[k], p + "/" + std::to_string(k)));
    o.violation = sc::fitness(row[objectives], p + "/" + std::to_string(objectives));
    if (!(o.violation >= 0))
      sc::fail(p + "/" + std::to_string(objectives), "expected a violation >= 0");
    return o;
  }
  // This generation's candidates: how many met every hard goal, and how many had a soft goal
  // that is not finite (diverged or undefined).
  static std::vector<std::pair<std::string, double>> generation(const ObjectiveVector* first,
                                                                const ObjectiveVector* last) {
    int feasible = 0, diverged = 0;
    for (const ObjectiveVector* o = first; o != last; ++o) {
      feasible += o->feasible() ? 1 : 0;
      bool finite = true;
      for (double v : o->values) finite = finite && std::isfinite(v);
      diverged += finite ? 0 : 1;
    }
    return {{"generation_feasible", static_cast<double>(feasible)},
            {"generation_diverged", static_cast<double>(diverged)}};
  }
};

// What every copy of the problem inside a replay points to: the log, the fitness for new
// evaluations, the cut-off, and the best candidate seen. pagmo copies problems freely (evolve()
// takes the population by value), so the copies share this instead of holding state.
template <class Value>
struct Link {
  BatchFitness* fitness = nullptr;  // null: answer from the log only (checking a checkpoint)
  const SearchSpace* space = nullptr;
  std::size_t objectives = 1;
  std::vector<Value>* log = nullptr;  // every evaluation of the run, in pagmo's order
  std::int64_t cursor = 0;            // evaluations of this replay so far
  std::int64_t limit = 0;             // evaluations up to the end of the wanted generation
  Decision best;
  Value best_value{};
  bool has_best = false;

  // pagmo's objectives of a batch, flat (its batch layout).
  std::vector<double> evaluate(std::vector<Decision> batch) {
    const auto n = static_cast<std::int64_t>(batch.size());
    if (cursor >= limit) throw GenerationEnd{};
    if (cursor + n > limit) throw std::logic_error("a pagmo batch spans two generations");
    // pagmo's operators keep candidates inside the box, but a rounding step past a bound would
    // make an invalid controller; evaluate (and report) the point actually inside.
    for (Decision& x : batch)
      for (std::size_t j = 0; j < x.size(); ++j) x[j] = space->clamp(j, x[j]);
    const auto logged = static_cast<std::int64_t>(log->size());
    const std::int64_t cached = std::clamp<std::int64_t>(logged - cursor, 0, n);
    if (cached < n) {
      if (!fitness) throw LogExhausted{};
      const std::vector<Decision> fresh(batch.begin() + cached, batch.end());
      std::vector<Value> F = LogOf<Value>::evaluate(*fitness, fresh, objectives);
      log->insert(log->end(), std::make_move_iterator(F.begin()), std::make_move_iterator(F.end()));
    }
    std::vector<double> out;
    out.reserve(static_cast<std::size_t>(n) * objectives);
    for (std::int64_t i = 0; i < n; ++i) {
      const Value& v = (*log)[static_cast<std::size_t>(cursor + i)];
      LogOf<Value>::objectives_of(v, objectives, out);
      if (!has_best || LogOf<Value>::better(v, best_value)) {
        best = batch[static_cast<std::size_t>(i)];
        best_value = v;
        has_best = true;
      }
    }
    cursor += n;
    return out;
  }
};

// The tuning problem as a pagmo UDP: box bounds, the link's objectives, batch fitness.
template <class Value>
class Udp {
 public:
  Udp() = default;
  Udp(std::vector<double> lower, std::vector<double> upper, Link<Value>* link)
      : lower_(std::move(lower)), upper_(std::move(upper)), link_(link) {}

  pagmo::vector_double fitness(const pagmo::vector_double& x) const {
    return linked().evaluate({x});
  }
  // A whole generation (pso_gen, gaco, nsga2) or the initial population in one call, so the
  // evaluator can simulate all its candidates at once.
  pagmo::vector_double batch_fitness(const pagmo::vector_double& dvs) const {
    const std::size_t d = lower_.size();
    std::vector<Decision> batch(dvs.size() / d);
    for (std::size_t i = 0; i < batch.size(); ++i)
      batch[i].assign(dvs.begin() + static_cast<std::ptrdiff_t>(i * d),
                      dvs.begin() + static_cast<std::ptrdiff_t>((i + 1) * d));
    return linked().evaluate(std::move(batch));
  }
  std::pair<pagmo::vector_double, pagmo::vector_double> get_bounds() const {
    return {lower_, upper_};
  }
  pagmo::vector_double::size_type get_nobj() const { return link_ ? link_->objectives : 1; }
  std::string get_name() const { return LogOf<Value>::problem_name; }
  // One run's BatchFitness, which is not to be called from several threads.
  pagmo::thread_safety get_thread_safety() const { return pagmo::thread_safety::none; }

 private:
  Link<Value>& linked() const {
    if (!link_) throw std::logic_error("pagmo problem without a fitness");
    return *link_;
  }
  std::vector<double> lower_, upper_;
  Link<Value>* link_ = nullptr;
};

using json = nlohmann::json;
using schema::Errors;
using schema::IntRange;

constexpr int kMaxPopulation = 100000;
constexpr int kMaxGenerations = 1000000;

// ---------------------------------------------------------------------------------------------
// Settings fields pagmo has and the schema engine does not.

// A number that is -1 (pagmo computes it from the problem) or lies in `r`.
template <class T>
schema::Object<T>& auto_or(schema::Object<T>& o, std::string key, double T::*m, Range r,
                           std::string doc) {
  const double dflt = T{}.*m;
  return o.field({key, false,
                  [m](const json& v, const std::string& path, T& out, Errors& e) {
                    schema::detail::read_number(v, path, out.*m, e);
                  },
                  [m, r](const T& t, const std::string& path, Errors& e) {
                    if (t.*m == -1.0) return;
                    if (!r.check(t.*m).empty())
                      e.push_back({path, "must be -1 (automatic) or " + r.describe() + " (got " +
                                             json_io::number_text(t.*m) + ")"});
                  },
                  [m, key](const T& t, json& o2) { o2[key] = t.*m; },
                  [doc, r, dflt] {
                    return json{{"description", doc},
                                {"default", dflt},
                                {"anyOf", {{{"const", -1}}, schema::detail::number_schema("", r)}}};
                  }});
}

// A non-empty list of integers in `r`.
template <class T>
schema::Object<T>& integer_list(schema::Object<T>& o, std::string key, std::vector<int> T::*m,
                                IntRange r, std::string doc) {
  const std::vector<int> dflt = T{}.*m;
  return o.field({key, false,
                  [m](const json& v, const std::string& path, T& out, Errors& e) {
                    std::vector<int> items;
                    bool ok = v.is_array();
                    for (std::size_t i = 0; ok && i < v.size(); ++i) {
                      long long n = 0;
                      ok = json_io::json_to_int(v[i], n) && n >= std::numeric_limits<int>::min() &&
                           n <= std::numeric_limits<int>::max();
                      items.push_back(static_cast<int>(n));
                    }
                    if (!ok)
                      e.push_back({path, schema::detail::type_error("an array of integers", v)});
                    else
                      out.*m = std::move(items);
                  },
                  [m, r](const T& t, const std::string& path, Errors& e) {
                    const std::vector<int>& items = t.*m;
                    if (items.empty()) e.push_back({path, "must name at least one"});
                    for (std::size_t i = 0; i < items.size(); ++i)
                      if (std::string msg = r.check(items[i]); !msg.empty())
                        e.push_back({path + "/" + std::to_string(i), msg});
                  },
                  [m, key](const T& t, json& o2) { o2[key] = t.*m; },
                  [doc, r, dflt] {
                    return json{
                        {"type", "array"},
                        {"items", {{"type", "integer"}, {"minimum", r.min}, {"maximum", r.max}}},
                        {"minItems", 1},
                        {"default", dflt},
                        {"description", doc}};
                  }});
}

// ---------------------------------------------------------------------------------------------
// The algorithms. Each settings struct holds the constructor options of one pagmo class except
// gen (the job's `generations`), seed (from the run's seed), verbosity, and `memory` (a run is
// one evolve call, so there is nothing to remember between calls).

struct Sizes {
  int population = 10;
  int generations = 10;
};

struct CmaesS {
  double cc = -1, cs = -1, c1 = -1, cmu = -1, sigma0 = 0.5, ftol = 1e-6, xtol = 1e-6;
};
struct XnesS {
  double eta_mu = -1, eta_sigma = -1, eta_b = -1, sigma0 = -1, ftol = 1e-6, xtol = 1e-6;
};
struct SadeS {
  int variant = 2, variant_adptv = 1;
  double ftol = 1e-6, xtol = 1e-6;
};
struct DeS {
  double F = 0.8, CR = 0.9;
  int variant = 2;
  double ftol = 1e-6, xtol = 1e-6;
};
struct De1220S {
  std::vector<int> allowed_variants{2, 3, 7, 10, 13, 14, 15, 16};
  int variant_adptv = 1;
  double ftol = 1e-6, xtol = 1e-6;
};
struct PsoS {
  double omega = 0.7298, eta1 = 2.05, eta2 = 2.05, max_vel = 0.5;
  int variant = 5, neighb_type = 2, neighb_param = 4;
};
struct BeeS {
  int limit = 20;
};
struct NoSettings {};
struct SgaS {
  double cr = 0.9, eta_c = 1.0, m = 0.02, param_m = 1.0;
  int param_s = 2;
  std::string crossover = "exponential", mutation = "polynomial", selection = "tournament";
};
struct GacoS {
  int ker = 63;
  double q = 1.0, oracle = 0.0, acc = 0.01;
  int threshold = 1, n_gen_mark = 7, impstop = 100000, evalstop = 100000;
  double focus = 0.0;
};
struct IhsS {
  double phmcr = 0.85, ppar_min = 0.35, ppar_max = 0.99, bw_min = 1e-5, bw_max = 1.0;
};

// One supported algorithm, seen through its resolved settings JSON.
class Entry {
 public:
  explicit Entry(PagmoAlgorithmInfo info) : info_(std::move(info)) {}
  virtual ~Entry() = default;
  const PagmoAlgorithmInfo& info() const { return info_; }
  std::int64_t per_generation(int population) const {
    return static_cast<std::int64_t>(population) * info_.per_member + info_.fixed;
  }
  // Evaluations from the start of a run to the end of generation g.
  std::int64_t evaluations_until(int population, int g) const {
    return population + g * per_generation(population);
  }
  // Reads `settings` (null = all defaults) strictly; the resolved form, or null on errors.
  virtual json read(const json* settings, const std::string& path, Errors& errs) const = 0;
  // Ranges and cross-field rules of the settings (at path/settings) and what the algorithm needs
  // of the population and generations (at path/population, path/settings/...).
  virtual void check(const json& resolved, Sizes sizes, const std::string& path,
                     Errors& errs) const = 0;
  virtual pagmo::algorithm make(const json& resolved, int generations, unsigned seed) const = 0;
  virtual json settings_schema() const = 0;
  // What the settings need of a front of `objectives` soft goals (after check() passed).
  virtual void check_front(const json& /*resolved*/, Sizes /*sizes*/, std::size_t /*objectives*/,
                           const std::string& /*path*/, Errors& /*errs*/) const {}

 protected:
  PagmoAlgorithmInfo info_;
};

template <class S>
class TypedEntry final : public Entry {
 public:
  using Build = std::function<pagmo::algorithm(const S&, unsigned gen, unsigned seed)>;
  using SizeRule = std::function<void(const S&, Sizes, const std::string& path, Errors&)>;
  using FrontRule =
      std::function<void(const S&, Sizes, std::size_t objectives, const std::string&, Errors&)>;

  TypedEntry(PagmoAlgorithmInfo info, std::shared_ptr<const schema::Object<S>> shape,
             SizeRule size_rule, Build build)
      : Entry(std::move(info)),
        shape_(std::move(shape)),
        size_rule_(std::move(size_rule)),
        build_(std::move(build)) {
    // The smallest population of the default settings, found by asking the rule itself.
    for (int n = 1; n <= kMaxPopulation; ++n) {
      Errors e;
      size_rule_(S{}, Sizes{n, 1}, "", e);
      if (e.empty()) {
        info_.min_population = n;
        break;
      }
    }
  }

  json read(const json* settings, const std::string& path, Errors& errs) const override {
    S s{};
    Errors mine;
    if (settings) shape_->read(*settings, path, s, mine);
    if (!mine.empty()) {
      errs.insert(errs.end(), mine.begin(), mine.end());
      return nullptr;
    }
    return shape_->write(s);
  }
  void check(const json& resolved, Sizes sizes, const std::string& path,
             Errors& errs) const override {
    const S s = from(resolved);
    Errors mine;
    shape_->validate(s, path + "/settings", mine);
    if (mine.empty()) size_rule_(s, sizes, path, mine);
    errs.insert(errs.end(), mine.begin(), mine.end());
  }
  pagmo::algorithm make(const json& resolved, int generations, unsigned seed) const override {
    return build_(from(resolved), static_cast<unsigned>(generations), seed);
  }
  json settings_schema() const override { return shape_->json_schema(); }
  void check_front(const json& resolved, Sizes sizes, std::size_t objectives,
                   const std::string& path, Errors& errs) const override {
    if (front_rule_) front_rule_(from(resolved), sizes, objectives, path, errs);
  }
  void set_front_rule(FrontRule rule) { front_rule_ = std::move(rule); }

 private:
  S from(const json& resolved) const {
    S s{};
    Errors e;
    shape_->read(resolved, "", s, e);
    assert(e.empty());
    return s;
  }

  std::shared_ptr<const schema::Object<S>> shape_;
  SizeRule size_rule_;
  Build build_;
  FrontRule front_rule_;
};

template <class S>
std::unique_ptr<Entry> entry(PagmoAlgorithmInfo info, schema::Object<S> shape,
                             typename TypedEntry<S>::SizeRule rule,
                             typename TypedEntry<S>::Build build) {
  return std::make_unique<TypedEntry<S>>(
      std::move(info), std::make_shared<const schema::Object<S>>(std::move(shape)), std::move(rule),
      std::move(build));
}

std::string population_text(int need, const std::string& why, int got) {
  return "must be at least " + std::to_string(need) + why + " (got " + std::to_string(got) + ")";
}

// A population of at least `n`: pagmo's own minimum for the algorithm.
template <class S>
typename TypedEntry<S>::SizeRule at_least(int n, std::string name) {
  return [n, name](const S&, Sizes sizes, const std::string& path, Errors& e) {
    if (sizes.population < n)
      e.push_back({path + "/population", population_text(n, " for " + name, sizes.population)});
  };
}

unsigned u(int v) { return static_cast<unsigned>(v); }

const char* kFtolDoc = "stop when the population's objectives differ by less than this";

std::unique_ptr<Entry> cmaes_entry() {
  using S = CmaesS;
  schema::Object<S> o(
      "CMA-ES (pagmo::cmaes): covariance matrix adaptation evolution strategy; the population "
      "is λ, and candidates are clipped to the bounds (force_bounds is always on)");
  auto_or(o, "cc", &S::cc, Range::unit(), "backward time horizon of the evolution path");
  auto_or(o, "cs", &S::cs, Range::unit(), "makes partly up for the small variance loss");
  auto_or(o, "c1", &S::c1, Range::unit(), "learning rate of the rank-one update");
  auto_or(o, "cmu", &S::cmu, Range::unit(), "learning rate of the rank-μ update");
  o.number("sigma0", &S::sigma0, Range::positive(), "initial step size (fraction of the box)")
      .number("ftol", &S::ftol, Range::non_negative(), kFtolDoc)
      .number("xtol", &S::xtol, Range::non_negative(), "stop when the step is shorter than this");
  return entry<S>({"cmaes", "covariance matrix adaptation evolution strategy", false, 1, 1, 0},
                  std::move(o), at_least<S>(5, "cmaes"),
                  [](const S& s, unsigned gen, unsigned seed) {
                    // force_bounds: the tuning bounds are hard (a gain outside them may not
                    // make a valid controller).
                    return pagmo::algorithm(pagmo::cmaes(gen, s.cc, s.cs, s.c1, s.cmu, s.sigma0,
                                                         s.ftol, s.xtol, false, true, seed));
                  });
}

std::unique_ptr<Entry> xnes_entry() {
  using S = XnesS;
  schema::Object<S> o(
      "xNES (pagmo::xnes): exponential natural evolution strategy; candidates are clipped to the "
      "bounds (force_bounds is always on)");
  auto_or(o, "eta_mu", &S::eta_mu, Range::half_open_unit(), "learning rate of the mean");
  auto_or(o, "eta_sigma", &S::eta_sigma, Range::half_open_unit(), "learning rate of the step size");
  auto_or(o, "eta_b", &S::eta_b, Range::half_open_unit(), "learning rate of the covariance");
  auto_or(o, "sigma0", &S::sigma0, Range::half_open_unit(),
          "initial step size (fraction of the box)");
  o.number("ftol", &S::ftol, Range::non_negative(), kFtolDoc)
      .number("xtol", &S::xtol, Range::non_negative(), "stop when the step is shorter than this");
  return entry<S>(
      {"xnes", "exponential natural evolution strategy", false, 1, 1, 0}, std::move(o),
      at_least<S>(5, "xnes"), [](const S& s, unsigned gen, unsigned seed) {
        return pagmo::algorithm(pagmo::xnes(gen, s.eta_mu, s.eta_sigma, s.eta_b, s.sigma0, s.ftol,
                                            s.xtol, false, true, seed));
      });
}

std::unique_ptr<Entry> sade_entry() {
  using S = SadeS;
  schema::Object<S> o("SaDE (pagmo::sade): self-adaptive differential evolution");
  o.integer("variant", &S::variant, IntRange{1, 18}, "mutation variant (pagmo's numbering)")
      .integer("variant_adptv", &S::variant_adptv, IntRange{1, 2},
               "self-adaptation scheme: 1 jDE, 2 iDE")
      .number("ftol", &S::ftol, Range::non_negative(), kFtolDoc)
      .number("xtol", &S::xtol, Range::non_negative(),
              "stop when the population's spread is below this");
  return entry<S>({"sade", "self-adaptive differential evolution (jDE/iDE)", false, 1, 1, 0},
                  std::move(o), at_least<S>(7, "sade"),
                  [](const S& s, unsigned gen, unsigned seed) {
                    return pagmo::algorithm(pagmo::sade(gen, u(s.variant), u(s.variant_adptv),
                                                        s.ftol, s.xtol, false, seed));
                  });
}

std::unique_ptr<Entry> de_entry() {
  using S = DeS;
  schema::Object<S> o("DE (pagmo::de): differential evolution");
  o.number("F", &S::F, Range::unit(), "weight coefficient")
      .number("CR", &S::CR, Range::unit(), "crossover probability")
      .integer("variant", &S::variant, IntRange{1, 10},
               "mutation variant (pagmo's numbering; 2 = rand/1/exp)")
      .number("ftol", &S::ftol, Range::non_negative(), kFtolDoc)
      .number("xtol", &S::xtol, Range::non_negative(),
              "stop when the population's spread is below this");
  return entry<S>(
      {"de", "differential evolution", false, 1, 1, 0}, std::move(o), at_least<S>(5, "de"),
      [](const S& s, unsigned gen, unsigned seed) {
        return pagmo::algorithm(pagmo::de(gen, s.F, s.CR, u(s.variant), s.ftol, s.xtol, seed));
      });
}

std::unique_ptr<Entry> de1220_entry() {
  using S = De1220S;
  schema::Object<S> o(
      "pDE (pagmo::de1220): differential evolution adapting its mutation variant, F and CR");
  integer_list(o, "allowed_variants", &S::allowed_variants, IntRange{1, 18},
               "mutation variants to choose among (pagmo's numbering)");
  o.integer("variant_adptv", &S::variant_adptv, IntRange{1, 2},
            "self-adaptation scheme: 1 jDE, 2 iDE")
      .number("ftol", &S::ftol, Range::non_negative(), kFtolDoc)
      .number("xtol", &S::xtol, Range::non_negative(),
              "stop when the population's spread is below this");
  return entry<S>(
      {"de1220", "differential evolution with self-adapted variant, F and CR", false, 1, 1, 0},
      std::move(o), at_least<S>(7, "de1220"), [](const S& s, unsigned gen, unsigned seed) {
        std::vector<unsigned> variants(s.allowed_variants.begin(), s.allowed_variants.end());
        return pagmo::algorithm(
            pagmo::de1220(gen, variants, u(s.variant_adptv), s.ftol, s.xtol, false, seed));
      });
}

schema::Object<PsoS> pso_shape(const std::string& description) {
  using S = PsoS;
  schema::Object<S> o(description);
  o.number("omega", &S::omega, Range::unit(), "inertia weight (or constriction factor)")
      .number("eta1", &S::eta1, Range::between(0, 4), "social component")
      .number("eta2", &S::eta2, Range::between(0, 4), "cognitive component")
      .number("max_vel", &S::max_vel, Range::half_open_unit(),
              "largest velocity, as a fraction of the box")
      .integer("variant", &S::variant, IntRange{1, 6}, "velocity update (pagmo's numbering)")
      .integer("neighb_type", &S::neighb_type, IntRange{1, 4},
               "swarm topology: 1 gbest, 2 lbest, 3 von Neumann, 4 adaptive random")
      .integer("neighb_param", &S::neighb_param, IntRange{1, std::numeric_limits<int>::max()},
               "neighbourhood size (lbest, adaptive random)");
  return o;
}

// lbest links each particle to neighb_param/2 particles on either side of it, and pagmo's index
// arithmetic wraps around the swarm once only.
void pso_sizes(const PsoS& s, Sizes sizes, const std::string& path, Errors& e) {
  const int radius = s.neighb_type == 2 ? s.neighb_param / 2 : 1;
  if (sizes.population < radius)
    e.push_back(
        {path + "/population",
         population_text(
             radius, " for the lbest topology with neighb_param " + std::to_string(s.neighb_param),
             sizes.population)});
  // The adaptive random topology gives each particle neighb_param - 1 informants, drawn again
  // after every generation without improvement: more than the swarm is only memory (2e9 took
  // tens of GB).
  if (s.neighb_type == 4 && s.neighb_param > sizes.population)
    e.push_back({path + "/settings/neighb_param",
                 "must be at most the population (" + std::to_string(sizes.population) +
                     ") for the adaptive random topology, got " +
                     std::to_string(s.neighb_param)});
}

std::unique_ptr<Entry> pso_entry() {
  return entry<PsoS>(
      {"pso", "particle swarm optimisation", false, 1, 1, 0},
      pso_shape("PSO (pagmo::pso): particle swarm optimisation, particles moved "
                "and evaluated one at a time"),
      pso_sizes, [](const PsoS& s, unsigned gen, unsigned seed) {
        return pagmo::algorithm(pagmo::pso(gen, s.omega, s.eta1, s.eta2, s.max_vel, u(s.variant),
                                           u(s.neighb_type), u(s.neighb_param), false, seed));
      });
}

std::unique_ptr<Entry> pso_gen_entry() {
  return entry<PsoS>(
      {"pso_gen", "particle swarm optimisation, generational (one batch per generation)", true, 1,
       1, 0},
      pso_shape("PSO, generational (pagmo::pso_gen): every particle moves, then the swarm is "
                "evaluated as one batch"),
      pso_sizes, [](const PsoS& s, unsigned gen, unsigned seed) {
        pagmo::pso_gen a(gen, s.omega, s.eta1, s.eta2, s.max_vel, u(s.variant), u(s.neighb_type),
                         u(s.neighb_param), false, seed);
        a.set_bfe(pagmo::bfe{pagmo::member_bfe{}});
        return pagmo::algorithm(std::move(a));
      });
}

std::unique_ptr<Entry> bee_entry() {
  using S = BeeS;
  schema::Object<S> o(
      "ABC (pagmo::bee_colony): artificial bee colony; employed and onlooker bees each try one "
      "candidate per food source, 2 × population evaluations per generation");
  o.integer("limit", &S::limit, IntRange{1, std::numeric_limits<int>::max()},
            "failed trials after which a food source is abandoned for a random one");
  return entry<S>({"bee_colony", "artificial bee colony", false, 1, 2, 0}, std::move(o),
                  at_least<S>(2, "bee_colony"), [](const S& s, unsigned gen, unsigned seed) {
                    return pagmo::algorithm(pagmo::bee_colony(gen, u(s.limit), seed));
                  });
}

std::unique_ptr<Entry> sea_entry() {
  schema::Object<NoSettings> o(
      "(N+1)-ES (pagmo::sea): simple evolutionary algorithm; each generation mutates the best "
      "member into one offspring, which replaces the worst if not worse");
  o.unknown_key_message([](const std::string&) { return "sea has no settings"; });
  return entry<NoSettings>(
      {"sea", "(N+1) evolution strategy, one evaluation per generation", false, 1, 0, 1},
      std::move(o), at_least<NoSettings>(1, "sea"),
      [](const NoSettings&, unsigned gen, unsigned seed) {
        return pagmo::algorithm(pagmo::sea(gen, seed));
      });
}

std::unique_ptr<Entry> gwo_entry() {
  schema::Object<NoSettings> o(
      "GWO (pagmo::gwo): grey wolf optimiser; the coefficient a falls linearly from 2 to 0 over "
      "the run's generations");
  o.unknown_key_message([](const std::string&) { return "gwo has no settings"; });
  return entry<NoSettings>({"gwo", "grey wolf optimiser", false, 1, 1, 0}, std::move(o),
                           at_least<NoSettings>(3, "gwo"),
                           [](const NoSettings&, unsigned gen, unsigned seed) {
                             return pagmo::algorithm(pagmo::gwo(gen, seed));
                           });
}

std::unique_ptr<Entry> ihs_entry() {
  using S = IhsS;
  schema::Object<S> o(
      "IHS (pagmo::ihs): improved harmony search; one new harmony per generation, the pitch "
      "adjustment rate rising and the bandwidth falling over the run's generations");
  o.number("phmcr", &S::phmcr, Range::unit(), "probability of choosing from the memory")
      .number("ppar_min", &S::ppar_min, Range::unit(), "first pitch adjustment rate")
      .number("ppar_max", &S::ppar_max, Range::unit(), "last pitch adjustment rate (>= ppar_min)")
      .number("bw_min", &S::bw_min, Range::positive(), "last bandwidth")
      .number("bw_max", &S::bw_max, Range::positive(), "first bandwidth (>= bw_min)")
      .rule([](const S& s, const std::string& path, Errors& e) {
        if (s.ppar_min > s.ppar_max)
          e.push_back({path + "/ppar_max", "must be >= ppar_min " +
                                               json_io::number_text(s.ppar_min) + " (got " +
                                               json_io::number_text(s.ppar_max) + ")"});
        if (s.bw_min > s.bw_max)
          e.push_back({path + "/bw_max", "must be >= bw_min " + json_io::number_text(s.bw_min) +
                                             " (got " + json_io::number_text(s.bw_max) + ")"});
      });
  return entry<S>({"ihs", "improved harmony search, one evaluation per generation", false, 1, 0, 1},
                  std::move(o), at_least<S>(1, "ihs"), [](const S& s, unsigned gen, unsigned seed) {
                    return pagmo::algorithm(
                        pagmo::ihs(gen, s.phmcr, s.ppar_min, s.ppar_max, s.bw_min, s.bw_max, seed));
                  });
}

std::unique_ptr<Entry> sga_entry() {
  using S = SgaS;
  schema::Object<S> o("SGA (pagmo::sga): simple genetic algorithm with elitist reinsertion");
  o.number("cr", &S::cr, Range::unit(), "crossover probability")
      .number("eta_c", &S::eta_c, Range::between(1, 100), "distribution index of sbx crossover")
      .number("m", &S::m, Range::unit(), "mutation probability")
      .number("param_m", &S::param_m, Range::between(0, 100),
              "distribution index (polynomial mutation, in [1, 100]) or width (gaussian, uniform: "
              "in [0, 1])")
      .integer("param_s", &S::param_s, IntRange{1, std::numeric_limits<int>::max()},
               "tournament size, or how many of the best truncated selection keeps")
      .choice<std::string>("crossover", &S::crossover,
                           {{"exponential", "exponential"},
                            {"binomial", "binomial"},
                            {"single", "single"},
                            {"sbx", "sbx"}},
                           "crossover operator")
      .choice<std::string>(
          "mutation", &S::mutation,
          {{"polynomial", "polynomial"}, {"gaussian", "gaussian"}, {"uniform", "uniform"}},
          "mutation operator")
      .choice<std::string>("selection", &S::selection,
                           {{"tournament", "tournament"}, {"truncated", "truncated"}},
                           "selection operator")
      .rule([](const S& s, const std::string& path, Errors& e) {
        const Range r = s.mutation == "polynomial" ? Range::between(1, 100) : Range::unit();
        if (std::isfinite(s.param_m) && !r.contains(s.param_m))
          e.push_back({path + "/param_m", "must be " + r.describe() + " for " + s.mutation +
                                              " mutation (got " + json_io::number_text(s.param_m) +
                                              ")"});
      });
  return entry<S>(
      {"sga", "simple genetic algorithm", false, 1, 1, 0}, std::move(o),
      [](const S& s, Sizes sizes, const std::string& path, Errors& e) {
        const int need = std::max(2, s.param_s);
        const std::string why =
            s.param_s > 2 ? " for sga with param_s " + std::to_string(s.param_s) : " for sga";
        if (sizes.population < need)
          e.push_back({path + "/population", population_text(need, why, sizes.population)});
        else if (s.crossover == "sbx" && sizes.population % 2 != 0)
          e.push_back({path + "/population", "must be even for sbx crossover (got " +
                                                 std::to_string(sizes.population) + ")"});
      },
      [](const S& s, unsigned gen, unsigned seed) {
        return pagmo::algorithm(pagmo::sga(gen, s.cr, s.eta_c, s.m, s.param_m, u(s.param_s),
                                           s.crossover, s.mutation, s.selection, seed));
      });
}

std::unique_ptr<Entry> gaco_entry() {
  using S = GacoS;
  schema::Object<S> o(
      "GACO (pagmo::gaco): extended ant colony optimisation; the solution archive (ker) must fit "
      "in the population, and each generation is evaluated as one batch");
  o.integer("ker", &S::ker, IntRange{1, kMaxPopulation}, "size of the solution archive")
      .number("q", &S::q, Range::non_negative(), "convergence speed")
      .number("oracle", &S::oracle, Range::any(), "oracle of the penalty method")
      .number("acc", &S::acc, Range::non_negative(), "accuracy of the penalty method")
      .integer("threshold", &S::threshold, IntRange{1, kMaxGenerations},
               "generation from which q is lowered to 0.01 (at most `generations`)")
      .integer("n_gen_mark", &S::n_gen_mark, IntRange{1, std::numeric_limits<int>::max()},
               "generations over which the standard deviations shrink")
      .integer("impstop", &S::impstop, IntRange{0, std::numeric_limits<int>::max()},
               "stop after this many generations without improvement (0: never)")
      .integer("evalstop", &S::evalstop, IntRange{0, std::numeric_limits<int>::max()},
               "stop after this many generations whose best does not improve on the archive's "
               "(pagmo counts them per generation, though it names them evaluations; 0: never)")
      .number("focus", &S::focus, Range::non_negative(), "focus of the search (0: none)");
  return entry<S>(
      {"gaco", "extended ant colony optimisation (one batch per generation)", true, 1, 1, 0},
      std::move(o),
      [](const S& s, Sizes sizes, const std::string& path, Errors& e) {
        if (sizes.population < s.ker)
          e.push_back({path + "/population",
                       population_text(s.ker, " for gaco with ker " + std::to_string(s.ker),
                                       sizes.population)});
        if (sizes.generations > 0 && s.threshold > sizes.generations)
          e.push_back({path + "/settings/threshold",
                       "must be at most generations " + std::to_string(sizes.generations) +
                           " (got " + std::to_string(s.threshold) + ")"});
      },
      [](const S& s, unsigned gen, unsigned seed) {
        pagmo::gaco a(gen, u(s.ker), s.q, s.oracle, s.acc, u(s.threshold), u(s.n_gen_mark),
                      u(s.impstop), u(s.evalstop), s.focus, false, seed);
        a.set_bfe(pagmo::bfe{pagmo::member_bfe{}});
        return pagmo::algorithm(std::move(a));
      });
}

// ---------------------------------------------------------------------------------------------
// The multi-objective algorithms (issue 26): they search the Pareto front of a job's soft goals.
// pagmo's NSGA-II, MOEA/D, NSPSO and MHACO take no constraints, so a job's hard goals reach them
// as constrained domination (Deb et al. 2002) written into the objectives: see FrontLink.

struct Nsga2S {
  double cr = 0.95, eta_c = 10.0, m = 0.01, eta_m = 50.0;
};
struct MoeadS {
  std::string weight_generation = "grid", decomposition = "tchebycheff";
  int neighbours = 20;
  double CR = 1.0, F = 0.5, eta_m = 20.0, realb = 0.9;
  int limit = 2;
  bool preserve_diversity = true;
};
struct NspsoS {
  double omega = 0.6, c1 = 2.0, c2 = 2.0, chi = 1.0, v_coeff = 0.5;
  int leader_selection_range = 60;
  std::string diversity_mechanism = "crowding distance";
};
struct MacoS {
  int ker = 63;
  double q = 1.0;
  int threshold = 1, n_gen_mark = 7, evalstop = 100000;
  double focus = 0.0;
};

std::unique_ptr<Entry> nsga2_entry() {
  using S = Nsga2S;
  schema::Object<S> o(
      "NSGA-II (pagmo::nsga2): non-dominated sorting genetic algorithm for a Pareto front; the "
      "population is a multiple of 4, and each generation's offspring are evaluated as one batch");
  o.number("cr", &S::cr, Range{0.0, false, 1.0, true}, "crossover probability, in [0, 1)")
      .number("eta_c", &S::eta_c, Range::between(1, 100), "distribution index of sbx crossover")
      .number("m", &S::m, Range::unit(), "mutation probability")
      .number("eta_m", &S::eta_m, Range::between(1, 100),
              "distribution index of polynomial mutation");
  PagmoAlgorithmInfo info{
      "nsga2", "NSGA-II, multi-objective (one batch per generation)", true, 1, 1, 0};
  info.front = true;
  return entry<S>(
      std::move(info), std::move(o),
      [](const S&, Sizes sizes, const std::string& path, Errors& e) {
        if (sizes.population < 8 || sizes.population % 4 != 0)
          e.push_back(
              {path + "/population", "must be a multiple of 4 and at least 8 for nsga2 (got " +
                                         std::to_string(sizes.population) + ")"});
      },
      [](const S& s, unsigned gen, unsigned seed) {
        pagmo::nsga2 a(gen, s.cr, s.eta_c, s.m, s.eta_m, seed);
        a.set_bfe(pagmo::bfe{pagmo::member_bfe{}});
        return pagmo::algorithm(std::move(a));
      });
}

std::unique_ptr<Entry> moead_entry() {
  using S = MoeadS;
  schema::Object<S> o(
      "MOEA/D (pagmo::moead): decomposition of the front into one weighted problem per member, "
      "with differential evolution; candidates are evaluated one at a time. With three or more "
      "soft goals the grid weights need a population of C(H + M - 1, M - 1) for some H");
  o.choice<std::string>(
       "weight_generation", &S::weight_generation,
       {{"grid", "grid"}, {"low discrepancy", "low discrepancy"}, {"random", "random"}},
       "how the weight vectors are made")
      .choice<std::string>("decomposition", &S::decomposition,
                           {{"tchebycheff", "tchebycheff"}, {"weighted", "weighted"}, {"bi", "bi"}},
                           "how a weight vector makes one objective of the goals")
      .integer("neighbours", &S::neighbours, IntRange{2, kMaxPopulation},
               "size of each weight vector's neighbourhood (less than the population)")
      .number("CR", &S::CR, Range::unit(), "crossover probability of the DE operator")
      .number("F", &S::F, Range::unit(), "weight of the DE operator")
      .number("eta_m", &S::eta_m, Range::non_negative(), "distribution index of the mutation")
      .number("realb", &S::realb, Range::unit(),
              "chance that parents come from the neighbourhood rather than the population")
      .integer("limit", &S::limit, IntRange{0, kMaxPopulation},
               "most members a new candidate replaces (with preserve_diversity)")
      .boolean("preserve_diversity", &S::preserve_diversity,
               "whether realb and limit keep the population diverse");
  PagmoAlgorithmInfo info{"moead", "MOEA/D, multi-objective by decomposition", false, 1, 1, 0};
  info.front = true;
  auto moead = std::make_unique<TypedEntry<S>>(
      std::move(info), std::make_shared<const schema::Object<S>>(std::move(o)),
      [](const S& s, Sizes sizes, const std::string& path, Errors& e) {
        if (sizes.population < s.neighbours + 1)
          e.push_back({path + "/population",
                       population_text(s.neighbours + 1,
                                       " for moead with neighbours " + std::to_string(s.neighbours),
                                       sizes.population)});
      },
      [](const S& s, unsigned gen, unsigned seed) {
        return pagmo::algorithm(
            pagmo::moead(gen, s.weight_generation, s.decomposition,
                         static_cast<pagmo::population::size_type>(s.neighbours), s.CR, s.F,
                         s.eta_m, s.realb, u(s.limit), s.preserve_diversity, seed));
      });
  // pagmo's decomposition_weights: a weight per member, at least one per objective; on a grid
  // (M objectives, H steps) exactly C(H + M - 1, M - 1) of them, any count for M = 2.
  moead->set_front_rule([](const S& s, Sizes sizes, std::size_t objectives, const std::string& path,
                       Errors& errs) {
    const auto m = static_cast<long long>(objectives);
    const long long n = sizes.population;
    if (n < m) {
      errs.push_back({path + "/population", population_text(static_cast<int>(m),
                                                            " for moead with " + std::to_string(m) +
                                                                " soft goals (a weight each)",
                                                            sizes.population)});
      return;
    }
    if (s.weight_generation != "grid" || m < 3) return;
    const auto grid = [m](long long h) {  // C(h + m - 1, m - 1), exact in a long long here
      long long c = 1;
      for (long long k = 1; k <= m - 1; ++k) c = c * (h + k) / k;
      return c;
    };
    long long h = 1;
    while (grid(h) < n) ++h;
    if (grid(h) == n) return;
    errs.push_back({path + "/population",
                    "must be C(H + " + std::to_string(m - 1) + ", " + std::to_string(m - 1) +
                        ") for some H with moead's grid weights and " + std::to_string(m) +
                        " soft goals, such as " + std::to_string(grid(h - 1)) + " or " +
                        std::to_string(grid(h)) + " (got " + std::to_string(n) +
                        "); or set settings.weight_generation to \"low discrepancy\""});
  });
  return moead;
}

std::unique_ptr<Entry> nspso_entry() {
  using S = NspsoS;
  schema::Object<S> o(
      "NSPSO (pagmo::nspso): non-dominated sorting particle swarm for a Pareto front; the swarm "
      "is evaluated as one batch per generation");
  o.number("omega", &S::omega, Range::unit(), "particles' inertia weight")
      .number("c1", &S::c1, Range::positive(), "magnitude of the force toward a particle's best")
      .number("c2", &S::c2, Range::positive(), "magnitude of the force toward its leader")
      .number("chi", &S::chi, Range::positive(), "velocity scaling factor")
      .number("v_coeff", &S::v_coeff, Range::half_open_unit(),
              "largest velocity, as a fraction of the box")
      .integer("leader_selection_range", &S::leader_selection_range, IntRange{1, 100},
               "percentage of the non-dominated particles leaders are drawn from")
      .choice<std::string>("diversity_mechanism", &S::diversity_mechanism,
                           {{"crowding distance", "crowding distance"},
                            {"niche count", "niche count"},
                            {"max min", "max min"}},
                           "how leaders are ranked");
  PagmoAlgorithmInfo info{
      "nspso", "NSPSO, multi-objective particle swarm (one batch per generation)", true, 1, 1, 0};
  info.front = true;
  return entry<S>(std::move(info), std::move(o), at_least<S>(2, "nspso"),
                  [](const S& s, unsigned gen, unsigned seed) {
                    pagmo::nspso a(gen, s.omega, s.c1, s.c2, s.chi, s.v_coeff,
                                   u(s.leader_selection_range), s.diversity_mechanism, false, seed);
                    a.set_bfe(pagmo::bfe{pagmo::member_bfe{}});
                    return pagmo::algorithm(std::move(a));
                  });
}

std::unique_ptr<Entry> maco_entry() {
  using S = MacoS;
  schema::Object<S> o(
      "MHACO (pagmo::maco): multi-objective hypervolume-based ant colony optimisation; the "
      "solution archive (ker) must fit in the population, and each generation is evaluated as "
      "one batch");
  o.integer("ker", &S::ker, IntRange{1, kMaxPopulation}, "size of the solution archive")
      .number("q", &S::q, Range::non_negative(), "convergence speed")
      .integer("threshold", &S::threshold, IntRange{1, kMaxGenerations},
               "generation from which q is lowered to 0.01 (at most `generations`)")
      .integer("n_gen_mark", &S::n_gen_mark, IntRange{1, std::numeric_limits<int>::max()},
               "generations over which the standard deviations shrink")
      .integer("evalstop", &S::evalstop, IntRange{0, std::numeric_limits<int>::max()},
               "stop after this many generations without a better ideal point (0: never)")
      .number("focus", &S::focus, Range::non_negative(), "focus of the search (0: none)");
  PagmoAlgorithmInfo info{
      "maco", "MHACO, multi-objective ant colony (one batch per generation)", true, 1, 1, 0};
  info.front = true;
  return entry<S>(
      std::move(info), std::move(o),
      [](const S& s, Sizes sizes, const std::string& path, Errors& e) {
        if (sizes.population < s.ker)
          e.push_back({path + "/population",
                       population_text(s.ker, " for maco with ker " + std::to_string(s.ker),
                                       sizes.population)});
        if (sizes.generations > 0 && s.threshold > sizes.generations)
          e.push_back({path + "/settings/threshold",
                       "must be at most generations " + std::to_string(sizes.generations) +
                           " (got " + std::to_string(s.threshold) + ")"});
      },
      [](const S& s, unsigned gen, unsigned seed) {
        pagmo::maco a(gen, u(s.ker), s.q, u(s.threshold), u(s.n_gen_mark), u(s.evalstop), s.focus,
                      false, seed);
        a.set_bfe(pagmo::bfe{pagmo::member_bfe{}});
        return pagmo::algorithm(std::move(a));
      });
}

const std::vector<std::unique_ptr<Entry>>& entries() {
  static const std::vector<std::unique_ptr<Entry>> all = [] {
    std::vector<std::unique_ptr<Entry>> v;
    v.push_back(bee_entry());
    v.push_back(cmaes_entry());
    v.push_back(de_entry());
    v.push_back(de1220_entry());
    v.push_back(gaco_entry());
    v.push_back(gwo_entry());
    v.push_back(ihs_entry());
    v.push_back(maco_entry());
    v.push_back(moead_entry());
    v.push_back(nsga2_entry());
    v.push_back(nspso_entry());
    v.push_back(pso_entry());
    v.push_back(pso_gen_entry());
    v.push_back(sade_entry());
    v.push_back(sea_entry());
    v.push_back(sga_entry());
    v.push_back(xnes_entry());
    return v;
  }();
  return all;
}

const Entry* find_entry(const std::string& name) {
  for (const auto& e : entries())
    if (e->info().name == name) return e.get();
  return nullptr;
}

std::string known_names() {
  std::string s;
  for (const auto& e : entries()) s += (s.empty() ? "" : ", ") + e->info().name;
  return s;
}

// pagmo's messages carry the function, file and line before "what: ".
std::string pagmo_message(const std::exception& e) {
  std::string m = e.what();
  if (const auto at = m.find("what: "); at != std::string::npos) m = m.substr(at + 6);
  while (!m.empty() && (m.back() == '\n' || m.back() == ' ')) m.pop_back();
  return m;
}

// A 32-bit seed for pagmo (whose engines take unsigned) from the run's engine.
unsigned seed32(Rng& rng) { return static_cast<unsigned>(rng.uniform() * 4294967296.0); }

// ---------------------------------------------------------------------------------------------

// A pagmo algorithm stepped one generation at a time by replaying its run (see the top of this
// file), over a log of J values (one objective) or of objective vectors (a front).
template <class Value>
class PagmoOptimizer final : public GenerationalOptimizer {
 public:
  PagmoOptimizer(const Entry& entry, json settings, Sizes sizes, std::uint64_t seed,
                 const SearchSpace& space, std::size_t objectives = 1)
      : GenerationalOptimizer(sizes.generations, seed, space),
        entry_(entry),
        settings_(std::move(settings)),
        sizes_(sizes),
        objectives_(objectives) {
    algorithm_seed_ = seed32(rng_);
    population_seed_ = seed32(rng_);
  }

  void initialize(BatchFitness& fitness) override {
    log_.clear();
    finished_ = false;
    t_ = 0;
    finish(replay(&fitness, 0));
  }

  void iterate(BatchFitness& fitness) override {
    assert(t_ >= 0 && "initialize() first");
    ++t_;
    // A run that met its own stopping rule (ftol, xtol, impstop, ...) has nothing more to do.
    finish(finished_ ? Replay{evaluations_, evaluations_, best_, best_fitness_, true}
                     : replay(&fitness, t_));
  }

  json state() const override {
    json s = common_state("pagmo");
    s["name"] = entry_.info().name;
    s["finished"] = finished_;
    s["pagmo_seeds"] = {algorithm_seed_, population_seed_};
    json log = json::array();
    for (const Value& v : log_) log.push_back(LogOf<Value>::to_json(v));
    s[LogOf<Value>::key] = std::move(log);
    return s;
  }

  void restore(const json& s) override {
    namespace sc = state_check;
    // pagmo's generations differ in size and a run may stop on its own, so the evaluations are
    // only bounded here; the replay below ties them to the log. Some algorithms (CMA-ES without
    // force_bounds) evaluate outside the bounds, so the points are not held to them.
    restore_common(s, "pagmo", 0, entry_.evaluations_until(sizes_.population, sizes_.generations),
                   false);
    const json& name_field = sc::member(s, "", "name");
    if (!name_field.is_string()) sc::fail("/name", "expected the name of a pagmo algorithm");
    const std::string name = name_field.get<std::string>();
    if (name != entry_.info().name)
      throw InputError("checkpoint", "/name",
                       "is a state of pagmo's " + name + ", the job runs " + entry_.info().name);
    finished_ = sc::boolean(sc::member(s, "", "finished"), "/finished");
    const json& seeds = sc::array(sc::member(s, "", "pagmo_seeds"), "/pagmo_seeds", 2);
    algorithm_seed_ =
        static_cast<unsigned>(sc::integer(seeds[0], "/pagmo_seeds/0", 0, 0xffffffffLL));
    population_seed_ =
        static_cast<unsigned>(sc::integer(seeds[1], "/pagmo_seeds/1", 0, 0xffffffffLL));
    const std::string key = LogOf<Value>::key;
    const json& log = sc::array(sc::member(s, "", LogOf<Value>::key), "/" + key,
                                static_cast<std::size_t>(evaluations_));
    log_.clear();
    for (std::size_t i = 0; i < log.size(); ++i)
      log_.push_back(
          LogOf<Value>::from_json(log[i], "/" + key + "/" + std::to_string(i), objectives_));
    // Replaying the logged evaluations must lead to the checkpoint's own best point: this is
    // what tells a state of another job, seed or algorithm settings from this run's.
    bool consistent = true;
    try {
      const Replay r = replay(nullptr, t_);
      consistent = r.evaluations == evaluations_ && r.best == best_ &&
                   r.best_fitness == best_fitness_ && r.finished == finished_;
    } catch (const LogExhausted&) {
      consistent = false;
    }
    if (!consistent)
      throw InputError("checkpoint", "/" + key,
                       "does not replay to the checkpoint's best point: a state of another job, "
                       "seed or setting, or damaged");
  }

 private:
  struct Replay {
    std::int64_t start = 0;        // evaluations before the generation
    std::int64_t evaluations = 0;  // after it
    Decision best;
    double best_fitness = 0.0;
    bool finished = false;  // pagmo's evolve() returned: the run is over
  };

  // The run from its start to the end of generation g, new evaluations through `fitness` (null:
  // the log must have them all).
  Replay replay(BatchFitness* fitness, int g) {
    Link<Value> link;
    link.fitness = fitness;
    link.space = &space_;
    link.objectives = objectives_;
    link.log = &log_;
    link.limit = entry_.evaluations_until(sizes_.population, g);
    const pagmo::problem problem{Udp<Value>(space_.lower, space_.upper, &link)};
    // The initial population as one batch.
    pagmo::population pop(problem, pagmo::bfe{pagmo::member_bfe{}},
                          static_cast<pagmo::population::size_type>(sizes_.population),
                          population_seed_);
    Replay r;
    r.start = g == 0 ? 0 : entry_.evaluations_until(sizes_.population, g - 1);
    if (g > 0) {
      const pagmo::algorithm algorithm =
          entry_.make(settings_, sizes_.generations, algorithm_seed_);
      try {
        algorithm.evolve(pop);
        r.finished = true;
      } catch (const GenerationEnd&) {
      } catch (const std::invalid_argument& e) {
        // pagmo refusing the job's shape (MOEA/D's grid weights for three or more goals).
        throw InputError(
            "job", "/tuning/algorithm",
            "pagmo's " + entry_.info().name + " refuses this job: " + pagmo_message(e));
      }
    }
    r.start = std::min(r.start, link.cursor);
    r.evaluations = link.cursor;
    r.best = link.best;
    r.best_fitness = link.has_best ? LogOf<Value>::fitness_of(link.best_value) : 0.0;
    return r;
  }

  void finish(const Replay& r) {
    evaluations_ = r.evaluations;
    best_ = r.best;
    best_fitness_ = r.best_fitness;
    finished_ = r.finished;
    record(LogOf<Value>::generation(log_.data() + r.start, log_.data() + r.evaluations));
  }

  const Entry& entry_;
  json settings_;
  Sizes sizes_;
  std::size_t objectives_;
  unsigned algorithm_seed_ = 0, population_seed_ = 0;
  std::vector<Value> log_;  // every evaluation, in pagmo's order
  bool finished_ = false;
};

// ---------------------------------------------------------------------------------------------

std::shared_ptr<const schema::Object<Sizes>> sizes_shape() {
  static const auto shape = std::make_shared<const schema::Object<Sizes>>(
      schema::Object<Sizes>()
          .integer("population", &Sizes::population, IntRange{1, kMaxPopulation},
                   "members of pagmo's population (some algorithms need more; see `name`)")
          .integer("generations", &Sizes::generations, IntRange{0, kMaxGenerations},
                   "generations after the initial population (pagmo's gen)"));
  return shape;
}

class PagmoSettings final : public AlgorithmSettings {
 public:
  PagmoSettings(const Entry* entry, Sizes sizes, json settings)
      : entry_(entry), sizes_(sizes), settings_(std::move(settings)) {}

  std::string type() const override { return "pagmo"; }
  json to_json() const override {
    json j = sizes_shape()->write(sizes_);
    j["type"] = "pagmo";
    j["name"] = entry_->info().name;
    j["settings"] = settings_;
    return j;
  }
  int population() const override { return sizes_.population; }
  int iterations() const override { return sizes_.generations; }
  std::int64_t evaluations() const override {
    return entry_->evaluations_until(sizes_.population, sizes_.generations);
  }
  std::vector<std::string> history_columns() const override {
    if (entry_->info().front) return {"generation_feasible", "generation_diverged"};
    return {"generation_mean_objective", "generation_diverged"};
  }
  std::vector<FieldError> validate(const std::string& path) const override {
    Errors errs;
    sizes_shape()->validate(sizes_, path, errs);
    if (errs.empty()) entry_->check(settings_, sizes_, path, errs);
    return errs;
  }
  std::unique_ptr<Optimizer> make(std::uint64_t seed, const SearchSpace& space) const override {
    if (entry_->info().front)
      throw InputError("job", "/tuning/algorithm/name",
                       "pagmo's " + entry_->info().name +
                           " searches a Pareto front: give the job two or more soft goals "
                           "(\"minimize\": true), or name an algorithm of one objective");
    return std::make_unique<PagmoOptimizer<double>>(*entry_, settings_, sizes_, seed, space);
  }
  bool searches_front() const override { return entry_->info().front; }
  std::vector<FieldError> validate_front(std::size_t objectives,
                                         const std::string& path) const override {
    Errors errs;
    if (entry_->info().front) entry_->check_front(settings_, sizes_, objectives, path, errs);
    return errs;
  }
  std::unique_ptr<Optimizer> make_front(std::uint64_t seed, const SearchSpace& space,
                                        std::size_t objectives) const override {
    if (!entry_->info().front) return AlgorithmSettings::make_front(seed, space, objectives);
    return std::make_unique<PagmoOptimizer<ObjectiveVector>>(*entry_, settings_, sizes_, seed,
                                                             space, objectives);
  }
  AlgorithmPtr with_budget(std::int64_t budget) const override {
    const std::int64_t per = entry_->per_generation(sizes_.population);
    if (budget < sizes_.population + per) return nullptr;
    Sizes s = sizes_;
    s.generations = static_cast<int>(
        std::min<std::int64_t>((budget - sizes_.population) / per, kMaxGenerations));
    return std::make_shared<PagmoSettings>(entry_, s, settings_);
  }

 private:
  const Entry* entry_;
  Sizes sizes_;
  json settings_;
};

AlgorithmPtr parse_pagmo(const json& j, const std::string& path, Errors& errs) {
  Errors mine;
  Sizes sizes;
  sizes_shape()->read_object(j, path, sizes, mine, {"type", "name", "settings"});
  const Entry* e = nullptr;
  const auto name = j.find("name");
  if (name == j.end()) {
    mine.push_back({path + "/name", "is required (one of " + known_names() + ")"});
  } else if (!name->is_string()) {
    mine.push_back({path + "/name", schema::detail::type_error("a string", *name)});
  } else if (!(e = find_entry(name->get<std::string>()))) {
    mine.push_back({path + "/name", "unknown pagmo algorithm \"" + name->get<std::string>() +
                                        "\" (known: " + known_names() + ")"});
  }
  const json* settings = nullptr;
  if (const auto it = j.find("settings"); it != j.end()) {
    if (it->is_object())
      settings = &*it;
    else
      mine.push_back({path + "/settings", schema::detail::type_error("an object", *it)});
  }
  json resolved;
  if (e) resolved = e->read(settings, path + "/settings", mine);
  if (e) {
    // The sizes whatever else is wrong: an unknown setting must not hide a population too small
    // for the algorithm (checked with the default settings where the given ones cannot be read).
    Errors sizing;
    sizes_shape()->validate(sizes, path, sizing);
    if (sizing.empty()) {
      Errors unused;
      e->check(resolved.is_null() ? e->read(nullptr, path + "/settings", unused) : resolved, sizes,
               path, sizing);
    }
    schema::detail::dedupe_append(mine, std::move(sizing));
  }
  if (mine.empty()) {
    // The rules above mirror pagmo's own checks; should pagmo still refuse, say so as bad input.
    try {
      e->make(resolved, sizes.generations, 0);
    } catch (const std::exception& ex) {
      mine.push_back({path + "/settings", "pagmo refuses these settings: " + pagmo_message(ex)});
    }
  }
  const bool ok = mine.empty();
  errs.insert(errs.end(), mine.begin(), mine.end());
  if (!ok) return nullptr;
  return std::make_shared<PagmoSettings>(e, sizes, std::move(resolved));
}

json pagmo_schema() {
  json cases = json::array();
  for (const auto& e : entries()) {
    const PagmoAlgorithmInfo& info = e->info();
    cases.push_back(sizes_shape()->object_schema(
        {{"type", {{"const", "pagmo"}}},
         {"name", {{"const", info.name}, {"description", info.description}}},
         {"settings", e->settings_schema()}},
        {"type", "name"}));
  }
  return {{"type", "object"},
          {"description", "an algorithm of pagmo2, by name, with its own settings"},
          {"oneOf", cases}};
}

}  // namespace

namespace {

const std::vector<PagmoAlgorithmInfo>& module_algorithms() {
  static const std::vector<PagmoAlgorithmInfo> all = [] {
    std::vector<PagmoAlgorithmInfo> v;
    for (const auto& e : entries()) v.push_back(e->info());
    return v;
  }();
  return all;
}

AlgorithmInfo module_info() {
  AlgorithmInfo info;
  info.type = "pagmo";
  info.description = "an algorithm of pagmo2 (" + known_names() +
                     "; nsga2, moead, nspso and maco search the Pareto front of two or more soft "
                     "goals)";
  info.parse = parse_pagmo;
  info.schema = pagmo_schema;
  return info;
}

}  // namespace

}  // namespace ftc::tune

// The module's one exported symbol (the target builds with hidden visibility).
namespace ftc::tune {
namespace {
double module_hypervolume(const std::vector<std::vector<double>>& points,
                          const std::vector<double>& reference) {
  return ::pagmo::hypervolume(points, true).compute(reference);
}
}  // namespace
}  // namespace ftc::tune

extern "C" [[gnu::visibility("default")]] const ftc::tune::pagmo_plugin::Api*
ftctune_pagmo_plugin() {
  static const ftc::tune::pagmo_plugin::Api api{FTC_BUILD_ID, ftc::tune::module_algorithms,
                                                ftc::tune::module_info,
                                                ftc::tune::module_hypervolume};
  return &api;
}
