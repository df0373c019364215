#pragma once
// The acceleration step() reads, formed in flight as it was in tuning (gains file key
// `acceleration`; docs/model.md "Sensors in the loop").
//
// The full-order surfaces need the angular acceleration a = dX2/dt. A job whose scenarios read
// `differentiated` acceleration tuned its gains on
//
//   d_k = (X2m_k − X2m_{k−1}) / Ts   (d_0 = 0),   X2m the measured rates (rad/s)
//   y_k = y_{k−1} + (Ts / (τ + Ts)) (d_k − y_{k−1}),   y_{−1} = 0,   τ ≥ 0 the low-pass's (s)
//
// and that y_k (rad/s²) is what step() must be given. This class computes it, out of line in the
// runtime library (built without floating-point contraction), with the tuner loop's operations
// in the tuner loop's order: fed the rates the controller reads, it returns the tuner's
// acceleration to the bit. With a delay of d samples the tuner differentiated the rates before
// delaying them, and flight software differentiates the delayed rates it receives: both give
// y_{k−d} at sample k (the first d + 1 rates are the same measurement, whose difference is 0).
//
//   const ftc::runtime::Gains gains = ftc::runtime::read_gains("gains.json");
//   ftc::runtime::AccelerationEstimator estimate(ftc::runtime::acceleration_path(gains),
//                                                gains.sample_time, 3);
//   every Ts: a = estimate.update<3>(X2m); u_d = controller->step(t, X1m, X2m, a);
#include <vector>

#include "ftc/runtime/gains.hpp"
#include "ftc/sim/sensors.hpp"
#include "ftc/sim/types.hpp"

namespace ftc::runtime {

// The acceleration path the gains were tuned with: the file's, else the ideal (exact) one.
sim::AccelerationSensor acceleration_path(const Gains& gains);

class AccelerationEstimator {
 public:
  // Throws InputError unless `path` is differentiated (an ideal acceleration is measured, not
  // estimated), τ ≥ 0 is finite, Ts > 0 and axes ≥ 1.
  AccelerationEstimator(const sim::AccelerationSensor& path, double sample_time, int axes);

  // Back to k = 0 (before a run, like Controller::reset()).
  void reset();
  // y_k from the rates read at sample k (axes values, rad/s); call once per sample, in order.
  void update(const double* rate, double* acceleration);
  template <int N>
  sim::Vec<N> update(const sim::Vec<N>& rate) {
    sim::Vec<N> a;
    update(rate.data(), a.data());
    return a;
  }

  double time_constant() const { return time_constant_; }
  double sample_time() const { return sample_time_; }

 private:
  double time_constant_, sample_time_, gain_;
  std::vector<double> previous_, filtered_;  // X2m_{k−1}, y_{k−1}
  bool first_ = true;
};

}  // namespace ftc::runtime
