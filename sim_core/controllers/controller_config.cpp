#include "ftc/sim/controller_config.hpp"

#include <cmath>

#include "checks.hpp"

namespace ftc::sim {
namespace {

constexpr std::uint8_t bit(ControllerType t) { return std::uint8_t(1U << static_cast<int>(t)); }
constexpr std::uint8_t N = bit(ControllerType::nftsmc);
constexpr std::uint8_t F = bit(ControllerType::fosmc);
constexpr std::uint8_t P = bit(ControllerType::pi_fosmc);
constexpr std::uint8_t A = bit(ControllerType::adaptive_neural_pi_fosmc);

using C = ControllerConfig;
constexpr Range kPositive = Range::positive(), kNonNegative = Range::non_negative();
constexpr Range kOpenUnit = Range::open_unit(), kAny = Range::any();
constexpr ControllerField kFields[] = {
    {"c1", &C::c1, F | P | A, false, false, kPositive, "rad^(1−α1)/s²",
     "gain of sig^α1(X1) in C(X)"},
    {"c2", &C::c2, F | P | A, false, false, kPositive, "rad^(1−α2)·s^(α2−2)",
     "gain of sig^α2(X2) in C(X)"},
    {"alpha1", &C::alpha1, F | P | A, false, true, kOpenUnit, "dimensionless",
     "exponent α1 of X1 in C(X); default α2 / (2 - α2)"},
    {"alpha2", &C::alpha2, F | P | A, false, false, kOpenUnit, "dimensionless",
     "exponent α2 of X2 in C(X)"},
    {"switching_gain", &C::switching_gain, N | F | P, false, false, kNonNegative, "rad/s³",
     "switching gain K (Ξ+ζ for NFTSMC, Π+ζ for FOSMC and PI-FOSMC)", "", "rad/s²"},
    {"theta", &C::theta, N | F | P | A, false, false, kPositive, "s²/rad",
     "slope θ of the smooth sign sigm(s) = tanh(θ s / 2)", "", "1/rad"},
    {"Kp", &C::Kp, P | A, false, false, kPositive, "dimensionless",
     "proportional gain of the PI surface"},
    {"Ki", &C::Ki, P | A, false, false, kNonNegative, "1/s", "integral gain of the PI surface"},
    {"sigma1", &C::sigma1, N, false, false, kPositive, "rad^(1−α)", "σ1 of the NFTSMC surface"},
    {"sigma2", &C::sigma2, N, false, false, kPositive, "rad^(1−p/q)·s^(p/q)",
     "σ2 of the NFTSMC surface"},
    {"alpha", &C::alpha, N, false, false, kAny, "dimensionless",
     "exponent α of X1 in the NFTSMC surface",
     "greater than p/q"},
    {"p", &C::p, N, true, false, Range::at_least(1), "", "numerator of the exponent p/q",
     "a positive odd integer, with 1 < p/q < 2"},
    {"q", &C::q, N, true, false, Range::at_least(1), "", "denominator of the exponent p/q",
     "a positive odd integer, with 1 < p/q < 2"},
    {"nodes", &C::nodes, A, true, false, Range::between(1, 64), "",
     "number l of RBF nodes, an integer in 1..64"},
    {"width", &C::width, A, false, false, kPositive, "rad and rad/s, as the state",
     "width σ of the Gaussian nodes"},
    {"weight_rate", &C::weight_rate, A, false, false, kNonNegative, "1/s²",
     "adaptation rate of the network weights (1/α of eq. 30)"},
    {"lambda", &C::lambda, A, false, false, kPositive, "s²",
     "λ of the switching-gain adaptation (eq. 29)"},
    {"zeta", &C::zeta, A, false, false, kNonNegative, "rad/s³", "ζ added to the adaptive gain"},
    {"ka0", &C::ka0, A, false, false, kNonNegative, "rad/s³", "initial adaptive gain K̂a(0)"},
};

bool is_odd_positive_int(double v) {
  return v >= 1 && v == std::floor(v) && v < 1e6 && static_cast<long>(v) % 2 == 1;
}

// The rules of one field; `cfg` gives the other fields a rule depends on (alpha vs p/q).
std::string check_value(const ControllerConfig& cfg, const ControllerField& f, double v) {
  using detail::fmt_num;
  const std::string got = " (got " + fmt_num(v) + ")";
  const std::string_view name = f.name;
  if (!std::isfinite(v)) return "must be a finite number";
  if (name == "p" || name == "q") {
    if (!is_odd_positive_int(v)) return "must be a positive odd integer" + got;
    if (is_odd_positive_int(cfg.p) && is_odd_positive_int(cfg.q)) {
      const double r = cfg.p / cfg.q;
      if (!(r > 1 && r < 2)) return "p/q must be in (1, 2) (got " + fmt_num(r) + ")";
    }
    return "";
  }
  if (name == "alpha") {
    const double r = cfg.p / cfg.q;
    if (std::isfinite(r) && !(v > r)) return "must be greater than p/q = " + fmt_num(r) + got;
    return "";
  }
  if (f.integer) {
    if (v != std::floor(v) || !f.range.contains(v))
      return "must be an integer in " + fmt_num(f.range.min) + ".." + fmt_num(f.range.max) + got;
    return "";
  }
  return f.range.check(v);
}

}  // namespace

double ControllerConfig::resolved_alpha1() const {
  return std::isnan(alpha1) ? alpha2 / (2.0 - alpha2) : alpha1;
}

std::vector<FieldError> ControllerConfig::validate(const std::string& path) const {
  std::vector<FieldError> errs;
  for (const ControllerField& f : kFields) {
    if (!f.applies_to(type)) continue;
    const double v = this->*f.member;
    if (f.optional && std::isnan(v)) {
      // An absent α1 is α2 / (2 - α2), which is in (0, 1) for any α2 in (0, 1) but rounds to
      // 0 for an α2 near the smallest double. Said once: a bad α2 has its own error.
      const double derived = resolved_alpha1();
      if (check_value(*this, *find_controller_field("alpha2"), alpha2).empty())
        if (std::string msg = check_value(*this, f, derived); !msg.empty())
          errs.push_back({path + "/" + f.name,
                          "is absent, and its default α2 / (2 - α2) " + msg + ": give alpha1"});
      continue;
    }
    std::string msg = check_value(*this, f, v);
    if (!msg.empty()) errs.push_back({path + "/" + f.name, std::move(msg)});
  }
  if (controller_info(type).adaptive) {
    const std::string cp = path + "/centre_range";
    if (!std::isfinite(centre_range[0]) || !std::isfinite(centre_range[1]))
      errs.push_back({cp, "must hold two finite numbers"});
    else if (!(centre_range[0] < centre_range[1]))
      errs.push_back({cp, "lower end " + detail::fmt_num(centre_range[0]) +
                              " must be below upper end " + detail::fmt_num(centre_range[1])});
  }
  return errs;
}

ControllerConfig ControllerConfig::table1(ControllerType type) {
  ControllerConfig c;  // the defaults are Table 1's
  c.type = type;
  return c;
}

std::span<const ControllerField> controller_fields() { return kFields; }

const ControllerField* find_controller_field(std::string_view name) {
  for (const ControllerField& f : kFields)
    if (name == f.name) return &f;
  return nullptr;
}

std::vector<std::string> controller_field_names(ControllerType t) {
  std::vector<std::string> names;
  for (const ControllerField& f : kFields)
    if (f.applies_to(t)) names.emplace_back(f.name);
  if (controller_info(t).adaptive) names.emplace_back("centre_range");
  return names;
}

std::string check_controller_value(const ControllerConfig& base, const ControllerField& field,
                                   double value) {
  ControllerConfig c = base;
  c.*field.member = value;
  return check_value(c, field, value);
}

namespace detail {

// Shared by every controller constructor: validated copy with α1 resolved.
ControllerConfig checked_config(const ControllerConfig& config, double sample_time) {
  std::vector<FieldError> errs = config.validate("");
  for (FieldError& e : errs) e.path = e.path.substr(1);  // field names, not JSON paths
  if (!(sample_time > 0.0) || !std::isfinite(sample_time))
    errs.push_back({"sample_time", "must be > 0 (got " + fmt_num(sample_time) + ")"});
  throw_if_errors(std::string("controller ") + to_string(config.type), std::move(errs));
  ControllerConfig c = config;
  c.alpha1 = config.resolved_alpha1();
  return c;
}

}  // namespace detail
}  // namespace ftc::sim
