#pragma once
// The plant as a model-based controller uses it: f(X) and G⁺(X) at the measured state. G⁺ is
// read once when the plant says G is constant (the spacecraft), which saves a virtual call
// and a 4×3 copy every sample; f comes from the measurement when the caller already has it.
#include "ftc/sim/controller.hpp"

namespace ftc::sim::detail {

class PlantModel {
 public:
  explicit PlantModel(const Plant& plant)
      : plant_(plant),
        constant_G_(plant.input_matrix_is_constant()),
        G_pinv_(constant_G_ ? plant.G_pinv(State::Zero()) : Mat43::Zero()) {}

  Vec3 f(const Measurement& m) const { return m.f ? *m.f : plant_.f(state(m)); }
  // G⁺(X) v.
  Vec4 G_pinv_times(const Measurement& m, const Vec3& v) const {
    if (constant_G_) return G_pinv_ * v;
    return plant_.G_pinv(state(m)) * v;
  }

 private:
  static State state(const Measurement& m) { return (State() << m.X1, m.X2).finished(); }

  const Plant& plant_;
  bool constant_G_;
  Mat43 G_pinv_;
};

}  // namespace ftc::sim::detail
