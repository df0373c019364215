#pragma once
// Sensors in the loop (SPEC §18; docs/model.md "Sensors"): what the controller reads instead of
// the exact state. Per sample k and axis i, with z independent standard normal draws:
//
//   X1m_k = q_a(X1_k + σ_a z)                    attitude (rad), noise σ_a (rad, 1σ)
//   X2m_k = q_r(X2_k + b_k + σ_r z)              rate (rad/s), noise σ_r (rad/s, 1σ)
//   b_{k+1} = b_k + σ_w √Ts z,  b_0 = bias       the rate bias's random walk, σ_w (rad/s/√s)
//   q(x) = Q · round(x / Q) when Q > 0 (half away from zero), x when Q = 0
//
// The acceleration the controller reads is either the exact a_k of the loop (`ideal`, undelayed)
// or `differentiated`: d_k = (X2m_k − X2m_{k−1}) / Ts (d_0 = 0) through the first-order low-pass
// y_k = y_{k−1} + (Ts / (τ + Ts)) (d_k − y_{k−1}), y_{−1} = 0, τ ≥ 0 (s). With a delay of d whole
// samples the controller at sample k reads the measurements of sample max(0, k − d), the
// differentiated acceleration included. The controller's model terms (f, and G⁺ where G depends
// on the state) are evaluated at the state it reads. The metrics measure the true state.
//
// The noise is a function of the scenario alone (common random numbers: every candidate sees
// the same measurement noise): one SplitMix64 stream per scenario (ftc/sim/random_stream.hpp),
// s0 = mix(seed XOR mix(0x53454E53 + i + 1)), i the scenario's 0-based index among the job's
// scenarios (an ensemble member's index among the members), normals by Box–Muller from one
// continuous stream of pairs, drawn per sample in the order angle noise axes 1..n, rate noise
// axes 1..n, bias walk axes 1..n, each drawn whether its σ is 0 or not.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ftc/sim/input_error.hpp"
#include "ftc/sim/random_stream.hpp"
#include "ftc/sim/range.hpp"

namespace ftc::sim {

struct AngleSensor {
  double noise = 0.0;         // σ_a, rad (1σ)
  double quantization = 0.0;  // Q_a, rad; 0: none
};

struct RateSensor {
  double noise = 0.0;         // σ_r, rad/s (1σ)
  std::vector<double> bias;   // b_0, rad/s: empty (0), one for every axis, or one per axis
  double bias_walk = 0.0;     // σ_w, rad/s/√s
  double quantization = 0.0;  // Q_r, rad/s; 0: none
  double bias_of(int axis) const {
    return bias.empty() ? 0.0 : bias.size() == 1 ? bias[0] : bias[static_cast<std::size_t>(axis)];
  }
};

enum class AccelerationSource { ideal, differentiated };

struct AccelerationSensor {
  AccelerationSource source = AccelerationSource::ideal;
  double time_constant = 0.0;  // τ of the low-pass, s (differentiated only)
};

struct SensorModel {
  // The stream's seed as the job gives it; absent: 1 for a listed scenario, the ensemble's seed
  // for its members.
  std::optional<std::uint64_t> seed;
  AngleSensor angle;
  RateSensor rate;
  int delay = 0;  // d, whole samples
  AccelerationSensor acceleration;

  // The stream's index i as the job gives it (`stream`); absent: the scenario's index among the
  // listed ones (0 for a scenario read alone). An ensemble member is written with its own, so
  // that a member replayed alone, or listed in a scenarios file, draws its noise.
  std::optional<std::uint64_t> stream;

  // The stream as resolved (SPEC §18; resolve()): its seed and the index i.
  std::uint64_t stream_seed = 1;
  std::uint64_t stream_index = 0;
  // Sets stream_seed to `seed`, else `default_seed`, and stream_index to `stream`, else
  // `default_index`.
  void resolve(std::uint64_t default_seed, std::uint64_t default_index) {
    stream_seed = seed.value_or(default_seed);
    stream_index = stream.value_or(default_index);
  }

  static constexpr Range kNoiseRange = Range::non_negative();
  static constexpr int kMaxDelay = 1000;
  static constexpr std::uint64_t kStreamSalt = 0x53454E53;  // "SENS"

  // The controller reads the exact state and acceleration: no noise, bias, walk, quantisation
  // or delay, and the ideal acceleration. The loop is then the loop without sensors, bit for bit.
  bool exact() const;
  // One line for reports: "angle noise 0.0001 rad, rate noise 0.001 rad/s, ..., delay 1
  // sample, acceleration differentiated (τ = 0.005 s), noise seed 1, stream 0".
  std::string summary() const;
  // Every bad field, for a plant with `axes` (n).
  std::vector<FieldError> validate(const std::string& path, int axes) const;
};

// The measurement noise of one scenario, sample after sample (the stream above): the terms σ_a z
// of the angles, the rates' bias b_k and their σ_r z, kept apart so that the loop adds them in
// §18's order, (X2 + b_k) + σ_r z; quantisation, delay and the acceleration are the loop's
// (lanes/closed_loop.hpp), as they act on the state.
class SensorNoise {
 public:
  SensorNoise(const SensorModel& model, int axes, double sample_time);
  // The next sample's terms: angle[0..n), bias[0..n), rate[0..n).
  void next(double* angle, double* bias, double* rate);
  // The next standard normal of the stream (Box–Muller: r = sqrt(−2 ln(1 − u1)), z = r cos(2π
  // u2), then r sin(2π u2) for the next request).
  double normal();

 private:
  SplitMix64 rng_;
  double sa_, sr_, sw_;  // σ_a, σ_r, σ_w √Ts
  std::vector<double> bias_;
  std::vector<double> z_;  // one sample's 3n normals
  double spare_ = 0.0;
  bool have_spare_ = false;
};

// The simulator keeps a scenario's noise once drawn, 3n doubles a sample, in a process-wide cache
// of at most this many bytes (least recently used out); a table larger than a quarter of it is
// not kept but drawn as its pack runs. The memory budget charges it (tune/run/memory_budget.hpp).
inline constexpr std::size_t kNoiseCacheBytes = std::size_t{256} << 20;

// §18's q(x) = Q · round(x / Q), ties away from zero; x when Q = 0.
double quantize(double x, double step);

// A scenario's sensors for a loop written sample by sample (the runtime example's plant, tests):
// what the controller reads of the true attitude and rates, as the tuner's loop gives them —
// the noise of the scenario's stream, the quantisers and the delay. The differentiated
// acceleration is the flight software's part (ftc/runtime/acceleration.hpp, on the rates this
// returns); the ideal one is the loop's exact a_k.
class SensorReadout {
 public:
  // `model` resolved (SensorModel::resolve).
  SensorReadout(const SensorModel& model, int axes, double sample_time);
  // Sample k's true X1 and X2 (axes values each), for k = 0, 1, ... in order: writes the
  // measurement of sample max(0, k − d) the controller reads at sample k.
  void measure(const double* X1, const double* X2, double* X1m, double* X2m);

 private:
  SensorNoise noise_;
  int axes_, delay_;
  double angle_step_, rate_step_;
  std::vector<double> angle_, bias_, rate_;  // one sample's noise terms
  std::vector<double> ring_;                 // delay + 1 samples of (X1m, X2m)
  long long k_ = 0;
};

}  // namespace ftc::sim
