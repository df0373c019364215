#pragma once
// SplitMix64, the one random stream of ftctune's specification (SPEC §12): a counter and a
// finaliser, so that a stream is fixed by its seed alone and any implementation, on any CPU,
// draws the same numbers. Ensembles (ftc/tune/job/ensemble.hpp) draw their members from it and
// sensors (ftc/sim/sensors.hpp) their noise.
#include <cstdint>

namespace ftc::sim {

class SplitMix64 {
 public:
  // The finaliser: z ^= z >> 30; z *= 0xBF58476D1CE4E5B9; z ^= z >> 27; z *= 0x94D049BB133111EB;
  // z ^= z >> 31 (mod 2^64).
  static std::uint64_t mix(std::uint64_t z) {
    z ^= z >> 30;
    z *= 0xBF58476D1CE4E5B9ULL;
    z ^= z >> 27;
    z *= 0x94D049BB133111EBULL;
    z ^= z >> 31;
    return z;
  }
  // Stream k of a seed: s0 = mix(seed XOR mix(k + 1)) (an ensemble's member k; a scenario's
  // sensors use k = 0x53454E53 + i).
  static SplitMix64 member(std::uint64_t seed, std::uint64_t k) {
    return SplitMix64(mix(seed ^ mix(k + 1)));
  }

  explicit SplitMix64(std::uint64_t state) : s_(state) {}
  std::uint64_t next_bits() {
    s_ += kGamma;
    return mix(s_);
  }
  double uniform() { return static_cast<double>(next_bits() >> 11) * 0x1.0p-53; }  // [0, 1)
  // Moves the stream on by n draws, as n calls of next_bits() would (the state is a counter).
  void skip(std::uint64_t n) { s_ += n * kGamma; }

 private:
  static constexpr std::uint64_t kGamma = 0x9E3779B97F4A7C15ULL;
  std::uint64_t s_;
};

}  // namespace ftc::sim
