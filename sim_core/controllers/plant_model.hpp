#pragma once
// The plant as a model-based controller uses it: f(X) and G⁺(X) at the measured state. G⁺ is
// read once when the plant says G is constant (the spacecraft), which saves a virtual call
// and an m×n copy every sample; f comes from the measurement when the caller already has it.
#include "ftc/sim/controller.hpp"

namespace ftc::sim::detail {

template <int N, int M>
class PlantModel {
 public:
  using P = Plant<N, M>;

  explicit PlantModel(const P& plant)
      : plant_(plant),
        constant_G_(plant.input_matrix_is_constant()),
        G_pinv_(constant_G_ ? plant.G_pinv(P::State::Zero()) : P::InputInverse::Zero()) {}

  FTC_HOT_INLINE Vec<N> f(const Measurement<N>& m) const { return m.f ? *m.f : plant_.f(state(m)); }
  // G⁺(X) v.
  FTC_HOT_INLINE Vec<M> G_pinv_times(const Measurement<N>& m, const Vec<N>& v) const {
    if (constant_G_) return G_pinv_ * v;
    return plant_.G_pinv(state(m)) * v;
  }

 private:
  static typename P::State state(const Measurement<N>& m) {
    return (typename P::State() << m.X1, m.X2).finished();
  }

  const P& plant_;
  bool constant_G_;
  typename P::InputInverse G_pinv_;
};

}  // namespace ftc::sim::detail
