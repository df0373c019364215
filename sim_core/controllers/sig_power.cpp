#include "controllers/sig_power.hpp"

namespace ftc::sim {

// The tables in long double (64-bit significand on x86-64): a·e is exact there, and exp2l and
// powl are accurate to well below a double ulp, so each entry is the double nearest its value.
SigPower::SigPower(double a) : a_(a) {
  const long double al = a;
  long double c = 1.0L;
  for (int k = 0; k < static_cast<int>(b_.size()); ++k) {
    b_[k] = static_cast<double>(c);
    c = c * (al - k) / (k + 1);
  }
  for (std::uint64_t i = 0; i < kExponents; ++i) {
    const long double e =
        static_cast<long double>(static_cast<std::int64_t>(i + kMinBiasedExponent) - 1023);
    scale_[i] = static_cast<double>(std::exp2(al * e));
  }
  for (int j = 0; j < kIntervals; ++j) {
    const double centre = 1.0 + (j + 0.5) / kIntervals;  // exact
    const double inv = 1.0 / centre;
    mantissa_[j] = {inv, static_cast<double>(std::pow(1.0L / inv, al))};
  }
}

}  // namespace ftc::sim
