#pragma once
// The tuner's random numbers: std::mt19937_64 seeded from the job, with doubles formed from the
// top 53 bits by hand, because std::uniform_real_distribution differs between standard
// libraries. Same seed, same sequence, on any platform.
#include <cstdint>
#include <random>
#include <sstream>
#include <string>

namespace ftc::tune {

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : gen_(seed) {}

  double uniform() { return static_cast<double>(gen_() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

  // The engine's full state as text (the standard's textual representation) and back.
  std::string save() const {
    std::ostringstream o;
    o << gen_;
    return o.str();
  }
  // False (and the engine unchanged) unless `state` is exactly one engine state, as save() writes.
  [[nodiscard]] bool load(const std::string& state) {
    std::istringstream in(state);
    std::mt19937_64 g;
    in >> g;
    if (in.fail()) return false;
    in >> std::ws;
    if (!in.eof()) return false;
    gen_ = g;
    return true;
  }

 private:
  std::mt19937_64 gen_;
};

}  // namespace ftc::tune
