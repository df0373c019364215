#pragma once
// The discrete-time controller interface shared by the simulator and the runtime.
//
// A controller runs every Ts seconds. At sample k it receives the measured attitude X1 (rad),
// rates X2 (rad/s) and accelerations a = dX2/dt (rad/s², the "acceleration sensor" the
// sliding surface sF = a + C(X) needs), returns the commanded actuator outputs u_d, and then
// advances its internal states with forward Euler. reset() returns it to its initial state.
#include <memory>

#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/plant.hpp"
#include "ftc/sim/types.hpp"

namespace ftc::sim {

// One sample of measurements. `f` optionally carries f(X) already computed by the caller (the
// simulator has it from its acceleration sensor); model-based controllers then skip their own
// evaluation. The result is bit-identical either way.
struct Measurement {
  double t = 0.0;
  Vec3 X1 = Vec3::Zero();
  Vec3 X2 = Vec3::Zero();
  Vec3 a = Vec3::Zero();
  const Vec3* f = nullptr;
};

class Controller {
 public:
  virtual ~Controller() = default;

  virtual void reset() = 0;
  virtual Vec4 step(const Measurement& m) = 0;
  Vec4 step(double t, const Vec3& X1, const Vec3& X2, const Vec3& a) {
    return step(Measurement{t, X1, X2, a, nullptr});
  }

  // The configuration as used (α1 resolved).
  virtual const ControllerConfig& config() const = 0;
  virtual double sample_time() const = 0;
};

// Builds the controller of config.type for a plant and sample time. Throws InputError naming
// every invalid field (source "controller"). The plant must outlive the controller.
std::unique_ptr<Controller> make_controller(const ControllerConfig& config, const Plant& plant,
                                            double sample_time);

}  // namespace ftc::sim
