#pragma once
// The plant concept of the paper (eq. 1): a second-order system
//
//     dX1/dt = X2
//     dX2/dt = f(X) + G(X) u + Δ(t)
//
// with X1, X2 in R^n and u in R^m the applied actuator outputs. The simulator and the
// model-based controllers see a plant only through this interface.
#include <array>
#include <string>

#include "ftc/sim/sincos.hpp"
#include "ftc/sim/types.hpp"

namespace ftc::sim {

// Scratch space owned by one simulation, which a plant may use to speed up evaluations at
// nearby states (the RK4 stages of a step). Plants themselves stay immutable, so one plant can
// serve many simulations on many threads.
struct PlantWorkspace {
  std::array<SinCosTracker, kAxes> trig{};  // one per attitude angle
};

class Plant {
 public:
  virtual ~Plant() = default;

  int n() const { return kAxes; }
  int m() const { return kActuators; }

  // Drift term f(X), rad/s².
  virtual Vec3 f(const State& x) const = 0;
  // The same f(X), allowed to reuse work kept in `ws` (equal to f(x) within a few ulp).
  virtual Vec3 f(const State& x, PlantWorkspace& /*ws*/) const { return f(x); }
  // Input matrix G(X), rad/s² per unit of actuator output.
  virtual Mat34 G(const State& x) const = 0;
  // True when G does not depend on X; the simulator then reads it once per run.
  virtual bool input_matrix_is_constant() const { return false; }
  // Moore–Penrose right inverse G⁺ = Gᵀ(GGᵀ)⁻¹, so that G G⁺ = I_n.
  virtual Mat43 G_pinv(const State& x) const = 0;

  virtual std::string model() const = 0;
};

}  // namespace ftc::sim
