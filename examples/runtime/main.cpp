// runtime_example GAINS_FILE [--scenario FILE [--index I]] [--duration S]
//                 [--accel ideal|differentiated|model] [--tau S]
//                 [--noise SIGMA] [--angle-noise SIGMA] [--delay N] [--seed S]
// Loads a gains file as flight software would and runs the tuned controller's step() loop in
// closed loop with a plant of its own: the spacecraft's equations integrated here (RK4, the
// command held over each sample), under a scenario's disturbance and faults, read through its
// sensors. Prints the attitude error at the end, the ISE over the run, after the first fault and
// over the gains file's objective window (beside the value the file records), and the control
// TV. Links ftctune::runtime only (Eigen and nlohmann-json underneath).
//
// The world: the paper's scenario, the first 1 s of it by default, or the scenario of FILE (a
// scenario's JSON, what `ftctune ensemble` and `evaluate` write, or a job or scenarios file whose
// `scenarios` list holds it at index I, default 0; then the whole scenario by default). Its
// `sensors` block (docs/model.md "Sensors in the loop") is the sensor hardware: noise, bias,
// quantisation and delay of the attitude and rates the controller reads, drawn from the
// scenario's noise stream as the tuner drew it (ftc::sim::SensorReadout). The options change it:
//   --noise SIGMA        the rate gyro's white noise σ_r, rad/s (1σ)
//   --angle-noise SIGMA  the attitude's white noise σ_a, rad (1σ)
//   --delay N            the measurements reach the controller N samples late
//   --seed S             the noise stream's seed
//
// step(t, X1, X2, a) also needs the angular acceleration a = dX2/dt. Where it comes from is the
// flight software's part, as the gains file says it was tuned (its `acceleration`, default
// ideal), or as --accel says:
//   ideal           the true dX2/dt = f(X) + G u + Δ(t), with the actuators' real (faulted)
//                   outputs of the command last applied: a perfect angular accelerometer, what
//                   the tuner feeds the controller without sensors;
//   differentiated  the rates the controller reads differentiated, (X2m_k − X2m_{k−1}) / Ts,
//                   through a first-order low-pass of time constant --tau (default the gains
//                   file's, else 0): ftc::runtime::AccelerationEstimator, the tuner's own
//                   arithmetic;
//   model           f(Xm) + G u_{k−1} from the model alone: it sees neither the disturbance nor
//                   the faults.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "ftc/runtime/acceleration.hpp"
#include "ftc/runtime/gains.hpp"
#include "ftc/runtime/json_reader.hpp"
#include "ftc/runtime/scenario_json.hpp"
#include "ftc/sim/disturbance.hpp"
#include "ftc/sim/faults.hpp"
#include "ftc/sim/scenario.hpp"
#include "ftc/sim/sensors.hpp"
#include "ftc/sim/spacecraft.hpp"

namespace {

using ftc::sim::Vec3;
using ftc::sim::Vec4;
using State = ftc::sim::Vec<6>;
using nlohmann::json;

int usage(const char* argv0) {
  std::fprintf(stderr,
               "usage: %s GAINS_FILE [--scenario FILE [--index I]] [--duration S] "
               "[--accel ideal|differentiated|model] [--tau S] [--noise SIGMA] "
               "[--angle-noise SIGMA] [--delay N] [--seed S]\n",
               argv0);
  return 2;
}

// A JSON file read as the tool reads its inputs (ftc/runtime/json_reader.hpp: strict, with the
// same messages).
json read_json(const std::string& file) {
  const std::optional<std::string> text = ftc::json_io::read_file(file);
  if (!text) throw ftc::InputError(file, "", "cannot be read");
  return ftc::json_io::parse_json_text(*text, file);
}

// The scenario of FILE: the file's own, or entry `index` of its `scenarios` list (a job or a
// scenarios file), whose noise stream is then its index there, as in the tuner.
ftc::sim::Scenario read_scenario(const std::string& file, std::size_t index) {
  json j = read_json(file);
  if (j.contains("scenarios")) {
    if (!j["scenarios"].is_array())
      throw ftc::InputError(file, "/scenarios",
                            "is not a list (a job whose scenarios are in a file of their own: "
                            "give that file)");
    if (index >= j["scenarios"].size())
      throw ftc::InputError(file, "/scenarios",
                            "has " + std::to_string(j["scenarios"].size()) +
                                " scenarios, no index " + std::to_string(index));
    json s = j["scenarios"][index];
    // A scenarios file (`ftctune ensemble`) says whether each member is recoverable: not a
    // scenario's key.
    if (s.is_object()) s.erase("recoverable");
    if (s.is_object() && s.contains("sensors") && s["sensors"].is_object() &&
        !s["sensors"].contains("stream"))
      s["sensors"]["stream"] = index;
    return ftc::runtime::scenario_from_json(s, file + " scenario " + std::to_string(index));
  }
  return ftc::runtime::scenario_from_json(j, file);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return usage(argv[0]);
  std::optional<double> duration, tau, noise, angle_noise;
  std::optional<int> delay;
  std::optional<unsigned long long> seed;
  std::optional<std::string> accel, scenario_file;
  std::size_t index = 0;
  for (int i = 2; i < argc; ++i) {
    const std::string opt = argv[i];
    if (i + 1 >= argc) return usage(argv[0]);
    const char* v = argv[++i];
    char* end = nullptr;
    const double number = std::strtod(v, &end);
    const bool numeric = end != v && *end == '\0' && std::isfinite(number);
    // Seeds and indices as whole numbers of up to 64 bits, exactly (a double would round them).
    errno = 0;
    const unsigned long long whole = std::strtoull(v, &end, 10);
    const bool integral = *v >= '0' && *v <= '9' && end != v && *end == '\0' && errno == 0;
    if (opt == "--accel")
      accel = v;
    else if (opt == "--scenario")
      scenario_file = v;
    else if (!numeric)
      return usage(argv[0]);
    else if (opt == "--duration" && number > 0)
      duration = number;
    else if (opt == "--tau" && number >= 0)
      tau = number;
    else if (opt == "--noise" && number >= 0)
      noise = number;
    else if (opt == "--angle-noise" && number >= 0)
      angle_noise = number;
    else if (opt == "--delay" && number >= 0 && number <= ftc::sim::SensorModel::kMaxDelay &&
             number == std::floor(number))
      delay = static_cast<int>(number);
    else if (opt == "--seed" && integral)
      seed = whole;
    else if (opt == "--index" && integral)
      index = static_cast<std::size_t>(whole);
    else
      return usage(argv[0]);
  }
  if ((accel && *accel != "ideal" && *accel != "differentiated" && *accel != "model") ||
      (index > 0 && !scenario_file))
    return usage(argv[0]);
  try {
    // The file says what it was tuned for: the controller, the sample time, the plant and the
    // acceleration path.
    const ftc::runtime::Gains gains = ftc::runtime::read_gains(argv[1]);
    const ftc::sim::Spacecraft plant(ftc::sim::spacecraft_params(gains.plant));
    // Refuses gains tuned for another sample time than the one the loop runs at.
    const auto controller = ftc::runtime::make_controller(gains, plant, gains.sample_time);
    const double Ts = gains.sample_time;

    // The world the flight computer does not see: the scenario's disturbance and faults, and
    // its sensors as the options change them.
    ftc::sim::Scenario scenario = ftc::sim::Scenario::paper();
    if (scenario_file) scenario = read_scenario(*scenario_file, index);
    // Checked against the spacecraft (3 axes, 4 actuators) and the gains' sample time, whose
    // bias walk per sample the tuner drew with.
    if (const auto errors = scenario.validate("", 3, 4); !errors.empty())
      throw ftc::InputError(scenario_file.value_or("scenario"), errors);
    if (std::abs(scenario.sample_time - Ts) > 1e-12 * Ts)
      throw ftc::InputError(
          scenario_file.value_or("scenario"), "/sample_time",
          "is " + ftc::json_io::number_text(scenario.sample_time) +
              " s, but the gains were tuned for Ts = " + ftc::json_io::number_text(Ts) + " s");
    if (scenario.actuator || !scenario.true_values.empty())
      throw ftc::InputError("scenario", "",
                            "has actuator dynamics or true plant values, which this example's "
                            "plant does not model (`ftctune simulate` does)");
    if (noise || angle_noise || delay || seed) {
      ftc::sim::SensorModel& m = scenario.sensors ? *scenario.sensors : scenario.sensors.emplace();
      if (noise) m.rate.noise = *noise;
      if (angle_noise) m.angle.noise = *angle_noise;
      if (delay) m.delay = *delay;
      if (seed) m.seed = *seed;
      m.resolve(1, m.stream.value_or(index));
    }
    const double run = duration.value_or(scenario_file ? scenario.duration : 1.0);
    ftc::sim::AccelerationSensor path = ftc::runtime::acceleration_path(gains);
    if (accel == "ideal") path.source = ftc::sim::AccelerationSource::ideal;
    if (accel == "differentiated") path.source = ftc::sim::AccelerationSource::differentiated;
    if (tau) path.time_constant = *tau;
    const std::string source = accel ? *accel
                               : path.source == ftc::sim::AccelerationSource::differentiated
                                   ? "differentiated"
                                   : "ideal";

    const ftc::sim::Disturbance disturbance(scenario.disturbance);
    const ftc::sim::FaultSet faults(scenario.faults, scenario.saturation);
    State x = scenario.initial_state.empty()
                  ? State(Eigen::Map<const State>(ftc::sim::Scenario::paper().initial_state.data()))
                  : State(Eigen::Map<const State>(scenario.initial_state.data()));
    // dX/dt with the command u_d held over the sample.
    const auto deriv = [&](double t, const State& s, const Vec4& u_d) {
      State d;
      d.head<3>() = s.tail<3>();
      d.tail<3>() = plant.f(s) + plant.G(s) * faults.apply<4>(t, u_d) + disturbance.at<3>(t);
      return d;
    };

    // The sensor hardware (exact without a block) and the flight software's estimator; the
    // block names the acceleration this loop reads.
    if (scenario.sensors && source != "model") scenario.sensors->acceleration = path;
    std::optional<ftc::sim::SensorReadout> sensors;
    if (scenario.sensors) sensors.emplace(*scenario.sensors, 3, Ts);
    std::optional<ftc::runtime::AccelerationEstimator> estimator;
    if (source == "differentiated") estimator.emplace(path, Ts, 3);

    // The gains file's objective, to replay: its window (from the first fault when its
    // window_from says so, cut at the run's end) when its metric is the ISE and its value is
    // taken over listed scenarios only (an ensemble's members are not this one scenario).
    const json file = read_json(argv[1]);
    const json objective = file.value("objective", json::object());
    const auto number_at = [](const json& j, const char* key) {
      return j.is_object() && j.contains(key) && j[key].is_number() ? j[key].get<double>()
                                                                    : std::nan("");
    };
    const json window = objective.value("window", json::array());
    const bool replayable = objective.value("metric", json()) == "ise" &&
                            !objective.contains("scenarios") && window.is_array() &&
                            window.size() == 2 && window[0].is_number() &&
                            std::isfinite(number_at(objective, "value"));
    double w0 = replayable ? window[0].get<double>() : 0.0;
    double w1 = replayable && window[1].is_number() ? window[1].get<double>() : run;
    if (objective.value("window_from", json()) == "first_fault" && !scenario.faults.empty()) {
      double first = scenario.faults.front().onset;
      for (const ftc::sim::Fault& f : scenario.faults) first = std::min(first, f.onset);
      w0 += first;
      w1 += first;
    }
    // A run shorter than the window measures another objective: no replay then.
    const bool whole_window = w1 <= run + Ts / 2;

    Vec4 u_prev = Vec4::Zero();
    double ise = 0.0, ise_after = 0.0, ise_window = 0.0, tv = 0.0;  // tv = Σ‖u_k − u_{k−1}‖
    double first_fault = run;
    for (const ftc::sim::Fault& f : scenario.faults) first_fault = std::min(first_fault, f.onset);
    const auto samples = static_cast<long long>(std::llround(run / Ts));
    const int substeps = std::max(1, scenario.substeps);
    const double h = Ts / substeps;
    controller->reset();
    for (long long k = 0; k < samples; ++k) {
      const double t = static_cast<double>(k) * Ts;
      const Vec3 X1 = x.head<3>(), X2 = x.tail<3>();
      // What the controller reads.
      Vec3 X1m = X1, X2m = X2;
      if (sensors) sensors->measure(X1.data(), X2.data(), X1m.data(), X2m.data());
      State xm;
      xm << X1m, X2m;
      Vec3 a;
      if (source == "ideal")
        a = deriv(t, x, u_prev).tail<3>();
      else if (source == "differentiated")
        a = estimator->update<3>(X2m);
      else
        a = plant.f(xm) + plant.G(xm) * u_prev;

      const Vec4 u = controller->step(t, X1m, X2m, a);
      ise += Ts * X1.squaredNorm();
      if (t >= first_fault) ise_after += Ts * X1.squaredNorm();
      if (replayable && t >= w0 && t < w1) ise_window += Ts * X1.squaredNorm();
      if (k > 0) tv += (u - u_prev).norm();

      // The plant over one sample: RK4 with the command held.
      for (int j = 0; j < substeps; ++j) {
        const double s = t + j * h;
        const State k1 = deriv(s, x, u), k2 = deriv(s + h / 2, x + h / 2 * k1, u),
                    k3 = deriv(s + h / 2, x + h / 2 * k2, u), k4 = deriv(s + h, x + h * k3, u);
        x += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
      }
      u_prev = u;
      if (!x.allFinite() || x.head<3>().cwiseAbs().maxCoeff() > 1e3) {
        std::printf("diverged at t = %.3f s\n", t + Ts);
        return 3;
      }
    }

    const Vec3 X1 = x.head<3>();
    std::printf("%s from job %s, Ts = %g s: after %.1f s the attitude error is %.6g rad\n",
                ftc::sim::to_string(gains.controller.type), gains.job_name.c_str(),
                gains.sample_time, run, X1.norm());
    std::string accel_text = source;
    if (source == "differentiated")
      accel_text += " (tau " + ftc::json_io::number_text(path.time_constant) + " s)";
    // The sensors as this loop read them (a model-only acceleration reads none of theirs).
    std::string sensors_text = scenario.sensors ? scenario.sensors->summary() : "exact";
    if (const auto at = sensors_text.find(", acceleration ");
        source == "model" && at != std::string::npos)
      sensors_text.erase(at, sensors_text.find(", noise seed", at) - at);
    std::printf(
        "ISE over [0, %g) s = %.6g rad^2 s, over [%g, %g) s = %.6g; control TV %.6g "
        "(acceleration: %s; sensors: %s)\n",
        run, ise, first_fault, run, ise_after, tv, accel_text.c_str(), sensors_text.c_str());
    if (replayable && whole_window && w1 > w0) {
      const double recorded = number_at(objective, "value");
      const json floor = file.value("noise_floor", json::object());
      const json how = objective.value("aggregate", json("mean"));
      const std::string aggregate = how.is_string() ? how.get<std::string>() : "aggregated";
      std::printf(
          "ISE over [%g, %g) s = %.6g; the gains file records %.6g for its job (%s over its "
          "listed scenarios: one scenario's job replays it), %+.3g %% from it, noise floor "
          "%.3g %%",
          w0, w1, ise_window, recorded, aggregate.c_str(), 100 * (ise_window - recorded) / recorded,
          100 * number_at(floor, "relative_spread"));
      // With sensors the floor has two parts; the rounding part is what a replay of the same
      // noise can differ by.
      if (floor.contains("rounding_spread"))
        std::printf(" (rounding alone %.3g %%)", 100 * number_at(floor, "rounding_spread"));
      std::printf("\n");
    }
    return 0;
  } catch (const ftc::InputError& e) {
    std::fprintf(stderr, "runtime_example: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {  // a gains file's field of an unexpected kind
    std::fprintf(stderr, "runtime_example: %s\n", e.what());
    return 2;
  }
}
