// runtime_example GAINS_FILE: loads a gains file as flight software would and runs the tuned
// controller in the closed loop for the first second of the paper's scenario, then prints the
// attitude error. Links ftctune::runtime only (Eigen and nlohmann-json underneath).
#include <cstdio>

#include "ftc/runtime/gains.hpp"
#include "ftc/sim/scenario.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/sim/spacecraft.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s GAINS_FILE\n", argv[0]);
    return 2;
  }
  try {
    // The file says what it was tuned for: the controller, the sample time and the plant.
    const ftc::runtime::Gains gains = ftc::runtime::read_gains(argv[1]);
    const ftc::sim::Spacecraft plant(ftc::sim::spacecraft_params(gains.plant));
    // Refuses gains tuned for another sample time than the one the loop runs at.
    const auto controller = ftc::runtime::make_controller(gains, plant, gains.sample_time);

    // Every Ts the flight computer measures X1 (rad), X2 (rad/s) and a = dX2/dt (rad/s²) and
    // applies controller->step(t, X1, X2, a); here the simulator plays the spacecraft.
    ftc::sim::Scenario scenario = ftc::sim::Scenario::paper();
    scenario.duration = 1.0;
    scenario.sample_time = gains.sample_time;
    const ftc::sim::SimulationResult r = ftc::sim::simulate(plant, *controller, scenario);

    const ftc::sim::Vec3 X1(r.final_state[0], r.final_state[1], r.final_state[2]);
    std::printf("%s from job %s, Ts = %g s: after %.1f s the attitude error is %.6g rad\n",
                ftc::sim::to_string(gains.controller.type), gains.job_name.c_str(),
                gains.sample_time, scenario.duration, X1.norm());
    return 0;
  } catch (const ftc::InputError& e) {
    std::fprintf(stderr, "runtime_example: %s\n", e.what());
    return 2;
  }
}
