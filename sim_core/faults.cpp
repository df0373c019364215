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

namespace {

using F = Fault;
constexpr NumberField<Fault> kCommon[] = {
    {"onset", &F::onset, Range::non_negative(), "s", "time t_f the fault starts"}};
constexpr NumberField<Fault> kBias[] = {
    {"offset", &F::offset, Range::any(), "", "constant part of the bias, in actuator units"},
    {"amplitude", &F::amplitude, Range::any(), "", "amplitude of its cosine"},
    {"frequency", &F::frequency, Range::any(), "rad/s", "frequency of its cosine"},
    {"phase", &F::phase, Range::any(), "rad", "phase of its cosine"}};
constexpr NumberField<Fault> kLoss[] = {
    {"fraction", &F::fraction, Range::unit(), "", "fraction of the command lost, 0..1"}};
constexpr NumberField<Fault> kStuck[] = {
    {"value", &F::value, Range::any(), "", "output the actuator is frozen at"}};
constexpr IntegerField<Fault> kActuator = {"actuator", &F::actuator, 1, kMaxActuators,
                                           "actuator index, 1..m of the plant"};
constexpr NumberField<FaultProfile> kRate = {"rate", &FaultProfile::rate, Range::positive(), "1/s",
                                             "β of ρ = 1 - exp(-β (t - t_f))"};

}  // namespace

std::span<const NumberField<Fault>> Fault::common_fields() { return kCommon; }
std::span<const NumberField<Fault>> Fault::type_fields(FaultType type) {
  switch (type) {
    case FaultType::bias:
      return kBias;
    case FaultType::loss_of_effectiveness:
      return kLoss;
    case FaultType::stuck:
      return kStuck;
  }
  return {};
}
const IntegerField<Fault>& Fault::actuator_field() { return kActuator; }
const NumberField<FaultProfile>& FaultProfile::rate_field() { return kRate; }

std::vector<FieldError> Fault::validate(const std::string& path, int actuators) const {
  std::vector<FieldError> errs;
  detail::check_int_range(errs, path + "/actuator", actuator, 1, actuators);
  for (const NumberField<Fault>& f : kCommon)
    detail::check_range(errs, path + "/" + f.name, f.range, this->*f.member);
  if (profile.type == FaultProfileType::incipient)
    detail::check_range(errs, path + "/profile/rate", kRate.range, profile.rate);
  for (const NumberField<Fault>& f : type_fields(type))
    detail::check_range(errs, path + "/" + f.name, f.range, this->*f.member);
  return errs;
}

FaultSet::FaultSet(std::vector<Fault> faults, Saturation saturation)
    : faults_(std::move(faults)), saturation_(std::move(saturation)) {}

}  // namespace ftc::sim
