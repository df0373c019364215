#include "ftc/tune/run/front.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <numeric>
#include <stdexcept>

#include "ftc/runtime/json_reader.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/metrics_record.hpp"
#include "ftc/tune/job/ensemble.hpp"
#include "ftc/tune/optimizers/hypervolume.hpp"
#include "ftc/tune/optimizers/pareto_bat.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/tuning_run.hpp"

namespace ftc::tune {

using json_io::json_number;
using nlohmann::json;

namespace {

std::vector<std::size_t> soft_goals(const Job& job) {
  std::vector<std::size_t> soft;
  for (std::size_t k = 0; k < job.goals.size(); ++k)
    if (job.goals[k].soft()) soft.push_back(k);
  return soft;
}

ObjectiveVector soft_vector(const Trial& t, const std::vector<std::size_t>& soft) {
  ObjectiveVector o;
  for (std::size_t k : soft)
    o.values.push_back(k < t.goals.size() ? t.goals[k] : std::numeric_limits<double>::quiet_NaN());
  o.violation = t.violation;
  return o;
}

std::vector<std::vector<double>> log_points(const Front& f) {
  std::vector<std::vector<double>> p;
  for (const FrontPoint& x : f.points) p.push_back(log_soft_goals(x.goals, f.soft));
  return p;
}

// The knee of log10 points (rule in front.hpp).
std::size_t knee_of(const std::vector<std::vector<double>>& p) {
  if (p.size() <= 2) return 0;
  const std::size_t m = p[0].size();
  std::vector<double> lo(m, std::numeric_limits<double>::infinity()),
      hi(m, -std::numeric_limits<double>::infinity());
  for (const auto& x : p)
    for (std::size_t k = 0; k < m; ++k) {
      lo[k] = std::min(lo[k], x[k]);
      hi[k] = std::max(hi[k], x[k]);
    }
  std::vector<std::vector<double>> n = p;
  for (auto& x : n)
    for (std::size_t k = 0; k < m; ++k) x[k] = hi[k] > lo[k] ? (x[k] - lo[k]) / (hi[k] - lo[k]) : 0;
  // The extremes: the best of the first soft goal (index 0, the sort order) and of the second.
  std::size_t b = 0;
  for (std::size_t i = 1; i < n.size(); ++i)
    if (n[i][1] < n[b][1]) b = i;
  std::vector<double> u(m);
  double len = 0;
  for (std::size_t k = 0; k < m; ++k) {
    u[k] = n[b][k] - n[0][k];
    len += u[k] * u[k];
  }
  len = std::sqrt(len);
  std::size_t best = 0;
  double far = -1;
  for (std::size_t i = 0; i < n.size(); ++i) {
    std::vector<double> d(m);
    double along = 0;
    for (std::size_t k = 0; k < m; ++k) {
      d[k] = n[i][k] - n[0][k];
      if (len > 0) along += d[k] * u[k] / len;
    }
    double dist = 0;
    for (std::size_t k = 0; k < m; ++k) {
      const double r = d[k] - (len > 0 ? along * u[k] / len : 0.0);
      dist += r * r;
    }
    if (dist > far) {
      far = dist;
      best = i;
    }
  }
  return best;
}

[[noreturn]] void refuse(const std::string& path, const std::string& message) {
  throw InputError("pick", path, message);
}

// The goal named by a metric in a rule.
std::size_t goal_named(const Job& job, const std::string& metric) {
  for (std::size_t k = 0; k < job.goals.size(); ++k)
    if (metric == job.goals[k].metric->name) return k;
  std::string known;
  for (const GoalConfig& g : job.goals)
    known += (known.empty() ? "" : ", ") + std::string(g.metric->name);
  refuse("/rule", "no goal of the job is \"" + metric + "\" (its goals: " + known + ")");
}

double parse_number(const std::string& text, const std::string& what) {
  // A decimal number as a user types it: std::stod alone would also take "0x2", " 2" and "inf".
  const bool decimal =
      !text.empty() && text.find_first_not_of("0123456789+-.eE") == std::string::npos;
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (!decimal || used != text.size() || !std::isfinite(v))
    refuse("/rule", what + " \"" + text + "\" is not a number");
  return v;
}

}  // namespace

FrontGoal front_goal(const Job& job, std::size_t k) {
  const GoalConfig& g = job.goals.at(k);
  FrontGoal out;
  out.label =
      measure_label(job.scenario_count(), sim::plain_label(*g.metric), g.measure(), g.windowed());
  out.unit = g.metric->unit;
  if (out.unit.rfind("the ", 0) == 0) out.unit.erase(0, 4);  // "the command's unit"
  out.at_most = g.at_most;
  return out;
}

std::vector<double> log_soft_goals(const std::vector<double>& goals,
                                   const std::vector<std::size_t>& soft) {
  std::vector<double> out;
  for (std::size_t k : soft) out.push_back(pareto::log_value(goals.at(k)));
  return out;
}

namespace {

// The non-dominated set of the feasible uncapped trials offered so far whose soft goals are all
// finite, one trial per distinct vector of soft goals (the first offered), ordered by the vector
// (lexicographic). A capped trial's goals are bounds; capping stopped it only because it is
// infeasible or an earlier trial dominates it (issue 42), so leaving it out changes nothing.
// Offering a trial costs one pass over the set: a trial dominated by a member, or equal to one, is
// not kept; the members it dominates leave (a trial they dominated is dominated by it too, so no
// trial that left ever returns).
class NonDominated {
 public:
  explicit NonDominated(std::vector<std::size_t> soft) : soft_(std::move(soft)) {}

  void offer(const std::vector<Trial>& trials, std::size_t i) {
    if (trials[i].capped) return;
    ObjectiveVector o = soft_vector(trials[i], soft_);
    if (!o.feasible() ||
        !std::all_of(o.values.begin(), o.values.end(), [](double v) { return std::isfinite(v); }))
      return;
    if (members_.count(o.values)) return;
    for (const auto& [values, index] : members_)
      if (pareto::dominates(ObjectiveVector{values, 0.0}, o)) return;
    for (auto it = members_.begin(); it != members_.end();)
      it = pareto::dominates(o, ObjectiveVector{it->first, 0.0}) ? members_.erase(it)
                                                                 : std::next(it);
    members_.emplace(std::move(o.values), i);
  }
  std::vector<std::size_t> indices() const {
    std::vector<std::size_t> out;
    out.reserve(members_.size());
    for (const auto& [values, index] : members_) out.push_back(index);
    return out;
  }

 private:
  std::vector<std::size_t> soft_;
  std::map<std::vector<double>, std::size_t> members_;
};

}  // namespace

std::vector<std::size_t> front_trials(const Job& job, const std::vector<Trial>& trials,
                                      std::size_t count) {
  NonDominated front(soft_goals(job));
  for (std::size_t i = 0; i < std::min(count, trials.size()); ++i) front.offer(trials, i);
  return front.indices();
}

std::vector<double> reference_point(const std::vector<std::vector<double>>& p) {
  if (p.empty()) return {};
  std::vector<double> r(p[0].size(), -std::numeric_limits<double>::infinity());
  for (const auto& x : p)
    for (std::size_t k = 0; k < r.size(); ++k) r[k] = std::max(r[k], x[k]);
  for (double& v : r) v += kReferenceMarginDecades;
  return r;
}

std::vector<double> hypervolume_history(const Job& job, const std::vector<Trial>& trials,
                                        const std::vector<double>& reference, int last) {
  const std::vector<std::size_t> soft = soft_goals(job);
  // The front after each iteration, kept across iterations: each offers only its own trials.
  NonDominated front(soft);
  std::vector<double> hv;
  std::size_t count = 0;
  for (int it = 0; it <= last; ++it) {
    for (; count < trials.size() && trials[count].iteration <= it; ++count)
      front.offer(trials, count);
    std::vector<std::vector<double>> p;
    for (std::size_t i : front.indices()) p.push_back(log_soft_goals(trials[i].goals, soft));
    hv.push_back(reference.empty() ? 0.0 : hypervolume(p, reference));
  }
  return hv;
}

Front make_front(const Job& job, const std::vector<Trial>& trials) {
  Front f;
  for (std::size_t k = 0; k < job.goals.size(); ++k) f.goals.push_back(front_goal(job, k));
  f.soft = soft_goals(job);
  for (std::size_t i : front_trials(job, trials, trials.size())) {
    FrontPoint p;
    p.parameters = trials[i].parameters;
    p.goals = trials[i].goals;
    p.violation = trials[i].violation;
    p.trial = i;
    p.noise_floor.assign(job.goals.size(), std::nullopt);
    f.points.push_back(std::move(p));
  }
  const std::vector<std::vector<double>> lp = log_points(f);
  f.reference = reference_point(lp);
  f.hypervolume = f.reference.empty() ? 0.0 : hypervolume(lp, f.reference);
  f.picked = lp.empty() ? 0 : knee_of(lp);
  return f;
}

bool within_noise_floor(const Front& front, std::size_t a, std::size_t b) {
  const FrontPoint &p = front.points.at(a), &q = front.points.at(b);
  for (std::size_t k : front.soft) {
    const auto floor = [k](const FrontPoint& x) -> std::optional<double> {
      const std::optional<double> s = k < x.noise_floor.size() ? x.noise_floor[k] : std::nullopt;
      if (!s || !std::isfinite(*s) || !std::isfinite(x.goals[k])) return std::nullopt;
      return *s * std::abs(x.goals[k]);
    };
    const std::optional<double> fp = floor(p), fq = floor(q);
    if (!fp && !fq) return false;
    if (!(std::abs(p.goals[k] - q.goals[k]) <= std::max(fp.value_or(0.0), fq.value_or(0.0))))
      return false;
  }
  return true;
}

bool no_trade_off(const Front& front, std::size_t a, std::size_t b) {
  const FrontPoint &p = front.points.at(a), &q = front.points.at(b);
  return p.within_noise_of == b || q.within_noise_of == a || within_noise_floor(front, a, b);
}

namespace {

// Each point's partners by the rule (no_trade_off), from its floors and within_noise_of.
void list_partners(Front& front) {
  for (std::size_t a = 0; a < front.points.size(); ++a) {
    front.points[a].within_noise.clear();
    for (std::size_t b = 0; b < front.points.size(); ++b)
      if (b != a && no_trade_off(front, a, b)) front.points[a].within_noise.push_back(b);
  }
}

}  // namespace

void apply_noise_floor(Front& front,
                       const std::vector<std::vector<std::optional<double>>>& spreads) {
  for (std::size_t i = 0; i < front.points.size() && i < spreads.size(); ++i)
    front.points[i].noise_floor = spreads[i];
  for (std::size_t i = 0; i < front.points.size(); ++i)
    front.points[i].within_noise_of =
        i > 0 && within_noise_floor(front, i - 1, i)
            ? std::optional<std::size_t>(front.points[i - 1].within_noise_of.value_or(i - 1))
            : std::nullopt;
  list_partners(front);
}

// The points the knee, min and limit choose among: all, but on a held-out front those its
// held-out values keep on it.
void mark_dominated_by_compared(Front& front) {
  for (FrontPoint& p : front.points) {
    p.dominated_by.reset();
    for (const FrontCompared& c : front.compared) {
      if (!c.feasible || c.goals.size() != p.goals.size()) continue;
      bool no_worse = true, better = false;
      for (std::size_t k : front.soft) {
        no_worse = no_worse && c.goals[k] <= p.goals[k];  // false for NaN
        better = better || c.goals[k] < p.goals[k];
      }
      if (no_worse && better) {
        p.dominated_by = c.label;
        break;
      }
    }
  }
}

std::string dominated_warning(const Front& front, std::size_t i) {
  if (i >= front.points.size() || !front.points[i].dominated_by) return "";
  const FrontPoint& p = front.points[i];
  const std::string& label = *p.dominated_by;
  // Each soft goal's two values, and where the controller is better, by how much against the
  // point's noise floor there: a difference inside it is no difference.
  std::string values;
  for (const FrontCompared& c : front.compared)
    if (c.label == label)
      for (std::size_t k : front.soft) {
        char buf[240];
        int n = std::snprintf(buf, sizeof buf, "%s%s %.4g against %.4g",
                              values.empty() ? "" : ", ", front.goals[k].label.c_str(),
                              c.goals[k], p.goals[k]);
        if (c.goals[k] < p.goals[k] && k < p.noise_floor.size() && p.noise_floor[k] &&
            n > 0 && static_cast<std::size_t>(n) < sizeof buf)
          std::snprintf(buf + n, sizeof buf - static_cast<std::size_t>(n),
                        ", %.3g %% better, %s the point's noise floor of %.2g %%",
                        100 * (p.goals[k] - c.goals[k]) / std::abs(p.goals[k]),
                        (p.goals[k] - c.goals[k]) / std::abs(p.goals[k]) > *p.noise_floor[k]
                            ? "beyond"
                            : "inside",
                        100 * *p.noise_floor[k]);
        values += buf;
      }
  return std::string(kDominatedWarningPrefix) + std::to_string(i) + kDominatedWarningVerb +
         label + " (" + values +
         "): that controller is no worse on every soft goal and better on one, so these gains "
         "trade nothing for what they give up; pick another point or keep " + label;
}

bool is_dominated_warning(std::string_view w) {
  return w.rfind(kDominatedWarningPrefix, 0) == 0 &&
         w.find(kDominatedWarningVerb) != std::string_view::npos;
}

std::vector<std::size_t> on_front(const Front& front) {
  std::vector<std::size_t> on;
  for (std::size_t i = 0; i < front.points.size(); ++i)
    if (!front.points[i].dominated) on.push_back(i);
  return on;
}

// knee_of takes the points in the front's order (by the first soft goal, then the others); a
// held-out front keeps the run's order, which its held-out values may not follow.
std::size_t knee_among(const Front& front, std::vector<std::size_t> on) {
  std::vector<std::vector<double>> lp(front.points.size());
  for (std::size_t i : on) lp[i] = log_soft_goals(front.points[i].goals, front.soft);
  if (front.held_out)
    std::stable_sort(on.begin(), on.end(),
                     [&](std::size_t a, std::size_t b) { return lp[a] < lp[b]; });
  std::vector<std::vector<double>> ordered;
  for (std::size_t i : on) ordered.push_back(lp[i]);
  return on.at(knee_of(ordered));
}

std::size_t pick_point(const Job& job, const Front& front, const std::string& rule) {
  if (front.points.empty()) refuse("/rule", "the front has no point");
  const std::vector<FrontPoint>& p = front.points;
  const std::vector<std::size_t> on = on_front(front);
  if (on.empty() && rule.rfind("index:", 0) != 0) {
    std::size_t infeasible = 0;
    for (const FrontPoint& x : p) infeasible += x.feasible() ? 0 : 1;
    refuse("/rule", "no point stays on the held-out front (" + std::to_string(infeasible) +
                        " of " + std::to_string(p.size()) +
                        " break a hard goal there, the others are dominated or not finite): "
                        "only index:N picks one");
  }
  if (rule == "knee") return knee_among(front, on);
  const auto colon = rule.find(':');
  const std::string kind = rule.substr(0, colon),
                    arg = colon == std::string::npos ? "" : rule.substr(colon + 1);
  if (colon != std::string::npos && kind == "index") {
    const double n = parse_number(arg, "index");
    if (n != std::floor(n) || n < 0 || n >= static_cast<double>(p.size()))
      refuse("/rule", "index " + arg + " is not a point of the front (0.." +
                          std::to_string(p.size() - 1) + ")");
    return static_cast<std::size_t>(n);
  }
  if (colon != std::string::npos && kind == "min") {
    const std::size_t g = goal_named(job, arg);
    std::size_t best = on.front();
    for (std::size_t i : on)
      if (p[i].goals[g] < p[best].goals[g]) best = i;
    return best;
  }
  if (colon != std::string::npos && kind == "limit") {
    const auto le = arg.find("<=");
    if (le == std::string::npos) refuse("/rule", "expected limit:METRIC<=X, got \"" + rule + "\"");
    const std::size_t g = goal_named(job, arg.substr(0, le));
    const double x = parse_number(arg.substr(le + 2), "limit");
    // Of the points within the limit, the least in the first soft goal that is not this one.
    std::size_t by = front.soft.empty() ? g : front.soft[0];
    for (std::size_t k : front.soft)
      if (k != g) {
        by = k;
        break;
      }
    std::optional<std::size_t> best;
    for (std::size_t i : on)
      if (p[i].goals[g] <= x && (!best || p[i].goals[by] < p[*best].goals[by])) best = i;
    if (!best)
      refuse("/rule",
             "no point of the front has " + arg.substr(0, le) + " <= " + json_io::number_text(x));
    return *best;
  }
  refuse("/rule", "expected knee, min:METRIC, limit:METRIC<=X or index:N, got \"" + rule + "\"");
}

Front held_out_front(const Job& job, Front f, FrontHeldOut where,
                     const std::vector<std::vector<double>>& goals,
                     std::vector<FrontCompared> compared) {
  where.in_sample_hypervolume = f.hypervolume;
  // The goals' labels count the held-out scenarios ("CVaR0.9 of ISE[...] over 1001 scenarios").
  Job held = job;
  if (held.ensemble) {
    auto members = std::make_shared<EnsembleConfig>(*held.ensemble);
    members->count = where.count;
    held.ensemble = std::move(members);
  }
  for (std::size_t k = 0; k < f.goals.size() && k < job.goals.size(); ++k)
    f.goals[k].label = front_goal(held, k).label;
  std::vector<ObjectiveVector> o;
  for (std::size_t i = 0; i < f.points.size(); ++i) {
    FrontPoint& p = f.points[i];
    p.in_sample = p.goals;
    p.goals = goals.at(i);
    p.violation = 0.0;
    for (std::size_t k = 0; k < job.goals.size(); ++k)
      p.violation += job.goals[k].violation(p.goals[k]);
    ObjectiveVector v;
    for (std::size_t k : f.soft) v.values.push_back(p.goals[k]);
    v.violation = p.violation;
    o.push_back(std::move(v));
  }
  std::vector<std::vector<double>> kept;
  for (std::size_t i = 0; i < f.points.size(); ++i) {
    FrontPoint& p = f.points[i];
    bool finite = true;
    for (double x : o[i].values) finite = finite && std::isfinite(x);
    p.dominated = !p.feasible() || !finite;
    for (std::size_t j = 0; j < f.points.size() && !p.dominated; ++j)
      p.dominated = j != i && pareto::dominates(o[j], o[i]);
    if (!p.dominated) kept.push_back(log_soft_goals(p.goals, f.soft));
  }
  // Against the run's reference point, so that the two hypervolumes compare (a point beyond it
  // adds nothing).
  f.hypervolume = kept.empty() ? 0.0 : hypervolume(kept, f.reference);
  f.held_out = where;  // before the knee, which takes the held-out values' order
  const std::vector<std::size_t> on = on_front(f);
  f.picked = on.empty() ? 0 : knee_among(f, on);
  f.rule = "knee";
  // The run's floors, the held-out values: which points the held-out values cannot tell apart
  // (neighbours in the run's order).
  std::vector<std::vector<std::optional<double>>> floors;
  for (const FrontPoint& p : f.points) floors.push_back(p.noise_floor);
  apply_noise_floor(f, floors);
  f.compared = std::move(compared);
  mark_dominated_by_compared(f);
  return f;
}

std::string front_rule_text(const Front& front) {
  const std::string rule =
      front.rule == "knee"
          ? "the knee (with each soft goal's log10 normalised to [0, 1] over the front, the point "
            "farthest from the line through the best points of the first two soft goals)"
          : front.rule;
  return "point " + std::to_string(front.picked) + " of the Pareto front of " +
         std::to_string(front.points.size()) +
         " feasible non-dominated trials (front.json), chosen by " + rule;
}

std::string front_summary(const Job& job, const Front& front, const std::filesystem::path& out) {
  const auto value = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return std::string(buf);
  };
  std::string s;
  if (front.points.empty()) {
    bool hard = false;
    for (const GoalConfig& g : job.goals) hard = hard || !g.soft();
    return std::string("  front: empty: no trial ") +
           (hard ? "met the hard goals with" : "had") +
           " a finite value of every soft goal, so no point was picked (front.json)\n";
  }
  if (front.held_out) {
    const std::vector<std::size_t> on = on_front(front);
    std::size_t infeasible = 0;
    for (const FrontPoint& x : front.points) infeasible += x.feasible() ? 0 : 1;
    s += "  held-out front: " + std::to_string(on.size()) + " of the run's " +
         std::to_string(front.points.size()) + " points stay on it (" +
         std::to_string(infeasible) + " break a hard goal there), hypervolume " +
         value(front.hypervolume) + " against the run's reference point (in the run: " +
         value(front.held_out->in_sample_hypervolume) + ")";
    if (on.empty()) return s + "\n";
    const FrontPoint& k = front.points[front.picked];
    s += "; its knee is point " + std::to_string(front.picked) + ":";
    for (std::size_t g : front.soft)
      s += (g == front.soft.front() ? " " : ", ") + front.goals[g].label + " = " +
           value(k.goals[g]) + " (run: " + value(k.in_sample[g]) + ")";
    s += "\n  its gains: ftctune pick " + out.string() + " --rule knee (or min:METRIC, "
         "limit:METRIC<=X, index:N)\n";
    return s;
  }
  const FrontPoint& p = front.points[front.picked];
  s += "  front: " + std::to_string(front.points.size()) + " point" +
       (front.points.size() == 1 ? "" : "s") + ", hypervolume " + value(front.hypervolume) +
       " (log10 of the soft goals); gains.json holds point " + std::to_string(front.picked) +
       " (" + (front.rule == "knee" ? std::string("the knee") : front.rule) + "):";
  for (std::size_t k : front.soft)
    s += (k == front.soft.front() ? " " : ", ") + front.goals[k].label + " = " + value(p.goals[k]);
  s += "\n  another point: ftctune pick " + out.string() + " --rule min:" +
       std::string(job.goals[front.soft.back()].metric->name) + " (or limit:METRIC<=X, index:N)\n";
  std::size_t dominated = 0;
  for (const FrontPoint& x : front.points) dominated += x.dominated_by ? 1 : 0;
  if (dominated > 0)
    s += "  " + std::to_string(dominated) + " of the " + std::to_string(front.points.size()) +
         " points are dominated by a compared controller (dominated_by in front.json and "
         "front.csv): taking one gives up something for nothing\n";
  return s;
}

json front_document(const Job& job, const std::string& job_sha256, std::uint64_t seed,
                    const Front& front) {
  json goals = json::array();
  for (std::size_t k = 0; k < job.goals.size(); ++k) {
    json g = to_json(job.goals[k]);
    g["label"] = front.goals.at(k).label;
    g["unit"] = front.goals.at(k).unit;
    goals.push_back(std::move(g));
  }
  json compared = json::array();
  for (const FrontCompared& c : front.compared) {
    json values = json::array();
    for (double v : c.goals) values.push_back(json_number(v));
    compared.push_back(
        {{"label", c.label}, {"role", c.role}, {"goals", values}, {"feasible", c.feasible}});
  }
  json reference = json::array();
  for (double r : front.reference) reference.push_back(json_number(r));
  json points = json::array();
  const std::vector<std::string> names =
      job.tuning ? [&] {
        std::vector<std::string> n;
        for (const ParameterBounds& b : job.tuning->parameters) n.push_back(b.name);
        return n;
      }()
                 : std::vector<std::string>{};
  for (const FrontPoint& p : front.points) {
    json parameters = json::object();
    for (std::size_t j = 0; j < p.parameters.size() && j < names.size(); ++j)
      parameters[names[j]] = json_number(p.parameters[j]);
    json values = json::array(), noise = json::array();
    for (double v : p.goals) values.push_back(json_number(v));
    for (const std::optional<double>& n : p.noise_floor)
      noise.push_back(n ? json_number(*n) : json());
    json point = {{"parameters", parameters},      {"goals", values},
                  {"feasible", p.feasible()},      {"violation", json_number(p.violation)},
                  {"noise_floor", noise},          {"trial", p.trial},
                  {"within_noise", p.within_noise}};
    if (p.within_noise_of) point["within_noise_of"] = *p.within_noise_of;
    if (p.dominated_by) point["dominated_by"] = *p.dominated_by;
    if (front.held_out) {
      json in_sample = json::array();
      for (double v : p.in_sample) in_sample.push_back(json_number(v));
      point["in_sample"] = std::move(in_sample);
      point["dominated"] = p.dominated;
    }
    points.push_back(std::move(point));
  }
  json doc = {{"schema", kFrontSchema},
          {"job", job.name},
          {"job_sha256", job_sha256},
          {"seed", seed},
          {"goals", goals},
          {"space", "log10"},
          {"reference_point", reference},
          {"hypervolume", json_number(front.hypervolume)},
          {"picked", front.points.empty() || (front.held_out && on_front(front).empty())
                         ? json()  // no feasible trial (or none held out): nothing to pick
                         : json{{"index", front.picked}, {"rule", front.rule}}},
          {"compared", compared},
          {"points", points}};
  if (front.held_out)
    doc["held_out"] = {{"run", front.held_out->run},
                       {"seed", front.held_out->seed},
                       {"count", front.held_out->count},
                       {"in_sample_hypervolume", json_number(front.held_out->in_sample_hypervolume)}};
  return doc;
}

std::string front_csv(const Job& job, const Front& front) {
  std::string s = "index";
  std::vector<std::string> labels;
  for (const GoalConfig& g : job.goals) labels.push_back(std::string(g.metric->name));
  // Two goals of one metric (other windows) are told apart by their position.
  for (std::size_t k = 0; k < labels.size(); ++k)
    if (std::count(labels.begin(), labels.end(), labels[k]) > 1)
      labels[k] += "_" + std::to_string(k);
  if (job.tuning)
    for (const ParameterBounds& b : job.tuning->parameters) s += "," + b.name;
  for (const std::string& l : labels) s += "," + l;
  s += ",feasible,violation";
  for (const std::string& l : labels) s += "," + l + "_noise_floor";
  s += ",trial,dominated_by\n";
  const auto num = [](double v) -> std::string {  // exact (round-trip) digits, as history.csv
    if (std::isnan(v)) return "";
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    char buf[48];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
  };
  for (std::size_t i = 0; i < front.points.size(); ++i) {
    const FrontPoint& p = front.points[i];
    s += std::to_string(i);
    for (double x : p.parameters) s += "," + num(x);
    for (double g : p.goals) s += "," + num(g);
    s += std::string(",") + (p.violation > 0 ? "false" : "true") + "," + num(p.violation);
    for (const std::optional<double>& n : p.noise_floor) s += "," + (n ? num(*n) : std::string());
    s += "," + std::to_string(p.trial) + ",";
    if (p.dominated_by) {  // RFC 4180: a label with a comma, a quote or a line break is quoted
      const std::string& l = *p.dominated_by;
      if (l.find_first_of(",\"\r\n") == std::string::npos) {
        s += l;
      } else {
        s += '"';
        for (char ch : l) s += ch == '"' ? std::string("\"\"") : std::string(1, ch);
        s += '"';
      }
    }
    s += "\n";
  }
  return s;
}

Front front_from_json(const Job& job, const json& j, const std::string& source) {
  const auto fail = [&](const std::string& path, const std::string& m) {
    throw InputError(source, path, m);
  };
  // A value that may be null: one that does not exist, or a diverged run's (`if_null`).
  const auto number = [&](const json& v, const std::string& path, double if_null) {
    if (v.is_null()) return if_null;
    if (!v.is_number()) fail(path, "expected a number or null");
    return v.get<double>();
  };
  const auto member = [&](const json& o, const char* key, const std::string& path) -> const json& {
    if (!o.is_object()) fail(path, "expected an object");
    if (!o.contains(key)) fail(path + "/" + key, "is missing");
    return o[key];
  };
  const auto boolean = [&](const json& o, const char* key, const std::string& path) {
    const json& b = member(o, key, path);
    if (!b.is_boolean()) fail(path + "/" + key, "expected true or false");
    return b.get<bool>();
  };
  const std::size_t G = job.goals.size();
  // The job's count of goal values (null: +inf).
  const auto goal_values = [&](const json& o, const std::string& path) {
    const json& a = member(o, "goals", path);
    if (!a.is_array() || a.size() != G)
      fail(path + "/goals", "expected " + std::to_string(G) + " values");
    std::vector<double> v;
    for (std::size_t k = 0; k < G; ++k)
      v.push_back(number(a[k], path + "/goals/" + std::to_string(k), INFINITY));
    return v;
  };
  // An index: an integral number >= 0 (none: not one).
  const auto index_of = [](const json& v) -> std::optional<std::size_t> {
    long long k = -1;
    if (!json_io::json_to_int(v, k) || k < 0) return std::nullopt;
    return static_cast<std::size_t>(k);
  };
  // An index of another point than `self` among `count`.
  const auto other_point = [&](const json& v, const std::string& path, std::size_t self,
                               std::size_t count) {
    const std::optional<std::size_t> k = index_of(v);
    if (!k || *k >= count || *k == self) fail(path, "is not the index of another point");
    return *k;
  };

  if (!j.is_object()) fail("", "is not a JSON object (damaged output?)");
  if (j.value("schema", json()) != kFrontSchema)
    fail("/schema", std::string("expected \"") + kFrontSchema + "\"");
  Front f;
  f.soft = soft_goals(job);
  if (f.soft.size() < 2)
    fail("/goals",
         "a front needs two or more soft goals; the job has " + std::to_string(f.soft.size()));
  const json& goals = member(j, "goals", "");
  if (!goals.is_array() || goals.size() != G)
    fail("/goals", "expected the job's " + std::to_string(G) + " goals");
  for (std::size_t k = 0; k < G; ++k) {
    const std::string at = "/goals/" + std::to_string(k);
    const json& metric = member(goals[k], "metric", at);
    if (!metric.is_string() || metric.get<std::string>() != job.goals[k].metric->name)
      fail(at + "/metric", "is not the job's goal " + std::to_string(k) + ", " +
                               std::string(job.goals[k].metric->name));
    FrontGoal g = front_goal(job, k);  // the words, unless the file has its own
    for (auto [key, text] : {std::pair{"label", &g.label}, std::pair{"unit", &g.unit}})
      if (goals[k].contains(key)) {
        if (!goals[k][key].is_string()) fail(at + "/" + key, "expected a string");
        *text = goals[k][key].get<std::string>();
      }
    f.goals.push_back(std::move(g));
  }

  const json& points = member(j, "points", "");
  if (!points.is_array()) fail("/points", "expected an array");
  const std::vector<std::string> names = [&] {
    std::vector<std::string> n;
    if (job.tuning)
      for (const ParameterBounds& b : job.tuning->parameters) n.push_back(b.name);
    return n;
  }();
  bool partners_given = true;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const json& p = points[i];
    const std::string at = "/points/" + std::to_string(i);
    FrontPoint x;
    const json& params = member(p, "parameters", at);
    for (const std::string& name : names)
      x.parameters.push_back(number(member(params, name.c_str(), at + "/parameters"),
                                    at + "/parameters/" + name, NAN));
    x.goals = goal_values(p, at);
    boolean(p, "feasible", at);  // written beside the violation, which it follows from
    x.violation =
        p.contains("violation") ? number(p["violation"], at + "/violation", INFINITY) : 0.0;
    const std::optional<std::size_t> trial = index_of(member(p, "trial", at));
    if (!trial) fail(at + "/trial", "expected a row of trials.csv");
    x.trial = *trial;
    x.noise_floor.assign(G, std::nullopt);
    if (p.contains("noise_floor")) {
      const json& noise = p["noise_floor"];
      if (!noise.is_array() || noise.size() != G)
        fail(at + "/noise_floor", "expected " + std::to_string(G) + " values");
      for (std::size_t k = 0; k < G; ++k)
        if (!noise[k].is_null())
          x.noise_floor[k] = number(noise[k], at + "/noise_floor/" + std::to_string(k), NAN);
    }
    if (p.contains("within_noise_of"))
      x.within_noise_of =
          other_point(p["within_noise_of"], at + "/within_noise_of", i, points.size());
    if (j.contains("held_out")) {
      const json& in_sample = member(p, "in_sample", at);
      if (!in_sample.is_array() || in_sample.size() != G)
        fail(at + "/in_sample", "expected " + std::to_string(G) + " values");
      for (std::size_t k = 0; k < G; ++k)
        x.in_sample.push_back(number(in_sample[k], at + "/in_sample/" + std::to_string(k), INFINITY));
      x.dominated = boolean(p, "dominated", at);
    }
    if (!p.contains("within_noise")) {
      partners_given = false;
    } else {
      const json& partners = p["within_noise"];
      if (!partners.is_array()) fail(at + "/within_noise", "expected an array");
      for (std::size_t k = 0; k < partners.size(); ++k)
        x.within_noise.push_back(
            other_point(partners[k], at + "/within_noise/" + std::to_string(k), i, points.size()));
    }
    f.points.push_back(std::move(x));
  }
  if (!partners_given) list_partners(f);  // a file from before the partners were written

  // A run with no feasible trial has an empty front, and no reference point to measure it by.
  const json& reference = member(j, "reference_point", "");
  if (!reference.is_array() ||
      (reference.empty() ? !f.points.empty() : reference.size() != f.soft.size()))
    fail("/reference_point", "expected " + std::to_string(f.soft.size()) +
                                 " numbers, one per soft goal (none for an empty front)");
  for (std::size_t k = 0; k < reference.size(); ++k) {
    f.reference.push_back(number(reference[k], "/reference_point/" + std::to_string(k), NAN));
    if (!std::isfinite(f.reference.back()))
      fail("/reference_point/" + std::to_string(k), "expected a number");
  }
  f.hypervolume = number(member(j, "hypervolume", ""), "/hypervolume", NAN);
  if (j.contains("held_out")) {
    const json& h = j["held_out"];
    FrontHeldOut where;
    const json& run = member(h, "run", "/held_out");
    if (!run.is_string() || run.get<std::string>().empty())
      fail("/held_out/run", "expected the run directory");
    where.run = run.get<std::string>();
    const json& seed = member(h, "seed", "/held_out");
    if (!seed.is_number_unsigned()) fail("/held_out/seed", "expected an integer >= 0");
    long long count = -1;
    if (!json_io::json_to_int(member(h, "count", "/held_out"), count) || count < 0)
      fail("/held_out/count", "expected an integer >= 0");
    where.seed = seed.get<std::uint64_t>();
    where.count = count;
    where.in_sample_hypervolume = number(member(h, "in_sample_hypervolume", "/held_out"),
                                         "/held_out/in_sample_hypervolume", NAN);
    f.held_out = std::move(where);
  }
  // null: no point was picked (an empty front, or a held-out one that keeps no point).
  const bool none_on = f.held_out && on_front(f).empty();
  if (j.contains("picked") && !(j["picked"].is_null() && (f.points.empty() || none_on))) {
    const std::optional<std::size_t> index = index_of(member(j["picked"], "index", "/picked"));
    if (!index || *index >= f.points.size()) fail("/picked/index", "is not the index of a point");
    f.picked = *index;
    const json& rule = member(j["picked"], "rule", "/picked");
    if (!rule.is_string()) fail("/picked/rule", "expected a string");
    f.rule = rule.get<std::string>();
  }
  if (j.contains("compared")) {
    if (!j["compared"].is_array()) fail("/compared", "expected an array");
    for (std::size_t i = 0; i < j["compared"].size(); ++i) {
      const std::string at = "/compared/" + std::to_string(i);
      const json& c = j["compared"][i];
      FrontCompared x;
      const json& label = member(c, "label", at);
      if (!label.is_string()) fail(at + "/label", "expected a string");
      x.label = label.get<std::string>();
      const json role = c.value("role", json("compare"));
      if (!role.is_string()) fail(at + "/role", "expected a string");
      x.role = role.get<std::string>();
      x.goals = goal_values(c, at);
      x.feasible = boolean(c, "feasible", at);
      f.compared.push_back(std::move(x));
    }
  }
  mark_dominated_by_compared(f);  // derived: the file's own field is not trusted
  return f;
}

namespace {

json read_json_file(const std::filesystem::path& file) {
  // The strict reader: a regular file only (a FIFO is not waited for, a directory is named), at
  // most kMaxInputFileBytes, duplicate keys and numbers beyond a double refused.
  const std::optional<std::string> text = json_io::read_file(file);
  if (!text)
    throw InputError(file.string(), "",
                     "cannot be read (is this a run directory of a job "
                     "with two or more soft goals?)");
  return json_io::parse_json_text(*text, file.string());
}

// A row of trials.csv as pick checks a front point against it.
struct TrialRow {
  std::vector<double> parameters, goals;
  double objective = 0, fitness = 0, violation = 0;
  bool capped = false, feasible = false;
};

// The longest line of trials.csv read: a row holds a few dozen numbers of at most 24 characters
// each, and one per scenario of a listed job; a longer line is not a row ftctune wrote.
constexpr std::size_t kMaxTrialsLine = std::size_t{16} << 20;

// The rows `wanted` of trials.csv (0: the first after the header), read in one pass; a row it
// does not have is an error of the front point that named it (front.json at
// /points/<point>/trial, `point_of` gives the point of each wanted row).
std::map<std::size_t, TrialRow> trial_rows(const std::filesystem::path& file, const Job& job,
                                           const std::map<std::size_t, std::size_t>& point_of,
                                           const std::string& front_source) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec))
    throw InputError(file.string(), "", "is not a regular file (is this a run directory?)");
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), "", "cannot be read");
  const auto split = [](const std::string& l) {
    std::vector<std::string> cells;
    std::size_t start = 0;
    for (std::size_t i = 0; i <= l.size(); ++i)
      if (i == l.size() || l[i] == ',') {
        cells.push_back(l.substr(start, i - start));
        start = i + 1;
      }
    return cells;
  };
  std::string line;
  const auto next_line = [&] {
    line.clear();
    for (char c; in.get(c) && c != '\n';) {
      line += c;
      if (line.size() > kMaxTrialsLine)
        throw InputError(file.string(), "",
                         "has a line longer than " + std::to_string(kMaxTrialsLine) +
                             " bytes: not a trials.csv ftctune wrote");
    }
    return !line.empty() || in.good();
  };
  if (!next_line()) throw InputError(file.string(), "", "has no header");
  const std::vector<std::string> header = split(line);
  const auto column = [&](const std::string& n) {
    const auto it = std::find(header.begin(), header.end(), n);
    if (it == header.end()) throw InputError(file.string(), "", "has no column " + n);
    return static_cast<std::size_t>(it - header.begin());
  };
  std::vector<std::size_t> parameter_columns, goal_columns;
  for (const ParameterBounds& b : job.tuning->parameters)
    parameter_columns.push_back(column(b.name));
  for (std::size_t k = 0; k < job.goals.size(); ++k)
    goal_columns.push_back(
        column("goal" + std::to_string(k) + "_" + std::string(job.goals[k].metric->name)));
  const std::size_t objective = column("objective"), fitness = column("fitness"),
                    capped = column("capped"), violation = column("violation"),
                    feasible = column("feasible");
  std::map<std::size_t, TrialRow> rows;
  std::size_t row = 0;
  for (const auto& [row_wanted, point] : point_of) {
    const std::size_t wanted = row_wanted;  // a lambda below captures it (not a binding)
    for (; row <= wanted; ++row)
      if (!next_line())
        throw InputError(front_source, "/points/" + std::to_string(point) + "/trial",
                         "is trial " + std::to_string(wanted) + ", a row " + file.string() +
                             " does not have");
    const std::vector<std::string> cells = split(line);
    const auto cell = [&](std::size_t k) {
      if (k >= cells.size())
        throw InputError(file.string(), "",
                         "row " + std::to_string(wanted) + " has " +
                             std::to_string(cells.size()) + " cells, the header " +
                             std::to_string(header.size()));
      const std::string& c = cells[k];
      if (c == "inf") return std::numeric_limits<double>::infinity();
      char* end = nullptr;
      const double v = c.empty() ? std::numeric_limits<double>::quiet_NaN()
                                 : std::strtod(c.c_str(), &end);
      if (!c.empty() && (end != c.c_str() + c.size()))
        throw InputError(file.string(), "",
                         "row " + std::to_string(wanted) + ", column " + header[k] + ": \"" +
                             c + "\" is not a number");
      return v;
    };
    TrialRow r;
    for (std::size_t k : parameter_columns) r.parameters.push_back(cell(k));
    for (std::size_t k : goal_columns) r.goals.push_back(cell(k));
    r.objective = cell(objective);
    r.fitness = cell(fitness);
    r.violation = cell(violation);
    r.capped = cell(capped) == 1;
    r.feasible = cell(feasible) == 1;
    rows.emplace(wanted, std::move(r));
  }
  return rows;
}

// Whether two numbers of the run's files are the same double (both NaN: the same).
bool same(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

// front.json carries authority: the gains pick writes are deployable. So every point must be a
// trial of this run, as trials.csv recorded it (its parameters and goal values bit for bit),
// within the job's bounds and feasible, and the file must be this job's (its job_sha256). A
// point that fails is an InputError at its path in front.json.
// `source`: the front.json checked (the run's, or a held-out front's, whose points' in_sample
// values are the ones the run recorded).
std::map<std::size_t, TrialRow> check_front_against_run(const std::filesystem::path& run,
                                                        const Job& job, const Front& front,
                                                        const std::string& source) {
  const auto fail = [&](const std::string& path, const std::string& m) {
    throw InputError(source, path, m);
  };
  const std::vector<ParameterBounds>& bounds = job.tuning->parameters;
  std::map<std::size_t, std::size_t> point_of;  // trial row -> first point naming it
  for (std::size_t i = 0; i < front.points.size(); ++i) {
    const FrontPoint& p = front.points[i];
    const std::string at = "/points/" + std::to_string(i);
    for (std::size_t k = 0; k < bounds.size(); ++k)
      if (!(p.parameters[k] >= bounds[k].lower && p.parameters[k] <= bounds[k].upper))
        fail(at + "/parameters/" + bounds[k].name,
             "is " + json_io::number_text(p.parameters[k]) + ", outside the job's bounds [" +
                 json_io::number_text(bounds[k].lower) + ", " +
                 json_io::number_text(bounds[k].upper) + "]");
    // A held-out point may break a hard goal on the held-out members; in the run it met them.
    const bool held = front.held_out.has_value();
    const std::vector<double>& recorded = held ? p.in_sample : p.goals;
    const std::string values = held ? "/in_sample/" : "/goals/";
    if (!held && !(p.violation == 0))
      fail(at + "/violation", "is " + json_io::number_text(p.violation) +
                                  ", but a point of the front meets every hard goal");
    for (std::size_t k = 0; k < job.goals.size(); ++k)
      if (!(job.goals[k].violation(recorded[k]) == 0))
        fail(at + values + std::to_string(k),
             "is " + json_io::number_text(recorded[k]) + ", above the hard goal's limit " +
                 json_io::number_text(*job.goals[k].at_most) +
                 ", but a point of the front meets every hard goal");
    if (!point_of.count(p.trial)) point_of[p.trial] = i;
  }
  std::map<std::size_t, TrialRow> rows = trial_rows(run / "trials.csv", job, point_of, source);
  const std::string trials = (run / "trials.csv").string();
  for (std::size_t i = 0; i < front.points.size(); ++i) {
    const FrontPoint& p = front.points[i];
    const TrialRow& r = rows.at(p.trial);
    const std::string at = "/points/" + std::to_string(i);
    const std::string row = "trial " + std::to_string(p.trial) + " of " + trials;
    for (std::size_t k = 0; k < bounds.size(); ++k)
      if (!same(p.parameters[k], r.parameters[k]))
        fail(at + "/parameters/" + bounds[k].name,
             "is " + json_io::number_text(p.parameters[k]) + ", but " + row + " has " +
                 json_io::number_text(r.parameters[k]));
    const std::vector<double>& recorded = front.held_out ? p.in_sample : p.goals;
    for (std::size_t k = 0; k < job.goals.size(); ++k)
      if (!same(recorded[k], r.goals[k]))
        fail(at + (front.held_out ? "/in_sample/" : "/goals/") + std::to_string(k),
             "is " + json_io::number_text(recorded[k]) + ", but " + row + " has " +
                 json_io::number_text(r.goals[k]));
    if (r.capped || !r.feasible || r.violation > 0)
      fail(at + "/trial", "is " + row + ", which is " +
                              (r.capped ? "capped (its goals are bounds)" : "infeasible") +
                              ": not a point of a front");
  }
  return rows;
}

}  // namespace

std::optional<Front> read_front(const std::filesystem::path& run, const Job& job,
                                const std::optional<std::string>& job_sha256) {
  const std::filesystem::path file = run / "front.json";
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) return std::nullopt;
  const json j = read_json_file(file);
  if (job_sha256 && j.is_object() && j.value("job_sha256", json("")) != *job_sha256)
    return std::nullopt;
  return front_from_json(job, j, file.string());
}

json pick_gains(const std::filesystem::path& dir, const std::string& rule) {
  const std::filesystem::path front_file = dir / "front.json";
  std::error_code ec;
  if (!std::filesystem::exists(front_file, ec))
    throw InputError(front_file.string(), "",
                     "does not exist (is this a run directory of a job with two or more soft "
                     "goals, or the output of evaluate --front?)");
  const json fj = read_json_file(front_file);
  // A held-out front (evaluate --front) names its run: that run's files give the gains.
  std::filesystem::path run = dir;
  if (fj.is_object() && fj.contains("held_out") && fj["held_out"].is_object() &&
      fj["held_out"].contains("run") && fj["held_out"]["run"].is_string())
    run = fj["held_out"]["run"].get<std::string>();
  const Job job = load_job(run / "job.json");
  if (front_objectives(job) < 2 || !job.tuning)
    throw InputError((run / "job.json").string(), "/goals",
                     "the run's job has fewer than two soft goals: it has no front to pick from");
  const std::string sha = canonical_job_sha256(job);
  if (fj.is_object() && fj.value("job_sha256", json()) != sha)
    throw InputError(front_file.string(), "/job_sha256",
                     (fj.contains("job_sha256") ? "is " + fj["job_sha256"].dump() + ", not"
                                                : std::string("is missing: it must be")) +
                         " the sha256 of the run's job.json (" + sha + ")" +
                         (fj.contains("job_sha256") ? ": a front of another job" : ""));
  Front front = front_from_json(job, fj, front_file.string());
  const std::map<std::size_t, TrialRow> rows =
      check_front_against_run(run, job, front, front_file.string());
  const std::size_t i = pick_point(job, front, rule);
  const std::string gains_file = (run / "gains.json").string();
  json g = read_json_file(run / "gains.json");
  if (!g.is_object()) throw InputError(gains_file, "", "expected an object");
  if (!g.contains("job") || !g["job"].is_object() || g["job"].value("sha256", json()) != sha)
    throw InputError(gains_file, "/job/sha256",
                     "is not the sha256 of the run's job.json (" + sha +
                         "): gains of another job");
  if (!g.contains("goals") || !g["goals"].is_object())
    throw InputError(gains_file, "/goals", "expected an object (the run's goals)");
  if (!g["goals"].contains("goals") || !g["goals"]["goals"].is_array() ||
      g["goals"]["goals"].size() != job.goals.size())
    throw InputError(
        gains_file, "/goals/goals",
        "expected an array of the job's " + std::to_string(job.goals.size()) + " goals");
  for (std::size_t k = 0; k < job.goals.size(); ++k)
    if (!g["goals"]["goals"][k].is_object())
      throw InputError(gains_file, "/goals/goals/" + std::to_string(k), "expected an object");
  for (const char* key : {"controller", "tuned", "objective"})
    if (g.contains(key) && !g[key].is_object())
      throw InputError(gains_file, std::string("/") + key, "expected an object");
  if (g.contains("warnings") && !g["warnings"].is_array())
    throw InputError(gains_file, "/warnings", "expected an array");
  const FrontPoint& p = front.points[i];
  for (std::size_t j = 0; j < job.tuning->parameters.size(); ++j) {
    const std::string& name = job.tuning->parameters[j].name;
    g["controller"][name] = p.parameters[j];
    g["tuned"][name] = p.parameters[j];
  }
  const TrialRow& row = rows.at(p.trial);
  g["objective"]["value"] = json_number(row.objective);
  g["fitness"] = json_number(row.fitness);
  // The run's values of the point (its trials.csv row); a held-out front's go beside them.
  const std::vector<double>& recorded = front.held_out ? p.in_sample : p.goals;
  json& goals = g["goals"];
  double violation = 0.0;
  for (std::size_t k = 0; k < job.goals.size(); ++k) {
    goals["goals"][k]["value"] = json_number(recorded[k]);
    violation += job.goals[k].violation(recorded[k]);
    if (job.goals[k].at_most)
      goals["goals"][k]["violation"] = json_number(job.goals[k].violation(recorded[k]));
  }
  goals["total_violation"] = json_number(violation);
  goals["feasible"] = !(violation > 0);
  const std::size_t measured = front.picked;
  front.picked = i;
  front.rule = rule;
  goals["rule"] = front_rule_text(front);
  goals["front"] = {
      {"index", i}, {"rule", rule}, {"points", front.points.size()}, {"trial", p.trial}};
  // The run's warning about its own point's dominance goes; this point's comes.
  if (g.contains("warnings"))
    for (std::size_t w = g["warnings"].size(); w-- > 0;)
      if (g["warnings"][w].is_string() && is_dominated_warning(g["warnings"][w].get<std::string>()))
        g["warnings"].erase(w);
  if (const std::string d = dominated_warning(front, i); !d.empty()) {
    goals["front"]["dominated_by"] = *p.dominated_by;
    g["warnings"].push_back(d);
  }
  if (front.held_out) {
    // Each soft goal whose held-out value is worse than the run's by more than the point's
    // noise floor (relative, as the floor is): the point does not hold out of sample there.
    json warnings = json::array(), values = json::array();
    for (double v : p.goals) values.push_back(json_number(v));
    for (std::size_t k : front.soft) {
      const double in = p.in_sample[k], out = p.goals[k];
      const double worse = (out - in) / std::abs(in);
      const std::optional<double>& floor = p.noise_floor[k];
      if (std::isfinite(out) && !(worse > floor.value_or(0.0))) continue;
      // Relative to the run's value; against a run value of 0 there is no percentage.
      const std::string percent =
          std::isfinite(worse)
              ? std::to_string(static_cast<long long>(std::llround(100 * worse))) + " % worse"
              : std::string("worse than 0");
      const std::string how =
          !std::isfinite(out)
              ? std::string("not finite")
              : floor ? percent + ", beyond its noise floor of " + [&] {
                          char f[32];
                          std::snprintf(f, sizeof f, "%.2g %%", 100 * *floor);
                          return std::string(f);
                        }()
                      : percent + " (no noise floor measured there)";
      char buf[400];
      std::snprintf(buf, sizeof buf,
                    "point %zu: %s is %.4g on the held-out scenarios against %.4g in the run, "
                    "%s: the point does not hold on members it was not tuned on",
                    i, front.goals[k].label.c_str(), out, in, how.c_str());
      warnings.push_back(buf);
      g["warnings"].push_back(buf);
    }
    // A hard goal the point meets in the run and breaks held out.
    for (std::size_t k = 0; k < job.goals.size(); ++k) {
      if (!job.goals[k].at_most || !(job.goals[k].violation(p.goals[k]) > 0)) continue;
      char buf[400];
      std::snprintf(buf, sizeof buf,
                    "point %zu: %s is %.4g on the held-out scenarios, above its limit %.4g "
                    "(%.4g in the run): the point breaks this hard goal on members it was not "
                    "tuned on",
                    i, front.goals[k].label.c_str(), p.goals[k], *job.goals[k].at_most,
                    p.in_sample[k]);
      warnings.push_back(buf);
      g["warnings"].push_back(buf);
    }
    goals["front"]["held_out"] = {{"seed", front.held_out->seed},
                                  {"count", front.held_out->count},
                                  {"front", front_file.string()},
                                  {"goals", values},
                                  {"total_violation", json_number(p.violation)},
                                  {"warnings", warnings}};
  }
  if (i != measured || front.held_out) g.erase("noise_floor");  // measured at the run's own point
  return g;
}

}  // namespace ftc::tune
