#pragma once
// Additive disturbance Δ(t) on the accelerations (SPEC §2): per axis a sum of sinusoids
// Δ_i(t) = Σ amplitude · shape(frequency · t + phase), shape ∈ {sin, cos}, in rad/s².
#include <span>
#include <string>
#include <vector>

#include "ftc/sim/input_error.hpp"
#include "ftc/sim/sincos.hpp"
#include "ftc/sim/types.hpp"

namespace ftc::sim {

enum class Shape { sin, cos };
const char* to_string(Shape s);

struct DisturbanceTerm {
  int axis = 1;  // 1-based axis index, 1..3
  Shape shape = Shape::sin;
  double amplitude = 0.0;  // rad/s²
  double frequency = 0.0;  // rad/s
  double phase = 0.0;      // rad

  std::vector<FieldError> validate(const std::string& path) const;
};

class Disturbance {
 public:
  Disturbance() = default;
  explicit Disturbance(std::vector<DisturbanceTerm> terms);

  Vec3 operator()(double t) const;
  // The same from one phasor per term (made by phasors(), advanced by the caller to t).
  Vec3 operator()(std::span<const Phasor> phasors) const;
  // One phasor per term stepping by dt, not yet anchored.
  std::vector<Phasor> phasors(double dt) const;
  const std::vector<DisturbanceTerm>& terms() const { return terms_; }

 private:
  std::vector<DisturbanceTerm> terms_;
};

// Inline: the simulator evaluates it twice a sample.
inline Vec3 Disturbance::operator()(std::span<const Phasor> phasors) const {
  Vec3 d = Vec3::Zero();
  for (std::size_t i = 0; i < terms_.size(); ++i) {
    const DisturbanceTerm& term = terms_[i];
    d[term.axis - 1] +=
        term.amplitude * (term.shape == Shape::sin ? phasors[i].sin() : phasors[i].cos());
  }
  return d;
}

}  // namespace ftc::sim
