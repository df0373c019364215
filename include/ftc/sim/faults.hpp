#pragma once
// Actuator faults (paper eqs. 2–4, SPEC §3).
//
//     u_j(t) = u_d,j + Σ_{faults on j} ρ(t - t_f) δu_j(t),    then optional |u_j| ≤ u_max
//
// Profiles: abrupt ρ(τ) = 1 for τ ≥ 0; incipient ρ(τ) = 1 - exp(-β τ); ρ = 0 before onset.
// Types: bias δu = offset + amplitude cos(frequency t + phase);
//        loss_of_effectiveness δu = -fraction u_d;  stuck δu = value - u_d.
//
// Every fault is affine in the command, so a fault set at time t reduces to
// u = sat(gain(t) ⊙ u_d + offset(t)); the simulator evaluates (gain, offset) once per stage time.
#include <cmath>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ftc/sim/input_error.hpp"
#include "ftc/sim/sincos.hpp"
#include "ftc/sim/types.hpp"

namespace ftc::sim {

enum class FaultType { bias, loss_of_effectiveness, stuck };
enum class FaultProfileType { abrupt, incipient };

struct FaultProfile {
  FaultProfileType type = FaultProfileType::abrupt;
  double rate = 1.0;  // β in 1/s, incipient only

  double rho(double tau) const {  // ρ(τ)
    if (tau < 0.0) return 0.0;
    if (type == FaultProfileType::abrupt) return 1.0;
    return 1.0 - std::exp(-rate * tau);
  }
};

struct Fault {
  int actuator = 1;  // 1-based, 1..4
  FaultType type = FaultType::bias;
  double onset = 0.0;  // t_f in s
  FaultProfile profile;
  // bias
  double offset = 0.0;
  double amplitude = 0.0;
  double frequency = 0.0;  // rad/s
  double phase = 0.0;      // rad
  // loss_of_effectiveness
  double fraction = 0.0;  // 0..1
  // stuck
  double value = 0.0;

  std::vector<FieldError> validate(const std::string& path) const;
};

// The faults' effect at one instant: u = gain ⊙ u_d + offset (before saturation).
struct FaultEffect {
  Vec4 gain = Vec4::Ones();
  Vec4 offset = Vec4::Zero();
};

class FaultSet {
 public:
  FaultSet() = default;
  FaultSet(std::vector<Fault> faults, std::optional<double> saturation);

  FaultEffect effect(double t) const;
  // The same with the bias sinusoids read from one phasor per fault (made by phasors(),
  // advanced by the caller to t).
  FaultEffect effect(double t, std::span<const Phasor> phasors) const;  // inline below
  // One phasor per fault stepping by dt, not yet anchored (unused but for bias faults).
  std::vector<Phasor> phasors(double dt) const;
  // Applied actuator output for a held command: sat(gain ⊙ u_d + offset).
  Vec4 apply(const FaultEffect& e, const Vec4& u_d) const {
    Vec4 u = e.gain.cwiseProduct(u_d) + e.offset;
    if (saturation_) u = u.cwiseMax(-*saturation_).cwiseMin(*saturation_);
    return u;
  }
  Vec4 apply(double t, const Vec4& u_d) const { return apply(effect(t), u_d); }

  const std::vector<Fault>& faults() const { return faults_; }
  const std::optional<double>& saturation() const { return saturation_; }

 private:
  std::vector<Fault> faults_;
  std::optional<double> saturation_;  // u_max, absent = no saturation
};

namespace detail {
// Σ over the faults of ρ δu, in affine form; cosine(i) is cos(ω t + φ) of fault i.
template <class Cos>
FaultEffect combine_faults(const std::vector<Fault>& faults, double t, Cos&& cosine) {
  FaultEffect e;
  for (std::size_t i = 0; i < faults.size(); ++i) {
    const Fault& f = faults[i];
    const double rho = f.profile.rho(t - f.onset);
    if (rho == 0.0) continue;
    const int j = f.actuator - 1;
    switch (f.type) {
      case FaultType::bias:
        e.offset[j] += rho * (f.offset + f.amplitude * cosine(i));
        break;
      case FaultType::loss_of_effectiveness:
        e.gain[j] -= rho * f.fraction;
        break;
      case FaultType::stuck:  // δu = value - u_d
        e.gain[j] -= rho;
        e.offset[j] += rho * f.value;
        break;
    }
  }
  return e;
}
}  // namespace detail

// Inline: the simulator evaluates it twice a sample.
inline FaultEffect FaultSet::effect(double t, std::span<const Phasor> phasors) const {
  return detail::combine_faults(faults_, t, [&](std::size_t i) { return phasors[i].cos(); });
}

const char* to_string(FaultType t);
const char* to_string(FaultProfileType t);

}  // namespace ftc::sim
