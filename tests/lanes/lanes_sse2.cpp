// Compiled for sse2 (tests/CMakeLists.txt sets the flags of this file alone).
#define FTC_LANES_XSIMD 1
#include "lanes/lane_functions.hpp"

namespace ftc::test {

void lanes_sse2(const double* xs, std::size_t n, double* out) {
  lanes_for<xsimd::sse2>(xs, n, out);
}

}  // namespace ftc::test
