#include "ftc/sim/disturbance.hpp"

#include <cmath>
#include <utility>

#include "checks.hpp"

namespace ftc::sim {

std::vector<FieldError> DisturbanceTerm::validate(const std::string& path, int axes) const {
  std::vector<FieldError> errs;
  detail::check_int_range(errs, path + "/axis", axis, 1, axes);
  detail::check_finite(errs, path + "/amplitude", amplitude);
  detail::check_finite(errs, path + "/frequency", frequency);
  detail::check_finite(errs, path + "/phase", phase);
  return errs;
}

const char* to_string(Shape s) { return s == Shape::sin ? "sin" : "cos"; }

Disturbance::Disturbance(std::vector<DisturbanceTerm> terms) : terms_(std::move(terms)) {}

}  // namespace ftc::sim
