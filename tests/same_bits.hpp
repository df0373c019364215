#pragma once
// Bit-for-bit comparison of doubles, for the tests that check determinism and same-bits claims.
#include <bit>
#include <cstdint>

namespace ftc::testing {

// Whether a and b are the same bits: unlike ==, +0 and -0 differ and a NaN equals its copy.
inline bool same_bits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

}  // namespace ftc::testing
