#pragma once
// The spacecraft's f(X), inline for the simulator, which evaluates it four times a sample
// through the final class. Private to sim_core: the workspace's angle trackers are a speed
// device, not part of the model.
#include <array>

#include "ftc/sim/spacecraft.hpp"
#include "lanes/lane.hpp"
#include "sincos.hpp"

namespace ftc::sim {

struct Spacecraft::Workspace {
  std::array<SinCosTracker, 3> trig{};  // one per attitude angle
};

FTC_HOT_INLINE Vec3 Spacecraft::f(const State& x, Workspace& ws) const {
  double s[3], c[3];
  for (int i = 0; i < 3; ++i) ws.trig[i].eval(x[i], s[i], c[i]);
  return f_trig(x, s, c);
}

// Appendix B (B.1–B.3), with the erratum of B.3 (s_2 x3 read as sin² x3), over the lane type
// T: the scalar plant and the batch simulator's W plants in lockstep (lanes/closed_loop.hpp, plants/spacecraft_lanes.cpp)
// evaluate the same operations. kx, ky, kz are (Iy-Iz)/Ix, (Iz-Ix)/Iy, (Ix-Iy)/Iz, w the
// orbital rate ω0; s and c the sines and cosines of the attitude angles x1, x2, x3. The terms
// are grouped by powers of ω0 and shared trigonometric products are formed once;
// sin(2x) = 2 sin x cos x. tests/test_spacecraft.cpp checks this against a term-by-term
// transcription of the paper.
inline namespace FTC_ISA_NS {
template <class T>
FTC_HOT_INLINE void spacecraft_f(const T& kx, const T& ky, const T& kz, const T& w, const T& x4,
                                 const T& x5, const T& x6, const T (&s)[3], const T (&c)[3],
                                 T (&out)[3]) {
  const T s1 = s[0], s2 = s[1], s3 = s[2];
  const T c1 = c[0], c2 = c[1], c3 = c[2];
  const T two(2.0), half(0.5), three_halves(1.5);
  const T d1 = two * s1 * c1, d2 = two * s2 * c2, d3 = two * s3 * c3;
  const T w2 = w * w;

  const T s3s2 = s3 * s2, s3c2 = s3 * c2;
  const T A = c1 * s3s2 + c3 * s1;  // c1 s3 s2 + c3 s1
  const T B = c3 * c1 - s3s2 * s1;  // c3 c1 - s3 s2 s1

  out[0] = w * (x6 * c3 * c2 - x5 * s3s2) +
           kx * (x5 * x6 + w * (x5 * A + x6 * B - d2 * s2 * s1 * s1) +
                 w2 * (half * d3 * c1 * c1 * s2 +
                       d1 * (half * c3 * c3 - half * s2 * s2 * s3 * s3 - three_halves * c2 * c2)));
  out[1] = w * (x6 * (s3 * c1 + c3 * s2 * s1) + x4 * A + x5 * s3c2 * s1) +
           ky * (x4 * x6 + w * (x4 * s2 * (c1 * s3 + c3 * s1) - x6 * s3c2) +
                 w2 * (-half * d2 * s3 * s3 * c1 - half * c2 * s1 * d3 + three_halves * d2 * c1));
  out[2] = w * (x6 * (s3 * s1 - c1 * c3 * s2) - x4 * B - x5 * c1 * s3c2) +
           kz * (x4 * x5 + w * (x4 * B - x5 * s3c2) +
                 w2 * (-half * d3 * c2 * c1 - half * s3 * s3 * s1 * d2 - three_halves * d2 * s1));
}
}  // namespace FTC_ISA_NS

FTC_HOT_INLINE Vec3 Spacecraft::f_trig(const State& x, const double (&s)[3],
                                       const double (&c)[3]) const {
  double out[3];
  spacecraft_f<double>(kx_, ky_, kz_, params_.orbital_rate, x[3], x[4], x[5], s, c, out);
  return Vec3(out[0], out[1], out[2]);
}

}  // namespace ftc::sim
