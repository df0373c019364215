#pragma once
// The discrete-time controller interface shared by the simulator and the runtime.
//
// A controller runs every Ts seconds. At sample k it receives the measured positions X1,
// rates X2 and accelerations a = dX2/dt (the "acceleration sensor" the sliding surface
// sF = a + C(X) needs), returns the commanded actuator outputs u_d, and then advances its
// internal states with forward Euler. reset() returns it to its initial state. For the
// spacecraft X1 is in rad, X2 in rad/s, a in rad/s².
//
// The four laws (NFTSMC, FOSMC, PI-FOSMC, adaptive neural PI-FOSMC) are written once for any
// plant shape; their equations are in the headers under sim_core/controllers/.
#include <memory>

#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/plant.hpp"
#include "ftc/sim/types.hpp"

namespace ftc::sim {

// One sample of measurements. `f` optionally carries f(X) of the plant `f_of` as the caller
// computed it (the simulator has it from its acceleration sensor); a model-based controller
// uses it when `f_of` is its own model, and evaluates its model otherwise (model mismatch, or
// none given).
template <int N>
struct Measurement {
  double t = 0.0;
  Vec<N> X1 = Vec<N>::Zero();
  Vec<N> X2 = Vec<N>::Zero();
  Vec<N> a = Vec<N>::Zero();
  const Vec<N>* f = nullptr;
  const void* f_of = nullptr;  // the plant (a Plant<N, M>) whose f(X) `f` is
};

template <int N, int M>
class Controller {
 public:
  using Vector = Vec<N>;
  using Input = Vec<M>;

  virtual ~Controller() = default;

  virtual void reset() = 0;
  virtual Input step(const Measurement<N>& m) = 0;
  Input step(double t, const Vector& X1, const Vector& X2, const Vector& a) {
    return step(Measurement<N>{t, X1, X2, a, nullptr});
  }

  // The configuration as used (α1 resolved).
  virtual const ControllerConfig& config() const = 0;
  virtual double sample_time() const = 0;
};

// Builds the controller of config.type for a plant and sample time. Throws InputError naming
// every invalid field (source "controller"). The plant must outlive the controller. Defined
// for the shapes of the plants in sim_core/plants/registry.cpp.
template <int N, int M>
std::unique_ptr<Controller<N, M>> make_controller(const ControllerConfig& config,
                                                  const Plant<N, M>& plant, double sample_time);

}  // namespace ftc::sim
