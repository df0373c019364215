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

namespace {
template <class SinCos>
Vec3 sum_terms(const std::vector<DisturbanceTerm>& terms, double t, SinCos&& sincos) {
  Vec3 d = Vec3::Zero();
  for (std::size_t i = 0; i < terms.size(); ++i) {
    const DisturbanceTerm& term = terms[i];
    double s, c;
    sincos(i, term.frequency * t + term.phase, s, c);
    d[term.axis - 1] += term.amplitude * (term.shape == Shape::sin ? s : c);
  }
  return d;
}
}  // namespace

Vec3 Disturbance::operator()(double t) const {
  return sum_terms(terms_, t, [](std::size_t, double x, double& s, double& c) {
    s = std::sin(x);
    c = std::cos(x);
  });
}

Vec3 Disturbance::operator()(double t, std::span<SinCosTracker> trackers) const {
  return sum_terms(
      terms_, t, [&](std::size_t i, double x, double& s, double& c) { trackers[i].eval(x, s, c); });
}

}  // namespace ftc::sim
