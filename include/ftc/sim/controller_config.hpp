#pragma once
// Parameters of the sliding-mode controllers (the table of controllers.hpp) in one plain struct,
// with the Table 1 values of the paper as defaults. Which fields a controller type uses, their valid ranges and whether
// they can be tuned is described by a field table (controller_fields()), which the job loader,
// the tuner and the error messages all share, so a field is defined exactly once.
#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ftc/sim/controllers.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/range.hpp"

namespace ftc::sim {

struct ControllerConfig {
  ControllerType type = ControllerType::pi_fosmc;

  // Full-order sliding surface C(X) = c2 sig^α2(X2) + c1 sig^α1(X1) (FOSMC family).
  double c1 = 10.0;
  double c2 = 9.0;
  double alpha1 = std::numeric_limits<double>::quiet_NaN();  // NaN: derived, α2 / (2 - α2)
  double alpha2 = 0.5625;                                    // 9/16
  double switching_gain = 20.0;  // K: Ξ+ζ (NFTSMC) or Π+ζ (FOSMC, PI-FOSMC)
  double theta = 1000.0;         // θ of the sigmoid sigm(s) = tanh(θ s / 2)
  double Kp = 20.0;
  double Ki = 5.0;

  // NFTSMC surface s = X1 + σ1 sig^α(X1) + σ2 sig^{p/q}(X2).
  double sigma1 = 10.0;
  double sigma2 = 5.0;
  double alpha = 1.4;
  double p = 9.0;  // positive odd integer
  double q = 7.0;  // positive odd integer

  // Adaptive neural PI-FOSMC (RBF network and adaptive switching gain).
  double nodes = 7.0;  // l, integer
  std::array<double, 2> centre_range{-1.5, 1.5};
  double width = 2.0;        // σ of the Gaussians
  double weight_rate = 0.1;  // 1/α of eq. (30)
  double lambda = 100.0;     // λ of eq. (29)
  double zeta = 5.0;         // ζ
  double ka0 = 15.0;         // K̂a(0)

  // α1 as used: the given value, or α2 / (2 - α2).
  double resolved_alpha1() const;
  // Every bad field, each with `path` + "/" + field name.
  std::vector<FieldError> validate(const std::string& path = "") const;
  // The Table 1 configuration of a controller type.
  static ControllerConfig table1(ControllerType type);
};

// One scalar field of ControllerConfig: the single description of it that validation, the
// job and gains file formats, their JSON Schema and the tuner's bounds checks all read.
struct ControllerField {
  const char* name;
  double ControllerConfig::*member;
  std::uint8_t types;  // bit (1 << type) set when the field belongs to that controller type
  bool integer;        // integer-valued: validated as such and not tunable
  bool optional;       // may be absent (alpha1)
  Range range;         // valid values; p, q and alpha have further rules (rule below)
  // The unit of the value for a state in rad and time in s (laws.hpp derives them); a gain of a
  // fractional power carries its exponent; "dimensionless", or "" for a count (p, q, nodes).
  const char* unit;
  const char* description;
  const char* rule = "";  // a condition beyond the range, in words ("" = none)
  // NFTSMC's unit where its surface gives the field another one (its s is in rad, not rad/s²).
  const char* nftsmc_unit = nullptr;

  bool applies_to(ControllerType t) const { return (types >> static_cast<int>(t)) & 1U; }
  // The one unit table: validation's descriptions, the schemas, the landscape's axes.
  const char* unit_for(ControllerType t) const {
    return t == ControllerType::nftsmc && nftsmc_unit ? nftsmc_unit : unit;
  }
  bool tunable() const { return !integer; }
};

std::span<const ControllerField> controller_fields();
const ControllerField* find_controller_field(std::string_view name);

// Names of all fields of a controller type, in table order (centre_range included).
std::vector<std::string> controller_field_names(ControllerType t);

// Checks one candidate value of a field in the context of a full configuration (used for
// tuning bounds): returns the message, or an empty string when the value is valid.
std::string check_controller_value(const ControllerConfig& base, const ControllerField& field,
                                   double value);

}  // namespace ftc::sim
