#pragma once
// The spacecraft's f(X), inline for the simulator, which evaluates it four times a sample
// through the final class. Private to sim_core: the workspace's angle trackers are a speed
// device, not part of the model.
#include <array>

#include "ftc/sim/spacecraft.hpp"
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

// Appendix B (B.1–B.3), with the erratum of B.3 (s_2 x3 read as sin² x3). The terms are grouped
// by powers of ω0 and shared trigonometric products are formed once; sin(2x) = 2 sin x cos x.
// tests/test_plant.cpp checks this against a term-by-term transcription of the paper.
FTC_HOT_INLINE Vec3 Spacecraft::f_trig(const State& x, const double (&s)[3],
                                       const double (&c)[3]) const {
  const double x4 = x[3], x5 = x[4], x6 = x[5];
  const double s1 = s[0], s2 = s[1], s3 = s[2];
  const double c1 = c[0], c2 = c[1], c3 = c[2];
  const double d1 = 2.0 * s1 * c1, d2 = 2.0 * s2 * c2, d3 = 2.0 * s3 * c3;
  const double w = params_.orbital_rate;
  const double w2 = w * w;

  const double s3s2 = s3 * s2, s3c2 = s3 * c2;
  const double A = c1 * s3s2 + c3 * s1;  // c1 s3 s2 + c3 s1
  const double B = c3 * c1 - s3s2 * s1;  // c3 c1 - s3 s2 s1

  const double f1 = w * (x6 * c3 * c2 - x5 * s3s2) +
                    kx_ * (x5 * x6 + w * (x5 * A + x6 * B - d2 * s2 * s1 * s1) +
                           w2 * (0.5 * d3 * c1 * c1 * s2 +
                                 d1 * (0.5 * c3 * c3 - 0.5 * s2 * s2 * s3 * s3 - 1.5 * c2 * c2)));
  const double f2 = w * (x6 * (s3 * c1 + c3 * s2 * s1) + x4 * A + x5 * s3c2 * s1) +
                    ky_ * (x4 * x6 + w * (x4 * s2 * (c1 * s3 + c3 * s1) - x6 * s3c2) +
                           w2 * (-0.5 * d2 * s3 * s3 * c1 - 0.5 * c2 * s1 * d3 + 1.5 * d2 * c1));
  const double f3 = w * (x6 * (s3 * s1 - c1 * c3 * s2) - x4 * B - x5 * c1 * s3c2) +
                    kz_ * (x4 * x5 + w * (x4 * B - x5 * s3c2) +
                           w2 * (-0.5 * d3 * c2 * c1 - 0.5 * s3 * s3 * s1 * d2 - 1.5 * d2 * s1));
  return Vec3(f1, f2, f3);
}

}  // namespace ftc::sim
