#pragma once
// The tuner's random numbers: std::mt19937_64 seeded from the job, with doubles formed from the
// top 53 bits by hand, because std::uniform_real_distribution differs between standard
// libraries. Same seed, same sequence, on any platform.
#include <cstdint>
#include <random>

namespace ftc::tune {

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : gen_(seed) {}

  double uniform() { return static_cast<double>(gen_() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

  std::mt19937_64& engine() { return gen_; }  // for saving and restoring the state
  const std::mt19937_64& engine() const { return gen_; }

 private:
  std::mt19937_64 gen_;
};

}  // namespace ftc::tune
