#pragma once
// Additive disturbance Δ(t) on the accelerations (SPEC §2): per axis a sum of sinusoids
// Δ_i(t) = Σ amplitude · shape(frequency · t + phase), shape ∈ {sin, cos}, in rad/s².
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "ftc/sim/elementary.hpp"
#include "ftc/sim/fields.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/types.hpp"

namespace ftc::sim {

enum class Shape { sin, cos };
const char* to_string(Shape s);

struct DisturbanceTerm {
  int axis = 1;  // 1-based axis index, 1..n
  Shape shape = Shape::sin;
  double amplitude = 0.0;  // rad/s²
  double frequency = 0.0;  // rad/s
  double phase = 0.0;      // rad

  // Every bad field; `axes` is the plant's n.
  std::vector<FieldError> validate(const std::string& path, int axes) const;

  static std::span<const NumberField<DisturbanceTerm>> number_fields();
  static const IntegerField<DisturbanceTerm>& axis_field();
};

class Disturbance {
 public:
  Disturbance() = default;
  explicit Disturbance(std::vector<DisturbanceTerm> terms);

  // Δ(t) on the N axes.
  template <int N>
  Vec<N> at(double t) const;
  // Δ at n instants into out(0) .. out(n-1) (each a Vec<N>&), given
  // value(i, k, shape) = shape(frequency_i t_k + phase_i)
  // of term i at instant k. The simulator fills a block of instants at once from phasor tables;
  // at(t) is the case n = 1, evaluating the sinusoids directly. Terms are summed in order, as the
  // definition reads, so both agree bit for bit on the same sinusoid values.
  template <class Value, class Out>
  void evaluate(std::size_t n, Value&& value, Out&& out) const;
  const std::vector<DisturbanceTerm>& terms() const { return terms_; }

 private:
  std::vector<DisturbanceTerm> terms_;
};

template <class Value, class Out>
void Disturbance::evaluate(std::size_t n, Value&& value, Out&& out) const {
  for (std::size_t k = 0; k < n; ++k) out(k).setZero();
  for (std::size_t i = 0; i < terms_.size(); ++i) {
    const DisturbanceTerm& term = terms_[i];
    const int a = term.axis - 1;
    for (std::size_t k = 0; k < n; ++k) out(k)[a] += term.amplitude * value(i, k, term.shape);
  }
}

template <int N>
Vec<N> Disturbance::at(double t) const {
  Vec<N> d;
  evaluate(
      1,
      [&](std::size_t i, std::size_t, Shape shape) {
        const double x = terms_[i].frequency * t + terms_[i].phase;
        return shape == Shape::sin ? math::sin(x) : math::cos(x);
      },
      [&](std::size_t) -> Vec<N>& { return d; });
  return d;
}

}  // namespace ftc::sim
