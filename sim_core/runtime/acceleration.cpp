#include "ftc/runtime/acceleration.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "ftc/runtime/json_reader.hpp"

namespace ftc::runtime {

sim::AccelerationSensor acceleration_path(const Gains& gains) {
  return gains.acceleration.value_or(sim::AccelerationSensor{});
}

AccelerationEstimator::AccelerationEstimator(const sim::AccelerationSensor& path,
                                             double sample_time, int axes)
    : time_constant_(path.time_constant), sample_time_(sample_time) {
  if (path.source != sim::AccelerationSource::differentiated)
    throw InputError("acceleration", "/acceleration/source",
                     "is \"ideal\": the gains were tuned on a measured acceleration, which is "
                     "fed to step() as it is; only \"differentiated\" is estimated from the rates");
  if (!(time_constant_ >= 0) || !std::isfinite(time_constant_))
    throw InputError(
        "acceleration", "/acceleration/time_constant",
        "must be a finite number >= 0 (got " + json_io::number_text(time_constant_) + ")");
  if (!(sample_time > 0) || !std::isfinite(sample_time))
    throw InputError("acceleration", "/sample_time",
                     "must be > 0 (got " + json_io::number_text(sample_time) + ")");
  if (axes < 1)
    throw InputError("acceleration", "",
                     "needs at least one axis (got " + std::to_string(axes) + ")");
  // The tuner's lanes compute the gain once per scenario as Ts / (τ + Ts), so does this.
  gain_ = sample_time_ / (time_constant_ + sample_time_);
  previous_.assign(static_cast<std::size_t>(axes), 0.0);
  filtered_.assign(static_cast<std::size_t>(axes), 0.0);
}

void AccelerationEstimator::reset() {
  std::fill(previous_.begin(), previous_.end(), 0.0);
  std::fill(filtered_.begin(), filtered_.end(), 0.0);
  first_ = true;
}

void AccelerationEstimator::update(const double* rate, double* acceleration) {
  // The operations of sim_core/lanes/closed_loop.hpp's measure(), in its order.
  for (std::size_t i = 0; i < filtered_.size(); ++i) {
    const double d = first_ ? 0.0 : (rate[i] - previous_[i]) / sample_time_;
    filtered_[i] = filtered_[i] + gain_ * (d - filtered_[i]);
    previous_[i] = rate[i];
    acceleration[i] = filtered_[i];
  }
  first_ = false;
}

}  // namespace ftc::runtime
