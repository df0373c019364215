#include "controllers/sig_power.hpp"

#include <cmath>

namespace ftc::sim {

// The tables in long double (64-bit significand on x86-64): a·e is exact there, and exp2l and
// powl are accurate to well below a double ulp, so each entry is the double nearest its value.
SigPowerTables::SigPowerTables(double exponent) : a(exponent) {
  const long double al = a;
  long double c = 1.0L;
  for (int k = 0; k < static_cast<int>(b.size()); ++k) {
    b[k] = static_cast<double>(c);
    c = c * (al - k) / (k + 1);
  }
  for (int i = 0; i < kExponents; ++i) {
    const long double e = static_cast<long double>(i + kMinBiasedExponent - 1023);
    scale[i] = static_cast<double>(std::exp2(al * e));
  }
  for (int j = 0; j < kIntervals; ++j) {
    const double centre = 1.0 + (j + 0.5) / kIntervals;  // exact
    const double inv = 1.0 / centre;
    inv_centre[j] = inv;
    centre_power[j] = static_cast<double>(std::pow(1.0L / inv, al));
  }
}

}  // namespace ftc::sim
