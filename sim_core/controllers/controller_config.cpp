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
constexpr ControllerField kFields[] = {
    {"c1", &C::c1, F | P | A, false, false},
    {"c2", &C::c2, F | P | A, false, false},
    {"alpha1", &C::alpha1, F | P | A, false, true},
    {"alpha2", &C::alpha2, F | P | A, false, false},
    {"switching_gain", &C::switching_gain, N | F | P, false, false},
    {"theta", &C::theta, N | F | P | A, false, false},
    {"Kp", &C::Kp, P | A, false, false},
    {"Ki", &C::Ki, P | A, false, false},
    {"sigma1", &C::sigma1, N, false, false},
    {"sigma2", &C::sigma2, N, false, false},
    {"alpha", &C::alpha, N, false, false},
    {"p", &C::p, N, true, false},
    {"q", &C::q, N, true, false},
    {"nodes", &C::nodes, A, true, false},
    {"width", &C::width, A, false, false},
    {"weight_rate", &C::weight_rate, A, false, false},
    {"lambda", &C::lambda, A, false, false},
    {"zeta", &C::zeta, A, false, false},
    {"ka0", &C::ka0, A, false, false},
};

bool is_odd_positive_int(double v) {
  return v >= 1 && v == std::floor(v) && v < 1e6 && static_cast<long>(v) % 2 == 1;
}

// The range rule of one field; `cfg` gives the other fields a rule depends on (alpha vs p/q).
std::string check_value(const ControllerConfig& cfg, std::string_view name, double v) {
  using detail::fmt_num;
  const std::string got = " (got " + fmt_num(v) + ")";
  if (!std::isfinite(v)) return "must be a finite number";
  if (name == "c1" || name == "c2" || name == "theta" || name == "Kp" || name == "sigma1" ||
      name == "sigma2" || name == "width" || name == "lambda")
    return v > 0 ? "" : "must be > 0" + got;
  if (name == "alpha1" || name == "alpha2")
    return (v > 0 && v < 1) ? "" : "must be in the open interval (0, 1)" + got;
  if (name == "switching_gain" || name == "Ki" || name == "weight_rate" || name == "zeta" ||
      name == "ka0")
    return v >= 0 ? "" : "must be >= 0" + got;
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
  if (name == "nodes") {
    if (v != std::floor(v) || v < 1 || v > 64) return "must be an integer in 1..64" + got;
    return "";
  }
  return "";
}

}  // namespace

const char* to_string(ControllerType t) {
  switch (t) {
    case ControllerType::nftsmc:
      return "nftsmc";
    case ControllerType::fosmc:
      return "fosmc";
    case ControllerType::pi_fosmc:
      return "pi_fosmc";
    case ControllerType::adaptive_neural_pi_fosmc:
      return "adaptive_neural_pi_fosmc";
  }
  return "?";
}

std::optional<ControllerType> controller_type_from_string(std::string_view s) {
  for (ControllerType t : kAllControllerTypes)
    if (s == to_string(t)) return t;
  return std::nullopt;
}

double ControllerConfig::resolved_alpha1() const {
  return std::isnan(alpha1) ? alpha2 / (2.0 - alpha2) : alpha1;
}

std::vector<FieldError> ControllerConfig::validate(const std::string& path) const {
  std::vector<FieldError> errs;
  for (const ControllerField& f : kFields) {
    if (!f.applies_to(type)) continue;
    const double v = this->*f.member;
    if (f.optional && std::isnan(v)) continue;
    std::string msg = check_value(*this, f.name, v);
    if (!msg.empty()) errs.push_back({path + "/" + f.name, std::move(msg)});
  }
  if (type == ControllerType::adaptive_neural_pi_fosmc) {
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
  if (t == ControllerType::adaptive_neural_pi_fosmc) names.emplace_back("centre_range");
  return names;
}

std::string check_controller_value(const ControllerConfig& base, const ControllerField& field,
                                   double value) {
  ControllerConfig c = base;
  c.*field.member = value;
  return check_value(c, field.name, value);
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
