#include "ftc/sim/faults.hpp"

#include <cmath>
#include <utility>

#include "checks.hpp"

namespace ftc::sim {

const char* to_string(FaultType t) {
  switch (t) {
    case FaultType::bias:
      return "bias";
    case FaultType::loss_of_effectiveness:
      return "loss_of_effectiveness";
    case FaultType::stuck:
      return "stuck";
  }
  return "?";
}

const char* to_string(FaultProfileType t) {
  return t == FaultProfileType::abrupt ? "abrupt" : "incipient";
}

std::vector<FieldError> Fault::validate(const std::string& path, int actuators) const {
  std::vector<FieldError> errs;
  detail::check_int_range(errs, path + "/actuator", actuator, 1, actuators);
  detail::check_non_negative(errs, path + "/onset", onset);
  if (profile.type == FaultProfileType::incipient)
    detail::check_positive(errs, path + "/profile/rate", profile.rate);
  switch (type) {
    case FaultType::bias:
      detail::check_finite(errs, path + "/offset", offset);
      detail::check_finite(errs, path + "/amplitude", amplitude);
      detail::check_finite(errs, path + "/frequency", frequency);
      detail::check_finite(errs, path + "/phase", phase);
      break;
    case FaultType::loss_of_effectiveness:
      detail::check_range(errs, path + "/fraction", fraction, 0.0, 1.0);
      break;
    case FaultType::stuck:
      detail::check_finite(errs, path + "/value", value);
      break;
  }
  return errs;
}

FaultSet::FaultSet(std::vector<Fault> faults, std::optional<double> saturation)
    : faults_(std::move(faults)), saturation_(saturation) {}

}  // namespace ftc::sim
