#pragma once
// Actuator faults (paper eqs. 2–4, SPEC §3) and the actuators' limits (SPEC §17.1).
//
//     c_j = clamp(u_d,j, −L_j, L_j)                          the command within its limit
//     u_j(t) = c_j + Σ_{faults on j} ρ(t - t_f) δu_j(t)      then the faults act on it
//     u_j ← clamp(u_j, −L_j, L_j)                             and the limit again
//
// so a weakened actuator (a loss ρ) delivers at most (1 − ρ) L_j, whatever it is commanded, and
// a bias or a stuck value never drives it past its limit. L_j = +inf without a limit.
//
// Profiles: abrupt ρ(τ) = 1 for τ ≥ 0; incipient ρ(τ) = 1 - exp(-β τ); ρ = 0 before onset.
// Types: bias δu = offset + amplitude cos(frequency t + phase);
//        loss_of_effectiveness δu = -fraction u_d;  stuck δu = value - u_d.
//
// Every fault is affine in the command, so a fault set at time t reduces to
// u = sat(gain(t) ⊙ sat(u_d) + offset(t)); the simulator evaluates (gain, offset) once per stage
// time.
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "ftc/sim/elementary.hpp"
#include "ftc/sim/fields.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/types.hpp"

namespace ftc::sim {

// The limit of each actuator's command, |u_j| ≤ limit(j) (a scenario's `saturation`): one value
// for every actuator, one per actuator, or none (+inf).
struct Saturation {
  std::vector<double> values;  // empty: none; one: every actuator's; else actuator j's at j

  Saturation() = default;
  Saturation(double limit) : values{limit} {}  // NOLINT: a number is one limit for all
  Saturation(std::optional<double> limit) {    // NOLINT
    if (limit) values = {*limit};
  }
  Saturation(std::vector<double> limits) : values(std::move(limits)) {}  // NOLINT
  Saturation(std::nullopt_t) {}                                          // NOLINT

  bool has_value() const { return !values.empty(); }
  explicit operator bool() const { return has_value(); }
  bool per_actuator() const { return values.size() > 1; }
  // Actuator j's limit (0-based), +inf without one (and past the list: a rigid body's kernel
  // columns past its m).
  double limit(int j) const {
    if (values.empty()) return std::numeric_limits<double>::infinity();
    if (values.size() == 1) return values[0];
    const auto i = static_cast<std::size_t>(j);
    return i < values.size() ? values[i] : std::numeric_limits<double>::infinity();
  }
};

enum class FaultType { bias, loss_of_effectiveness, stuck };
enum class FaultProfileType { abrupt, incipient };

struct FaultProfile {
  FaultProfileType type = FaultProfileType::abrupt;
  double rate = 1.0;  // β in 1/s, incipient only

  static const NumberField<FaultProfile>& rate_field();

  double rho(double tau) const {  // ρ(τ)
    if (tau < 0.0) return 0.0;
    if (type == FaultProfileType::abrupt) return 1.0;
    // Past β τ = 40, exp(−β τ) < 4.3e-18 < 2^-54, and 1 − exp(−β τ) rounds to 1 (the same
    // bits, without the exp).
    const double x = rate * tau;
    return x > 40.0 ? 1.0 : 1.0 - math::exp(-x);
  }
};

struct Fault {
  int actuator = 1;  // 1-based, 1..m
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

  // Every bad field; `actuators` is the plant's m.
  std::vector<FieldError> validate(const std::string& path, int actuators) const;

  // The numeric fields every fault has (onset), those of one type, and the actuator index.
  static std::span<const NumberField<Fault>> common_fields();
  static std::span<const NumberField<Fault>> type_fields(FaultType type);
  static const IntegerField<Fault>& actuator_field();
};

// The faults' effect at one instant on the m actuators: u = gain ⊙ u_d + offset (between the
// limits).
template <int M>
struct FaultEffect {
  Vec<M> gain = Vec<M>::Ones();
  Vec<M> offset = Vec<M>::Zero();
};

class FaultSet {
 public:
  FaultSet() = default;
  FaultSet(std::vector<Fault> faults, Saturation saturation);

  template <int M>
  FaultEffect<M> effect(double t) const;
  // The effects at the instants t[0..n) into out(0) .. out(n-1) (each a FaultEffect<M>&), given
  // cosine(i, k) = cos(ω_i t_k + φ_i)
  // of fault i at instant k (read for bias faults only). The simulator fills a block of
  // instants at once from phasor tables; effect(t) is the case n = 1, evaluating the cosines
  // directly.
  template <class Cos, class Out>
  void evaluate(std::span<const double> t, Cos&& cosine, Out&& out) const;
  // Applied actuator output for a held command: sat(gain ⊙ sat(u_d) + offset), the limits of
  // the set's saturation. (The closed loop clamps with the same comparisons, in the same order:
  // lanes/closed_loop.hpp's forcing.)
  template <int M>
  FTC_HOT_INLINE Vec<M> apply(const FaultEffect<M>& e, const Vec<M>& u_d) const {
    Vec<M> u;
    for (int j = 0; j < M; ++j) {
      const double m = saturation_.limit(j), lo = -m;
      double c = u_d[j] < lo ? lo : u_d[j];
      c = c > m ? m : c;
      double v = e.gain[j] * c + e.offset[j];
      v = v < lo ? lo : v;
      u[j] = v > m ? m : v;
    }
    return u;
  }
  template <int M>
  Vec<M> apply(double t, const Vec<M>& u_d) const {
    return apply(effect<M>(t), u_d);
  }

  const std::vector<Fault>& faults() const { return faults_; }
  const Saturation& saturation() const { return saturation_; }

 private:
  std::vector<Fault> faults_;
  Saturation saturation_;
};

// Σ over the faults of ρ δu, in affine form. Faults are taken in order at every instant, so
// the sum is the same bit for bit whatever the number of instants.
template <class Cos, class Out>
void FaultSet::evaluate(std::span<const double> t, Cos&& cosine, Out&& out) const {
  using Effect = std::remove_reference_t<decltype(out(0))>;
  for (std::size_t k = 0; k < t.size(); ++k) out(k) = Effect{};
  // Per fault, its type's loop over the instants (no branch on the type per instant); each
  // instant still adds the faults in order.
  for (std::size_t i = 0; i < faults_.size(); ++i) {
    const Fault& f = faults_[i];
    const int j = f.actuator - 1;
    const auto each = [&](auto add) {
      for (std::size_t k = 0; k < t.size(); ++k) {
        const double rho = f.profile.rho(t[k] - f.onset);
        if (rho == 0.0) continue;
        add(out(k), rho, k);
      }
    };
    switch (f.type) {
      case FaultType::bias:
        each([&](Effect& e, double rho, std::size_t k) {
          e.offset[j] += rho * (f.offset + f.amplitude * cosine(i, k));
        });
        break;
      case FaultType::loss_of_effectiveness:
        each([&](Effect& e, double rho, std::size_t) { e.gain[j] -= rho * f.fraction; });
        break;
      case FaultType::stuck:  // δu = value - u_d
        each([&](Effect& e, double rho, std::size_t) {
          e.gain[j] -= rho;
          e.offset[j] += rho * f.value;
        });
        break;
    }
  }
}

template <int M>
FaultEffect<M> FaultSet::effect(double t) const {
  FaultEffect<M> e;
  evaluate(
      std::span<const double>(&t, 1),
      [&](std::size_t i, std::size_t) {
        return math::cos(faults_[i].frequency * t + faults_[i].phase);
      },
      [&](std::size_t) -> FaultEffect<M>& { return e; });
  return e;
}

const char* to_string(FaultType t);
const char* to_string(FaultProfileType t);

}  // namespace ftc::sim
