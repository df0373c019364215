// runtime_example GAINS_FILE [--duration S] [--accel exact|rates|model] [--noise SIGMA]
//                 [--delay N] [--seed S]
// Loads a gains file as flight software would and runs the tuned controller's step() loop in
// closed loop with a plant of its own: the spacecraft's equations integrated here (RK4 over each
// sample, the command held), under the paper's disturbance and faults. Prints the attitude error
// at the end, the ISE over the run and after the first fault, and the control TV. Links
// ftctune::runtime only (Eigen and nlohmann-json underneath).
//
// step(t, X1, X2, a) needs the angular acceleration a = dX2/dt as a measurement. Where it comes
// from is the flight software's choice, and this program tries the usual ones:
//   exact  the true dX2/dt = f(X) + G u + Δ(t), with the actuators' real (faulted) outputs of the
//          command last applied: what `ftctune run` and `simulate` feed the controller;
//   rates  the gyro rates differentiated, (X2_k − X2_{k−1}) / Ts: the mean acceleration over the
//          last sample, half a sample late;
//   model  f(X) + G u_{k−1} from the model alone: it sees neither the disturbance nor the faults.
// --noise adds white Gaussian noise of SIGMA rad/s² to each axis of a (after the choice above),
// --delay hands the controller the acceleration of N samples before.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <random>
#include <string>

#include "ftc/runtime/gains.hpp"
#include "ftc/sim/disturbance.hpp"
#include "ftc/sim/faults.hpp"
#include "ftc/sim/scenario.hpp"
#include "ftc/sim/spacecraft.hpp"

namespace {

using ftc::sim::Vec3;
using ftc::sim::Vec4;
using State = ftc::sim::Vec<6>;

int usage(const char* argv0) {
  std::fprintf(stderr,
               "usage: %s GAINS_FILE [--duration S] [--accel exact|rates|model] [--noise SIGMA] "
               "[--delay N] [--seed S]\n",
               argv0);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return usage(argv[0]);
  double duration = 1.0, noise = 0.0;
  int delay = 0;
  unsigned long long seed = 1;
  std::string accel = "exact";
  for (int i = 2; i < argc; ++i) {
    const std::string opt = argv[i];
    if (i + 1 >= argc) return usage(argv[0]);
    const char* v = argv[++i];
    if (opt == "--duration")
      duration = std::atof(v);
    else if (opt == "--accel")
      accel = v;
    else if (opt == "--noise")
      noise = std::atof(v);
    else if (opt == "--delay")
      delay = std::atoi(v);
    else if (opt == "--seed")
      seed = std::strtoull(v, nullptr, 10);
    else
      return usage(argv[0]);
  }
  if (!(duration > 0) || noise < 0 || delay < 0 ||
      (accel != "exact" && accel != "rates" && accel != "model"))
    return usage(argv[0]);
  try {
    // The file says what it was tuned for: the controller, the sample time and the plant.
    const ftc::runtime::Gains gains = ftc::runtime::read_gains(argv[1]);
    const ftc::sim::Spacecraft plant(ftc::sim::spacecraft_params(gains.plant));
    // Refuses gains tuned for another sample time than the one the loop runs at.
    const auto controller = ftc::runtime::make_controller(gains, plant, gains.sample_time);
    const double Ts = gains.sample_time;

    // The world the flight computer does not see: the paper's disturbance and faults.
    const ftc::sim::Scenario scenario = ftc::sim::Scenario::paper();
    const ftc::sim::Disturbance disturbance(scenario.disturbance);
    const ftc::sim::FaultSet faults(scenario.faults, scenario.saturation);
    State x = Eigen::Map<const State>(scenario.initial_state.data());
    // dX/dt with the command u_d held over the sample.
    const auto deriv = [&](double t, const State& s, const Vec4& u_d) {
      State d;
      d.head<3>() = s.tail<3>();
      d.tail<3>() = plant.f(s) + plant.G(s) * faults.apply<4>(t, u_d) + disturbance.at<3>(t);
      return d;
    };

    std::mt19937_64 rng(seed);
    std::normal_distribution<double> gauss(0.0, 1.0);
    std::deque<Vec3> sensed;  // the last delay + 1 accelerations, newest at the back
    Vec4 u_prev = Vec4::Zero();
    Vec3 X2_prev = x.tail<3>();
    double ise = 0.0, ise_after = 0.0, tv = 0.0;  // after the first fault; Σ‖u_k − u_{k−1}‖
    double first_fault = duration;
    for (const ftc::sim::Fault& f : scenario.faults) first_fault = std::min(first_fault, f.onset);
    const auto samples = static_cast<long long>(std::llround(duration / Ts));
    controller->reset();
    for (long long k = 0; k < samples; ++k) {
      const double t = static_cast<double>(k) * Ts;
      const Vec3 X1 = x.head<3>(), X2 = x.tail<3>();
      // The acceleration measurement, as the flight software forms it.
      Vec3 a;
      if (accel == "exact")
        a = deriv(t, x, u_prev).tail<3>();
      else if (accel == "rates")
        a = k == 0 ? Vec3(deriv(t, x, u_prev).tail<3>()) : Vec3((X2 - X2_prev) / Ts);
      else
        a = plant.f(x) + plant.G(x) * u_prev;
      if (noise > 0)
        for (int i = 0; i < 3; ++i) a[i] += noise * gauss(rng);
      sensed.push_back(a);
      if (static_cast<int>(sensed.size()) > delay + 1) sensed.pop_front();

      const Vec4 u = controller->step(t, X1, X2, sensed.front());
      ise += Ts * X1.squaredNorm();
      if (t >= first_fault) ise_after += Ts * X1.squaredNorm();
      if (k > 0) tv += (u - u_prev).norm();

      // The plant over one sample: RK4 with the command held.
      const State k1 = deriv(t, x, u), k2 = deriv(t + Ts / 2, x + Ts / 2 * k1, u),
                  k3 = deriv(t + Ts / 2, x + Ts / 2 * k2, u), k4 = deriv(t + Ts, x + Ts * k3, u);
      x += Ts / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
      X2_prev = X2;
      u_prev = u;
      if (!x.allFinite() || x.head<3>().cwiseAbs().maxCoeff() > 1e3) {
        std::printf("diverged at t = %.3f s\n", t + Ts);
        return 3;
      }
    }

    const Vec3 X1 = x.head<3>();
    std::printf("%s from job %s, Ts = %g s: after %.1f s the attitude error is %.6g rad\n",
                ftc::sim::to_string(gains.controller.type), gains.job_name.c_str(),
                gains.sample_time, duration, X1.norm());
    std::printf(
        "ISE over [0, %g) s = %.6g rad^2 s, over [%g, %g) s = %.6g; control TV %.6g "
        "(acceleration: %s, noise %g rad/s^2, delay %d sample%s)\n",
        duration, ise, first_fault, duration, ise_after, tv, accel.c_str(), noise, delay,
        delay == 1 ? "" : "s");
    return 0;
  } catch (const ftc::InputError& e) {
    std::fprintf(stderr, "runtime_example: %s\n", e.what());
    return 2;
  }
}
