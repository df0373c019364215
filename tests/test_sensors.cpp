// Sensors in the loop (ftc/sim/sensors.hpp, SPEC §18): the noise stream, the quantiser, the
// delay, the differentiated acceleration and its low-pass, what the controller reads against the
// true state, exact sensors as no sensors, lanes against one lane on every instruction set, the
// job's fields and the streams of listed scenarios and ensemble members, and the noise floor's
// sensor seeds.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ftc/runtime/acceleration.hpp"
#include "ftc/runtime/gains.hpp"
#include "ftc/runtime/scenario_json.hpp"
#include "ftc/sim/elementary.hpp"
#include "ftc/sim/isa.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/rigid_body.hpp"
#include "ftc/sim/sensors.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/sim/spacecraft.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/job/ensemble.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/problem/problem.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "same_bits.hpp"
#include "short_job.hpp"

using namespace ftc::sim;
using nlohmann::json;

namespace {

using ftc::testing::same_bits;

// SPEC §12's SplitMix64 written out, apart from the library's.
struct SpecStream {
  std::uint64_t s;
  static std::uint64_t mix(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  double uniform() {
    s += 0x9E3779B97F4A7C15ULL;
    return static_cast<double>(mix(s) >> 11) / 9007199254740992.0;
  }
};

// A controller that commands nothing and keeps what it is given: the trajectory is then the same
// whatever it reads, and what it read can be set against the true state sample by sample.
class Recorder final : public Controller<3, 4> {
 public:
  void reset() override { seen.clear(); }
  Input step(const Measurement<3>& m) override {
    seen.push_back({m.X1, m.X2, m.a});
    return Input::Zero();
  }
  const ControllerConfig& config() const override { return config_; }
  double sample_time() const override { return 1e-3; }

  struct Seen {
    Vec<3> X1, X2, a;
  };
  std::vector<Seen> seen;

 private:
  ControllerConfig config_ = ControllerConfig::table1(ControllerType::pi_fosmc);
};

Scenario two_seconds() {
  Scenario s = Scenario::paper();
  s.duration = 2.0;
  s.faults[0].onset = 0.5;
  s.faults[1].onset = 1.0;
  return s;
}

// The recorder's run: what it read, and the true state at every sample (trajectory rows t, X1,
// X2, u_d, u).
struct Recorded {
  std::vector<Recorder::Seen> seen;
  std::vector<std::array<double, 6>> x;
};
Recorded record(const Scenario& s) {
  Spacecraft plant;
  Recorder c;
  SimulationOptions o;
  o.record_every = 1;
  const SimulationResult r = simulate(plant, c, s, o);
  Recorded out;
  out.seen = c.seen;
  const std::size_t w = r.trajectory.width();
  for (std::size_t row = 0; row * w < r.trajectory.values.size(); ++row) {
    std::array<double, 6> x;
    for (int i = 0; i < 6; ++i) x[i] = r.trajectory.values[row * w + 1 + i];
    out.x.push_back(x);
  }
  return out;
}

// Every "path: message" of an input error, one a line.
std::string every_error(const ftc::InputError& e) {
  std::string all;
  for (const ftc::FieldError& f : e.errors()) all += f.path + ": " + f.message + "\n";
  return all;
}

SensorModel resolved(SensorModel m, std::uint64_t seed = 1, std::uint64_t index = 0) {
  m.stream_seed = seed;
  m.stream_index = index;
  return m;
}

}  // namespace

TEST(Sensors, StreamIsSplitMixThenBoxMullerInContinuousPairs) {
  SensorModel m = resolved({}, 7, 2);
  SensorNoise noise(m, 3, 1e-3);
  SpecStream spec{SpecStream::mix(7 ^ SpecStream::mix(0x53454E53 + 2 + 1))};
  for (int pair = 0; pair < 50; ++pair) {
    const double u1 = spec.uniform(), u2 = spec.uniform();
    const double r = std::sqrt(-2.0 * math::log(1.0 - u1));
    const double angle = 6.283185307179586 * u2;
    EXPECT_TRUE(same_bits(noise.normal(), r * math::cos(angle))) << "pair " << pair;
    EXPECT_TRUE(same_bits(noise.normal(), r * math::sin(angle))) << "pair " << pair;
    // ftctune's log and sincos are libm's to within an ulp or two.
    EXPECT_NEAR(r * math::cos(angle), r * std::cos(angle), 1e-15 * (1 + r));
  }
  // The first normals of seed 1, scenario 0, as any implementation of §18 draws them.
  SensorNoise first(resolved({}), 3, 1e-3);
  SpecStream s0{SpecStream::mix(1 ^ SpecStream::mix(0x53454E53 + 1))};
  const double u1 = s0.uniform(), u2 = s0.uniform();
  EXPECT_NEAR(first.normal(), std::sqrt(-2.0 * std::log(1.0 - u1)) * std::cos(2 * M_PI * u2),
              1e-14);
}

TEST(Sensors, EachSampleDrawsAngleThenRateThenWalkNoiseOnEveryAxis) {
  SensorModel m;
  m.angle.noise = 1e-3;
  m.rate.noise = 2e-3;
  m.rate.bias = {0.01, -0.02, 0.03};
  m.rate.bias_walk = 0.5;
  const double Ts = 4e-3;
  SensorNoise noise(resolved(m), 3, Ts);
  SensorNoise z(resolved({}), 3, Ts);  // the same stream: its normals
  double bias[3] = {0.01, -0.02, 0.03};
  for (int k = 0; k < 20; ++k) {
    double angle[3], b[3], rate[3], want_z[9];
    noise.next(angle, b, rate);
    for (double& v : want_z) v = z.normal();  // consumed even where σ is 0
    for (int i = 0; i < 3; ++i) {
      EXPECT_TRUE(same_bits(angle[i], 1e-3 * want_z[i])) << k << " " << i;
      EXPECT_TRUE(same_bits(b[i], bias[i])) << k << " " << i;
      EXPECT_TRUE(same_bits(rate[i], 2e-3 * want_z[3 + i])) << k << " " << i;
      bias[i] = bias[i] + (0.5 * std::sqrt(Ts)) * want_z[6 + i];
    }
  }
  // σ = 0 still draws: a model without noise consumes the stream as one with it.
  SensorNoise quiet(resolved({}), 3, Ts), loud(resolved(m), 3, Ts);
  double a[3], b[3], r[3];
  quiet.next(a, b, r);
  loud.next(a, b, r);
  EXPECT_TRUE(same_bits(quiet.normal(), loud.normal()));
}

TEST(Sensors, ControllerReadsTheQuantisedNoisyStateAndTheMetricsTheTrueOne) {
  Scenario s = two_seconds();
  SensorModel m;
  m.angle.noise = 2e-4;
  m.rate.noise = 1e-3;
  m.rate.bias = {0.05};
  s.sensors = resolved(m, 3, 0);
  const Recorded got = record(s);
  Scenario exact = s;
  exact.sensors.reset();
  const Recorded truth = record(exact);
  ASSERT_EQ(got.seen.size(), 2000u);
  ASSERT_EQ(got.x.size(), 2000u);
  // The true trajectory does not depend on what a controller that commands nothing reads.
  for (std::size_t k = 0; k < got.x.size(); ++k)
    for (int i = 0; i < 6; ++i) ASSERT_TRUE(same_bits(got.x[k][i], truth.x[k][i]));
  SensorNoise noise(*s.sensors, 3, s.sample_time);
  for (std::size_t k = 0; k < got.seen.size(); ++k) {
    double angle[3], bias[3], rate[3];
    noise.next(angle, bias, rate);
    for (int i = 0; i < 3; ++i) {
      EXPECT_TRUE(same_bits(got.seen[k].X1[i], got.x[k][i] + angle[i])) << k;
      // §18's order: (X2 + b) + σ_r z.
      EXPECT_TRUE(same_bits(got.seen[k].X2[i], (got.x[k][3 + i] + bias[i]) + rate[i])) << k;
      // The ideal acceleration is the exact one.
      EXPECT_TRUE(same_bits(got.seen[k].a[i], truth.seen[k].a[i])) << k;
    }
  }

  // Quantised, without noise: Q · round(x / Q), ties away from zero.
  SensorModel q;
  q.angle.quantization = 0.01;
  q.rate.quantization = 0.002;
  s.sensors = resolved(q);
  const Recorded quantised = record(s);
  for (std::size_t k = 0; k < quantised.seen.size(); ++k)
    for (int i = 0; i < 3; ++i) {
      EXPECT_TRUE(same_bits(quantised.seen[k].X1[i], 0.01 * std::round(truth.x[k][i] / 0.01)));
      EXPECT_TRUE(
          same_bits(quantised.seen[k].X2[i], 0.002 * std::round(truth.x[k][3 + i] / 0.002)));
    }
  // Ties go away from zero (the rounding instruction's default, ties to even, would give -0.5
  // and 0.5): X1(0) = (-0.625, 0.625, ·) on a step of 0.25 is ∓2.5 steps.
  s.initial_state[0] = -0.625;
  s.initial_state[1] = 0.625;
  q.angle.quantization = 0.25;
  s.sensors = resolved(q);
  const Recorded ties = record(s);
  EXPECT_EQ(ties.seen[0].X1[0], -0.75);
  EXPECT_EQ(ties.seen[0].X1[1], 0.75);
}

TEST(Sensors, DelayedMeasurementsReachTheControllerDSamplesLater) {
  Scenario s = two_seconds();
  SensorModel m;
  m.delay = 7;
  m.acceleration.source = AccelerationSource::differentiated;
  s.sensors = resolved(m);
  const Recorded got = record(s);
  Scenario exact = s;
  exact.sensors.reset();
  const Recorded truth = record(exact);
  for (std::size_t k = 0; k < got.seen.size(); ++k) {
    const std::size_t from = k < 7 ? 0 : k - 7;
    for (int i = 0; i < 3; ++i) {
      ASSERT_TRUE(same_bits(got.seen[k].X1[i], truth.x[from][i])) << k;
      ASSERT_TRUE(same_bits(got.seen[k].X2[i], truth.x[from][3 + i])) << k;
    }
  }
  // The differentiated acceleration is delayed as the rest: d_j = (X2_j − X2_{j−1}) / Ts of
  // sample j = k − 7 (d_0 = 0), through the low-pass of gain Ts / (0 + Ts) = 1, as §18 writes it.
  std::vector<std::array<double, 3>> y(got.seen.size());
  for (std::size_t j = 0; j < y.size(); ++j)
    for (int i = 0; i < 3; ++i) {
      const double d = j == 0 ? 0.0 : (truth.x[j][3 + i] - truth.x[j - 1][3 + i]) / s.sample_time;
      const double before = j == 0 ? 0.0 : y[j - 1][i];
      y[j][i] = before + 1.0 * (d - before);
      EXPECT_NEAR(y[j][i], d, 1e-12 * (1 + std::abs(d)));  // which is d to rounding
    }
  for (std::size_t k = 0; k < got.seen.size(); ++k)
    for (int i = 0; i < 3; ++i)
      ASSERT_TRUE(same_bits(got.seen[k].a[i], y[k < 7 ? 0 : k - 7][i])) << k;
  // An ideal acceleration is not delayed.
  s.sensors->acceleration.source = AccelerationSource::ideal;
  const Recorded ideal = record(s);
  for (std::size_t k = 0; k < ideal.seen.size(); ++k)
    for (int i = 0; i < 3; ++i) ASSERT_TRUE(same_bits(ideal.seen[k].a[i], truth.seen[k].a[i]));
}

TEST(Sensors, DifferentiatedAccelerationPassesAFirstOrderLowPass) {
  Scenario s = two_seconds();
  SensorModel m;
  m.rate.noise = 1e-4;
  m.acceleration = {AccelerationSource::differentiated, 0.02};
  s.sensors = resolved(m);
  const Recorded got = record(s);
  const double Ts = s.sample_time, c = Ts / (0.02 + Ts);
  double y[3] = {0, 0, 0};
  for (std::size_t k = 0; k < got.seen.size(); ++k)
    for (int i = 0; i < 3; ++i) {
      const double d = k == 0 ? 0.0 : (got.seen[k].X2[i] - got.seen[k - 1].X2[i]) / Ts;
      y[i] = y[i] + c * (d - y[i]);
      ASSERT_TRUE(same_bits(got.seen[k].a[i], y[i])) << k;
    }
  // The filter lags: the filtered acceleration is smoother than the raw difference, whose
  // noise is σ √2 / Ts ≈ 0.14 rad/s².
  double raw = 0, filtered = 0;
  for (std::size_t k = 1; k < got.seen.size(); ++k) {
    const double d = (got.seen[k].X2[0] - got.seen[k - 1].X2[0]) / Ts;
    raw += std::abs(d - got.seen[k].a[0]);
    filtered += std::abs(got.seen[k].a[0] - got.seen[k - 1].a[0]);
  }
  EXPECT_LT(filtered, 0.2 * raw);
}

// Flight software's side: the sensors read sample by sample (SensorReadout, what the runtime
// example's plant uses) and the runtime's AccelerationEstimator fed the rates the controller
// reads give what the tuner's loop gave the controller, bit for bit, delay included.
TEST(Sensors, RuntimeReadoutAndEstimatorReplayWhatTheLoopGaveTheController) {
  Scenario s = two_seconds();
  SensorModel m;
  m.angle = {2e-4, 1e-5};
  m.rate.noise = 1e-3;
  m.rate.bias = {2e-3, -1e-3, 0.0};
  m.rate.bias_walk = 1e-4;
  m.rate.quantization = 1e-5;
  m.delay = 3;
  m.acceleration = {AccelerationSource::differentiated, 0.005};
  s.sensors = resolved(m, 9, 2);
  const Recorded got = record(s);  // the recorder commands nothing: got.x is the true state
  SensorReadout readout(*s.sensors, 3, s.sample_time);
  ftc::runtime::AccelerationEstimator estimate(m.acceleration, s.sample_time, 3);
  ASSERT_EQ(got.seen.size(), got.x.size());
  for (std::size_t k = 0; k < got.seen.size(); ++k) {
    Vec<3> X1m, X2m;
    readout.measure(got.x[k].data(), got.x[k].data() + 3, X1m.data(), X2m.data());
    const Vec<3> a = estimate.update<3>(X2m);
    for (int i = 0; i < 3; ++i) {
      ASSERT_TRUE(same_bits(X1m[i], got.seen[k].X1[i])) << k;
      ASSERT_TRUE(same_bits(X2m[i], got.seen[k].X2[i])) << k;
      ASSERT_TRUE(same_bits(a[i], got.seen[k].a[i])) << k;
    }
  }
  // reset() starts over: the first acceleration is 0 again.
  estimate.reset();
  EXPECT_EQ(estimate.update<3>(Vec<3>(1.0, 2.0, 3.0)), Vec<3>::Zero());
  // An ideal acceleration is measured, not estimated; the refusal says which is.
  try {
    ftc::runtime::AccelerationEstimator ideal(AccelerationSensor{}, 1e-3, 3);
    FAIL() << "accepted";
  } catch (const ftc::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("only \"differentiated\" is estimated"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(quantize(-0.625, 0.25), -0.75);  // -2.5 steps: ties away from zero
  EXPECT_EQ(quantize(0.375, 0.25), 0.5);
  EXPECT_EQ(quantize(0.6, 0.25), 0.5);
  EXPECT_FALSE(std::signbit(quantize(-0.0, 0.25)));  // as the lanes: −0 / Q is not < 0
  EXPECT_TRUE(std::signbit(quantize(-0.1, 0.25)));   // −0.4 steps: −0, as the lanes
  EXPECT_EQ(quantize(0.123, 0.0), 0.123);
}

TEST(Sensors, ExactSensorsAreTheLoopWithoutThemAndNoiseChangesIt) {
  const auto plant = make_plant(PlantSpec{});
  Scenario s = two_seconds();
  const ControllerConfig c = ControllerConfig::table1(ControllerType::pi_fosmc);
  const SimulationResult without = plant->simulate(c, s, {});
  SensorModel zero;
  zero.rate.bias = {0.0, 0.0, 0.0};
  zero.acceleration.time_constant = 0.5;  // unused by the ideal source
  s.sensors = resolved(zero, 99, 4);
  const SimulationResult exact = plant->simulate(c, s, {});
  EXPECT_TRUE(same_bits(exact.metrics.errors.ise, without.metrics.errors.ise));
  EXPECT_TRUE(same_bits(exact.metrics.control_tv, without.metrics.control_tv));
  for (std::size_t i = 0; i < 6; ++i)
    EXPECT_TRUE(same_bits(exact.final_state[i], without.final_state[i]));
  s.sensors->rate.noise = 1e-3;
  const SimulationResult noisy = plant->simulate(c, s, {});
  EXPECT_FALSE(same_bits(noisy.metrics.errors.ise, without.metrics.errors.ise));
  EXPECT_FALSE(same_bits(noisy.metrics.control_tv, without.metrics.control_tv));
}

// Lanes of different scenarios, sensors and gains in one pack, on every instruction set, give
// the bits of each run alone; the spacecraft (constant G) and the rigid body (G⁺ at the measured
// Euler angles), with and without a delay and the differentiated acceleration.
TEST(Sensors, LanesGiveTheScalarBitsOnEveryInstructionSet) {
  for (const char* model : {"spacecraft", "rigid_body"})
    for (int shape = 0; shape < 3; ++shape) {
      PlantSpec spec;
      spec.model = model;
      const auto plant = make_plant(spec);
      std::vector<ControllerConfig> configs;
      std::vector<Scenario> scenarios;
      for (int l = 0; l < 9; ++l) {
        ControllerConfig c = ControllerConfig::table1(ControllerType::pi_fosmc);
        c.Kp = 5.0 + l;
        configs.push_back(c);
        Scenario s = two_seconds();
        if (std::string(model) == "rigid_body") {
          s.initial_state = {0.3, -0.2, 0.1, 0.0, 0.0, 0.0};
          s.faults.clear();
        }
        s.name = "s" + std::to_string(l % 3);
        SensorModel m;
        m.angle.noise = 1e-4 * (1 + l % 3);
        m.rate.noise = 1e-3;
        m.rate.bias_walk = 1e-3;
        m.angle.quantization = l % 2 ? 1e-4 : 0.0;
        m.delay = shape == 0 ? 0 : 3;
        if (shape == 2) m.acceleration = {AccelerationSource::differentiated, 0.01 * (l % 3)};
        s.sensors = resolved(m, 1, static_cast<std::uint64_t>(l % 3));
        scenarios.push_back(s);
      }
      SimulationOptions o;
      std::vector<PackTask> tasks;
      for (int l = 0; l < 9; ++l) tasks.push_back({&configs[l], &scenarios[l], &o});
      std::vector<SimulationResult> want;
      for (int l = 0; l < 9; ++l) want.push_back(plant->simulate(configs[l], scenarios[l], o));
      for (Isa isa : supported_isas()) {
        std::vector<SimulationResult> got(9);
        std::vector<std::string> errors(9);
        plant->simulate_pack(tasks, got, errors, isa);
        for (int l = 0; l < 9; ++l) {
          EXPECT_EQ(errors[l], "");
          const std::string what = std::string(model) + " shape " + std::to_string(shape) +
                                   " on " + to_string(isa) + ", lane " + std::to_string(l);
          EXPECT_TRUE(same_bits(got[l].metrics.errors.ise, want[l].metrics.errors.ise)) << what;
          EXPECT_TRUE(same_bits(got[l].metrics.control_tv, want[l].metrics.control_tv)) << what;
          for (std::size_t i = 0; i < want[l].final_state.size(); ++i)
            EXPECT_TRUE(same_bits(got[l].final_state[i], want[l].final_state[i])) << what;
        }
      }
      EXPECT_TRUE(std::isfinite(want[0].metrics.errors.ise));
    }
}

TEST(Sensors, BadFieldsAreRefusedAtTheirJsonPath) {
  json j = ftc::testing::short_table1_job();
  j["scenarios"][0]["sensors"] = {{"angle", {{"noise", -1}}},
                                  {"rate", {{"bias", {0.1, 0.2}}, {"quantization", -0.5}}},
                                  {"delay", 1001},
                                  {"acceleration", {{"source", "kalman"}}},
                                  {"seed", -3}};
  try {
    ftc::tune::parse_job(j, "job.json");
    FAIL() << "accepted";
  } catch (const ftc::InputError& e) {
    const std::string all = every_error(e);
    for (const char* path :
         {"/scenarios/0/sensors/angle/noise", "/scenarios/0/sensors/rate/bias",
          "/scenarios/0/sensors/rate/quantization", "/scenarios/0/sensors/delay",
          "/scenarios/0/sensors/acceleration/source", "/scenarios/0/sensors/seed"})
      EXPECT_NE(all.find(std::string(path) + ": "), std::string::npos) << path << " in " << all;
    EXPECT_NE(all.find("ideal"), std::string::npos) << all;  // says what is supported
    EXPECT_NE(all.find("one per axis"), std::string::npos) << all;
  }
  json ok = ftc::testing::short_table1_job();
  ok["scenarios"][0]["sensors"] = {
      {"angle", {{"noise", 1e-4}}},
      {"acceleration", {{"source", "differentiated"}, {"time_constant", 0.01}}},
      {"delay", 2}};
  const ftc::tune::Job job = ftc::tune::parse_job(ok, "job.json");
  ASSERT_TRUE(job.scenarios[0].sensors);
  EXPECT_EQ(job.scenarios[0].sensors->delay, 2);
  EXPECT_EQ(job.scenarios[0].sensors->acceleration.time_constant, 0.01);
  // Written and read back the same.
  const json written = ftc::runtime::to_json(job.scenarios[0]);
  EXPECT_EQ(written["sensors"]["acceleration"]["source"], "differentiated");
  EXPECT_EQ(ftc::runtime::to_json(ftc::runtime::scenario_from_json(written, "w")), written);

  // A tuned job's gains file records one acceleration path, so its scenarios agree on it.
  json mixed = ok;
  mixed["scenarios"].push_back(mixed["scenarios"][0]);
  mixed["scenarios"][1]["name"] = "second";
  mixed["scenarios"][1]["sensors"]["acceleration"]["time_constant"] = 0.02;
  try {
    ftc::tune::parse_job(mixed, "job.json");
    FAIL() << "accepted";
  } catch (const ftc::InputError& e) {
    EXPECT_EQ(every_error(e),
              "/scenarios/1/sensors/acceleration: is differentiated (time_constant 0.02 s) but "
              "/scenarios/0/sensors/acceleration is differentiated (time_constant 0.01 s): the "
              "scenarios of a tuned job read one acceleration path, the one its gains file "
              "records for flight software\n");
  }
  mixed["scenarios"][1].erase("sensors");  // a scenario with exact sensors reads no path
  EXPECT_EQ(ftc::tune::parse_job(mixed, "job.json").tuned_acceleration()->time_constant, 0.01);
}

TEST(Sensors, ListedScenariosAndMembersHaveStreamsOfTheirOwn) {
  json j = ftc::testing::short_table1_job();
  json s = j["scenarios"][0];
  s["sensors"] = {{"rate", {{"noise", 1e-3}}}};
  json t = s;
  t["name"] = "second";
  j["scenarios"] = {s, t};
  j["scenarios"].push_back(t);
  j["scenarios"][2]["name"] = "third";
  j["scenarios"][2]["sensors"]["stream"] = 7;
  j["scenarios"][2]["sensors"]["seed"] = 3;
  const ftc::tune::Job job = ftc::tune::parse_job(j, "job.json");
  EXPECT_EQ(job.scenarios[0].sensors->stream_seed, 1u);
  EXPECT_EQ(job.scenarios[0].sensors->stream_index, 0u);
  EXPECT_EQ(job.scenarios[1].sensors->stream_index, 1u);
  EXPECT_EQ(job.scenarios[2].sensors->stream_seed, 3u);  // as given
  EXPECT_EQ(job.scenarios[2].sensors->stream_index, 7u);

  json e = ftc::testing::short_ensemble_job();
  e["scenarios"][0]["sensors"] = {{"rate", {{"noise", 1e-3}}}};
  const ftc::tune::Job ej = ftc::tune::parse_job(e, "job.json");
  const Scenario m3 = ftc::tune::ensemble_member(ej, 4242, 3);
  EXPECT_EQ(m3.sensors->stream_seed, 4242u);  // the ensemble's seed
  EXPECT_EQ(m3.sensors->stream_index, 3u);
  e["scenarios"][0]["sensors"]["seed"] = 17;
  const ftc::tune::Job seeded = ftc::tune::parse_job(e, "job.json");
  EXPECT_EQ(ftc::tune::ensemble_member(seeded, 4242, 3).sensors->stream_seed, 17u);
}

// The noise floor reruns the tuned gains with the sensor seeds seed + 1 ... seed + 8 as well as
// with nudged initial states, and gives each part; the files are the same on 1 and 2 threads.
TEST(Sensors, NoiseFloorAddsOtherSensorSeedsAndRunsAreThreadIndependent) {
  json j = ftc::testing::short_table1_job();
  j["scenarios"][0]["sensors"] = {{"seed", 5},
                                  {"angle", {{"noise", 1e-4}}},
                                  {"rate", {{"noise", 1e-3}, {"bias_walk", 1e-4}}},
                                  {"delay", 1},
                                  {"acceleration", {{"source", "differentiated"}}}};
  const ftc::tune::Job job = ftc::tune::parse_job(j, "job.json");
  ftc::tune::TbbEvaluator one(1), two(2);
  const ftc::tune::TuningOutcome a = ftc::tune::tune(job, one);
  const ftc::tune::TuningOutcome b = ftc::tune::tune(job, two);
  ASSERT_TRUE(a.noise_floor);
  EXPECT_EQ(a.noise_floor->sensor_seeds,
            (std::vector<std::uint64_t>{6, 7, 8, 9, 10, 11, 12, 13}));
  EXPECT_GT(a.noise_floor->sensor_spread, 0.0);
  EXPECT_GE(a.noise_floor->relative_spread,
            std::max(a.noise_floor->sensor_spread, a.noise_floor->rounding_spread));
  const auto files_a = ftc::tune::output_files(a), files_b = ftc::tune::output_files(b);
  EXPECT_EQ(files_a, files_b);
  const json gains = json::parse(files_a.at("gains.json"));
  EXPECT_EQ(gains["noise_floor"]["sensor_seeds"], json({6, 7, 8, 9, 10, 11, 12, 13}));
  // The gains file records the acceleration path the gains were tuned with, and the runtime's
  // loader reads it back; a job without sensors records none.
  EXPECT_EQ(gains["acceleration"], json({{"source", "differentiated"}, {"time_constant", 0.0}}));
  const ftc::runtime::Gains loaded = ftc::runtime::parse_gains(gains, "gains.json");
  ASSERT_TRUE(loaded.acceleration);
  EXPECT_EQ(ftc::runtime::acceleration_path(loaded).source, AccelerationSource::differentiated);
  EXPECT_NE(files_a.at("comparison.md").find("other sensor seeds"), std::string::npos);
  // Different from the run without sensors: the loop did read them.
  json plain = ftc::testing::short_table1_job();
  const ftc::tune::TuningOutcome c = ftc::tune::tune(ftc::tune::parse_job(plain, "job.json"), one);
  EXPECT_TRUE(c.noise_floor->sensor_seeds.empty());
  EXPECT_FALSE(json::parse(ftc::tune::output_files(c).at("gains.json")).contains("acceleration"));
  EXPECT_NE(c.best().outcome.evaluation.objective, a.best().outcome.evaluation.objective);
}

// An ensemble's `sensors` key draws each member's sensors after every other draw (SPEC §12's
// and §17's), in the documented order, and leaves the members' faults as they were.
TEST(Sensors, EnsembleMembersDrawTheirSensorsLast) {
  json e = ftc::testing::short_ensemble_job();
  const ftc::tune::Job plain = ftc::tune::parse_job(e, "job.json");
  e["ensemble"]["sensors"] = {{"angle_noise", {{"uniform", {1e-4, 3e-4}}}},
                              {"rate_bias", {{"uniform", {-0.01, 0.01}}}},
                              {"delay", {0, 4}}};
  const ftc::tune::Job job = ftc::tune::parse_job(e, "job.json");
  for (std::int64_t k = 0; k < 6; ++k) {
    const Scenario with = ftc::tune::ensemble_member(job, 7, k);
    const Scenario without = ftc::tune::ensemble_member(plain, 7, k);
    EXPECT_EQ(ftc::runtime::to_json(with)["faults"], ftc::runtime::to_json(without)["faults"]);
    EXPECT_FALSE(without.sensors);
    ASSERT_TRUE(with.sensors);
    // 3 parameter, 6 initial-state and 1 disturbance draws, the fault count and 2 slots of 11.
    SplitMix64 r = SplitMix64::member(7, static_cast<std::uint64_t>(k));
    r.skip(3 + 6 + 1 + 1 + 2 * 11);
    EXPECT_EQ(with.sensors->angle.noise, 1e-4 + (3e-4 - 1e-4) * r.uniform());
    EXPECT_EQ(with.sensors->rate.noise, 0.0);
    r.skip(1);  // rate_noise: drawn, not given
    ASSERT_EQ(with.sensors->rate.bias.size(), 3u);
    for (int i = 0; i < 3; ++i) EXPECT_EQ(with.sensors->rate.bias[i], -0.01 + 0.02 * r.uniform());
    r.skip(1);  // bias_walk
    EXPECT_EQ(with.sensors->delay, static_cast<int>(std::floor(r.uniform() * 5)));
    EXPECT_EQ(with.sensors->stream_seed, 7u);
    EXPECT_EQ(with.sensors->stream_index, static_cast<std::uint64_t>(k));
    // Written out with its seed and stream: replayed alone, it draws the same noise.
    const json written = ftc::runtime::to_json(with);
    EXPECT_EQ(written["sensors"]["seed"], 7);
    EXPECT_EQ(written["sensors"]["stream"], k);
    const Scenario replayed = ftc::runtime::scenario_from_json(written, "member");
    EXPECT_EQ(replayed.sensors->stream_seed, 7u);
    EXPECT_EQ(replayed.sensors->stream_index, static_cast<std::uint64_t>(k));
  }
  e["ensemble"]["sensors"] = {{"rate_noise", {{"uniform", {-1, 1}}}}, {"delay", {3, 1}}};
  try {
    ftc::tune::parse_job(e, "job.json");
    FAIL() << "accepted";
  } catch (const ftc::InputError& err) {
    const std::string all = every_error(err);
    EXPECT_NE(all.find("/ensemble/sensors/rate_noise: must be >= 0"), std::string::npos) << all;
    EXPECT_NE(all.find("/ensemble/sensors/delay: expected 0 <= lo <= hi"), std::string::npos)
        << all;
  }
}
