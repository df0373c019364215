#include "ftc/tune/problem/problem.hpp"

#include <utility>

namespace ftc::tune {

TuningProblem::TuningProblem(Job job) : job_(std::move(job)) {
  std::vector<FieldError> errs = job_.validate();
  if (!job_.tuning) errs.push_back({"/tuning", "is required to tune"});
  throw_if_errors("job " + job_.name, std::move(errs));
  plant_ = sim::make_plant(job_.plant);
  for (const ParameterBounds& b : job_.tuning->parameters) {
    const sim::ControllerField* f = sim::find_controller_field(b.name);
    space_.names.push_back(b.name);
    space_.lower.push_back(b.lower);
    space_.upper.push_back(b.upper);
    members_.push_back(f->member);  // validate() made sure the field exists and is tunable
  }
}

sim::ControllerConfig TuningProblem::controller_for(std::span<const double> x) const {
  sim::ControllerConfig c = job_.controller;
  for (std::size_t j = 0; j < members_.size(); ++j) c.*members_[j] = x[j];
  return c;
}

sim::SimulationResult TuningProblem::simulate(const sim::ControllerConfig& controller,
                                              std::size_t scenario,
                                              std::int64_t record_every) const {
  return simulate_scenario(job_, *plant_, controller, scenario, record_every);
}

}  // namespace ftc::tune
