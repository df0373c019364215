#pragma once
// An open-loop "controller" that issues a constant command, and converters from the flat result
// vectors to the spacecraft's Eigen types: for tests of the integrator and the simulation loop.
#include <span>
#include <vector>

#include "ftc/sim/controller.hpp"
#include "ftc/sim/types.hpp"

namespace ftc::testing {

using namespace ftc::sim;

inline State state_of(const std::vector<double>& v) { return Eigen::Map<const State>(v.data()); }
inline Vec4 input_of(std::span<const double> v) { return Eigen::Map<const Vec4>(v.data()); }

// Open loop: a constant command, so the closed loop is a smooth ODE and RK4's order shows.
class ConstantCommand final : public Controller<3, 4> {
 public:
  explicit ConstantCommand(const Vec4& u) : u_(u) {}
  void reset() override {}
  Vec4 step(const Measurement<3>&) override { return u_; }
  using Controller<3, 4>::step;
  const ControllerConfig& config() const override { return config_; }
  double sample_time() const override { return 0.05; }

 private:
  Vec4 u_;
  ControllerConfig config_;
};

}  // namespace ftc::testing
