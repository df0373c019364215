#include "ftc/sim/scenario.hpp"

#include <cmath>

#include "checks.hpp"
#include "ftc/sim/elementary.hpp"

namespace ftc::sim {

namespace {

constexpr NumberField<Scenario> kScenarioFields[] = {
    {"duration", &Scenario::duration, Range::positive(), "s",
     "length T of the run, a whole multiple of sample_time"},
    {"sample_time", &Scenario::sample_time, Range::positive(), "s",
     "controller period Ts (zero-order hold in between)"},
};
constexpr IntegerField<Scenario> kSubsteps = {"substeps", &Scenario::substeps, 1, 1000,
                                              "RK4 steps per sample, h = Ts / substeps"};

}  // namespace

std::span<const NumberField<Scenario>> Scenario::number_fields() { return kScenarioFields; }
const IntegerField<Scenario>& Scenario::substeps_field() { return kSubsteps; }

std::vector<FieldError> Scenario::validate(const std::string& path, int axes, int actuators) const {
  std::vector<FieldError> errs;
  if (name.empty()) errs.push_back({path + "/name", "must not be empty"});
  for (const NumberField<Scenario>& f : kScenarioFields)
    detail::check_range(errs, path + "/" + f.name, f.range, this->*f.member);
  if (std::isfinite(duration) && std::isfinite(sample_time) && duration > 0 && sample_time > 0) {
    const double n = std::round(duration / sample_time);
    if (n < 1 || std::abs(n * sample_time - duration) > 1e-9 * duration)
      errs.push_back({path + "/duration", "must be a whole multiple of sample_time " +
                                              detail::fmt_num(sample_time) + " (got " +
                                              detail::fmt_num(duration) + ")"});
    else if (n > 1e9)
      errs.push_back({path + "/duration", "needs more than 1e9 samples"});
  }
  detail::check_int_range(errs, path + "/substeps", substeps, static_cast<int>(kSubsteps.min),
                          static_cast<int>(kSubsteps.max));
  if (initial_state.size() != static_cast<std::size_t>(2 * axes))
    errs.push_back({path + "/initial_state", "expected " + std::to_string(2 * axes) +
                                                 " numbers (X1 and X2 of the plant's " +
                                                 std::to_string(axes) + " axes), got " +
                                                 std::to_string(initial_state.size())});
  for (std::size_t i = 0; i < initial_state.size(); ++i)
    detail::check_range(errs, path + "/initial_state/" + std::to_string(i), Range::any(),
                        initial_state[i]);
  for (std::size_t i = 0; i < disturbance.size(); ++i) {
    auto e = disturbance[i].validate(path + "/disturbance/" + std::to_string(i), axes);
    errs.insert(errs.end(), e.begin(), e.end());
  }
  for (std::size_t i = 0; i < faults.size(); ++i) {
    auto e = faults[i].validate(path + "/faults/" + std::to_string(i), actuators);
    errs.insert(errs.end(), e.begin(), e.end());
  }
  if (saturation.values.size() == 1) {
    detail::check_range(errs, path + "/saturation", kSaturationRange, saturation.values[0]);
  } else if (saturation.per_actuator()) {
    if (saturation.values.size() != static_cast<std::size_t>(actuators))
      errs.push_back({path + "/saturation",
                      "expected one number for every actuator or " + std::to_string(actuators) +
                          " (one per actuator of the plant's " + std::to_string(actuators) +
                          "), got " + std::to_string(saturation.values.size())});
    for (std::size_t j = 0; j < saturation.values.size(); ++j)
      detail::check_range(errs, path + "/saturation/" + std::to_string(j), kSaturationRange,
                          saturation.values[j]);
  }
  if (actuator) {
    const std::string a = path + "/actuator";
    if (!actuator->time_constant && !actuator->rate_limit)
      errs.push_back({a, "give time_constant, rate_limit or both"});
    if (actuator->rate_limit)
      detail::check_range(errs, a + "/rate_limit", ActuatorModel::kRateLimitRange,
                          *actuator->rate_limit);
    if (const auto& tau = actuator->time_constant) {
      const std::size_t before = errs.size();
      detail::check_range(errs, a + "/time_constant", ActuatorModel::kTimeConstantRange, *tau);
      const double h = sample_time / substeps;
      if (errs.size() == before && std::isfinite(h) && h > 0 &&
          !(*tau >= ActuatorModel::kMinSteps * h))
        errs.push_back({a + "/time_constant",
                        "must be at least 2 integration steps (2 · sample_time / substeps = " +
                            detail::fmt_num(ActuatorModel::kMinSteps * h) + " s), got " +
                            detail::fmt_num(*tau)});
    }
  }
  if (sensors) {
    auto e = sensors->validate(path + "/sensors", axes);
    errs.insert(errs.end(), e.begin(), e.end());
  }
  return errs;
}

ActuatorSteps actuator_steps(const ActuatorModel& model, double half_step) {
  ActuatorSteps s;
  if (model.time_constant) s.gain = -math::expm1(-half_step / *model.time_constant);
  if (model.rate_limit) s.max_step = *model.rate_limit * half_step;
  return s;
}

const std::vector<double>* Scenario::true_value(std::string_view parameter) const {
  for (const TrueValue& t : true_values)
    if (t.parameter == parameter) return &t.values;
  return nullptr;
}

void Scenario::set_true_value(const std::string& parameter, std::vector<double> values) {
  for (TrueValue& t : true_values)
    if (t.parameter == parameter) {
      t.values = std::move(values);
      return;
    }
  true_values.push_back({parameter, std::move(values)});
}

Scenario Scenario::paper() {
  Scenario s;
  s.initial_state = {-0.7, -0.07, 1.5, 0.3, 1.3, -0.2};
  s.disturbance = {{1, Shape::sin, 0.5, 1.0, 0.0},
                   {2, Shape::cos, 0.5, 2.0, 0.0},
                   {3, Shape::sin, 0.5, 3.0, 0.0}};
  Fault bias;
  bias.actuator = 1;
  bias.type = FaultType::bias;
  bias.onset = 10.0;
  bias.offset = 5.0;
  bias.amplitude = 15.0;
  bias.frequency = 1.0;
  Fault loe;
  loe.actuator = 2;
  loe.type = FaultType::loss_of_effectiveness;
  loe.onset = 20.0;
  loe.fraction = 0.8;
  s.faults = {bias, loe};
  return s;
}

}  // namespace ftc::sim
