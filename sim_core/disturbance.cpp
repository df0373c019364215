#include "ftc/sim/disturbance.hpp"

#include <cmath>
#include <utility>

#include "checks.hpp"

namespace ftc::sim {

namespace {

using D = DisturbanceTerm;
constexpr NumberField<DisturbanceTerm> kTermFields[] = {
    {"amplitude", &D::amplitude, Range::any(), "rad/s²", "amplitude, added to the acceleration"},
    {"frequency", &D::frequency, Range::any(), "rad/s", "angular frequency"},
    {"phase", &D::phase, Range::any(), "rad", "phase"}};
constexpr IntegerField<DisturbanceTerm> kAxis = {"axis", &D::axis, 1, kMaxAxes,
                                                 "axis index, 1..n of the plant"};

}  // namespace

std::span<const NumberField<DisturbanceTerm>> DisturbanceTerm::number_fields() {
  return kTermFields;
}
const IntegerField<DisturbanceTerm>& DisturbanceTerm::axis_field() { return kAxis; }

std::vector<FieldError> DisturbanceTerm::validate(const std::string& path, int axes) const {
  std::vector<FieldError> errs;
  detail::check_int_range(errs, path + "/axis", axis, 1, axes);
  for (const NumberField<DisturbanceTerm>& f : kTermFields)
    detail::check_range(errs, path + "/" + f.name, f.range, this->*f.member);
  return errs;
}

const char* to_string(Shape s) { return s == Shape::sin ? "sin" : "cos"; }

Disturbance::Disturbance(std::vector<DisturbanceTerm> terms) : terms_(std::move(terms)) {}

}  // namespace ftc::sim
