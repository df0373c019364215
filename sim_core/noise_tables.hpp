#pragma once
// The measurement noise of a scenario's sensors (ftc/sim/sensors.hpp), kept once drawn: the noise
// is a function of the scenario alone (common random numbers), and a tuning run simulates each
// scenario once per candidate, so drawing it once per pack spent most of a sensed loop's time on
// Box–Muller (issue 39: 45.6 → 80 ns per sample and candidate on AVX-512). A process-wide cache of
// whole tables, least recently used first out, bounded in bytes; a table larger than a quarter of
// the bound is not kept (its pack draws as it goes). Private to sim_core (plants/lane_host.hpp).
#include <cstdint>
#include <memory>
#include <vector>

#include "ftc/sim/sensors.hpp"

namespace ftc::sim::detail {

// Sample k's 3n terms (SensorNoise::next: the angles' σ_a z, the rates' b_k, their σ_r z) at
// [k · 3n, (k + 1) · 3n).
using NoiseTable = std::vector<double>;

using sim::kNoiseCacheBytes;

// The table of `samples` samples of the model's stream; null when it would be larger than a
// quarter of kNoiseCacheBytes. Thread-safe.
std::shared_ptr<const NoiseTable> noise_table(const SensorModel& model, int axes,
                                              double sample_time, std::int64_t samples);

}  // namespace ftc::sim::detail
