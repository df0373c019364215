#pragma once
// sin and cos of angles that move in small steps (attitude angles, joint angles), as in
// SinCosTracker (sincos.hpp): from an anchor by the Taylor series of sin δ and cos δ for
// |δ| ≤ 0.02, the anchor renewed (in the lanes that need it) otherwise. For a plant's lane code
// (PlantLanes, lanes/closed_loop.hpp).
#include <limits>

#include "lanes/elementary.hpp"

namespace ftc::sim::detail {
inline namespace FTC_ISA_NS {

// Out of line, as it is rare. x by value: an address passed to it would make the caller's state
// (the closed loop's X) addressable, and its compiler would then keep it in memory throughout.
template <class T>
[[gnu::noinline]] void anchor_sincos(T x, T& s, T& c) {
  lane::sincos(x, s, c);
}

template <class T>
struct AngleTracker {
  T anchor = T(std::numeric_limits<double>::quiet_NaN());
  T s = T(0.0), c = T(1.0);

  FTC_HOT_INLINE void eval(const T& x, T& so, T& co) {
    const lane::Mask<T> near = lane::abs(x - anchor) <= T(0.02);  // false for NaN
    if (!lane::all(near)) [[unlikely]] {
      T sn, cn;
      anchor_sincos(x, sn, cn);
      anchor = lane::select(near, anchor, x);
      s = lane::select(near, s, sn);
      c = lane::select(near, c, cn);
    }
    const T d = x - anchor;
    const T d2 = d * d;
    const T sd = d * (T(1.0) + d2 * (T(-1.0 / 6) + d2 * (T(1.0 / 120) + d2 * T(-1.0 / 5040))));
    const T cd =
        T(1.0) + d2 * (T(-0.5) + d2 * (T(1.0 / 24) + d2 * (T(-1.0 / 720) + d2 * T(1.0 / 40320))));
    so = s * cd + c * sd;
    co = c * cd - s * sd;
  }
};

}  // namespace FTC_ISA_NS
}  // namespace ftc::sim::detail
