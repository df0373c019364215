#pragma once
// A reaction-wheel inverted pendulum with two wheels on its axle (n = 1, m = 2): a rigid
// pendulum on a pivot, balanced upright by the reaction torques of two motor-driven wheels
// mounted on it (Åström, Block and Spong, "The Reaction Wheel Pendulum", 2007, with a second
// wheel for fault tolerance).
//
// State: X1 = θ in rad, the pendulum's angle from upright (positive either way, gravity pulls it
// further); X2 = θ̇ in rad/s. A wheel's motor applies the torque τ_j to its wheel and −τ_j to the
// pendulum; with J the pendulum's moment of inertia about the pivot, wheels included (kg·m²),
// m ℓ the product of its mass and the distance from the pivot to its centre of mass (kg·m), g0
// the gravity (m/s²) and b the pivot's viscous friction (N·m·s/rad):
//
//   J θ̈ = m ℓ g0 sin θ − b θ̇ − Σ_j k_j u_j
//
// where u_j is the torque commanded to wheel j (N·m) and k_j the share of it the motor gives
// (1 for a healthy motor; an effectiveness the plant declares per actuator). In the form
// dX2/dt = f(X) + G u + Δ:
//
//   f(X) = (m ℓ g0 / J) sin θ − (b / J) θ̇          (rad/s²)
//   G    = −[k_1, k_2] / J                         (rad/s² per N·m), constant in X
//   G⁺   = Gᵀ / (G Gᵀ) = Gᵀ / (g_1² + g_2²)         (one wheel's torque is enough: m = 2 > n = 1)
//
// The wheels' own speeds do not enter θ's equation (they only matter to a wheel's speed limit,
// which this model leaves out). J and m ℓ are declared uncertain: a scenario can give their true
// values (model mismatch) and an ensemble scales them member by member.
#include <array>
#include <string>
#include <vector>

#include "ftc/sim/elementary.hpp"
#include "ftc/sim/plant.hpp"
#include "ftc/sim/plants.hpp"

namespace pendulum {

struct Params {
  double inertia = 0.04;                        // J, kg·m²
  double mass_length = 0.12;                    // m ℓ, kg·m
  double gravity = 9.81;                        // g0, m/s²
  double friction = 5e-4;                       // b, N·m·s/rad
  std::array<double, 2> wheel_gains{1.0, 1.0};  // k_1, k_2
};

// G⁺ of G = [g1, g2] as Plant::right_inverse forms it (GGᵀ = g1 g1 + g2 g2, then Gᵀ (GGᵀ)⁻¹),
// over the lane type T: the plant and its lane code evaluate the same operations.
template <class T>
inline void pinv(const T& g1, const T& g2, T* out) {
  const T inv = T(1.0) / (g1 * g1 + g2 * g2);
  out[0] = g1 * inv;
  out[1] = g2 * inv;
}

class Pendulum final : public ftc::sim::Plant<1, 2> {
 public:
  // Throws InputError for a non-positive inertia or a negative friction or gain.
  explicit Pendulum(const Params& p = {});

  Vector f(const State& x) const override {
    return Vector(a_ * ftc::sim::math::sin(x[0]) - c_ * x[1]);
  }
  InputMatrix G(const State&) const override { return InputMatrix(g1_, g2_); }
  InputInverse G_pinv(const State&) const override {
    double out[2];
    pinv<double>(g1_, g2_, out);
    return InputInverse(out[0], out[1]);
  }
  // G does not depend on X, but it depends on J, which a scenario may give truly: the lane code
  // evaluates the simulated plant's G, so the loop does not read the model's once.
  bool input_matrix_is_constant() const override { return false; }
  std::string model() const override { return "plugin:reaction_wheel_pendulum"; }

  // What the lane code reads per lane: a = m ℓ g0 / J, c = b / J, g1, g2.
  std::array<double, 4> f_constants() const { return {a_, c_, g1_, g2_}; }

 private:
  double a_, c_, g1_, g2_;
};

// The plant as job files know it (its parameters in the order build() reads them), and a plant
// made from those values; FTCTUNE_PLANT_PLUGIN in pendulum.cpp gives both to ftctune, and a
// program that compiles the plant in (tests) registers them itself.
ftc::sim::PlantKind kind();
Pendulum build(const std::vector<double>& values);

}  // namespace pendulum
