#include "ftc/sim/disturbance.hpp"

#include <cmath>
#include <utility>

#include "checks.hpp"

namespace ftc::sim {

std::vector<FieldError> DisturbanceTerm::validate(const std::string& path) const {
  std::vector<FieldError> errs;
  detail::check_int_range(errs, path + "/axis", axis, 1, kAxes);
  detail::check_finite(errs, path + "/amplitude", amplitude);
  detail::check_finite(errs, path + "/frequency", frequency);
  detail::check_finite(errs, path + "/phase", phase);
  return errs;
}

const char* to_string(Shape s) { return s == Shape::sin ? "sin" : "cos"; }

Disturbance::Disturbance(std::vector<DisturbanceTerm> terms) : terms_(std::move(terms)) {}

Vec3 Disturbance::operator()(double t) const {
  Vec3 d;
  evaluate(
      1,
      [&](std::size_t i, std::size_t, Shape shape) {
        const double x = terms_[i].frequency * t + terms_[i].phase;
        return shape == Shape::sin ? std::sin(x) : std::cos(x);
      },
      [&](std::size_t) -> Vec3& { return d; });
  return d;
}

std::vector<Phasor> Disturbance::phasors(double dt) const { return phasors_of(terms_, dt); }

}  // namespace ftc::sim
