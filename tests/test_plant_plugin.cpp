// Plant plugins (ftc/sim/plant_plugin.hpp, docs/plugins.md): the example plugin loaded, described
// and checked; libraries that fail each way refused with a message, never a crash; a job naming a
// plugin found on the search path or refused with where it looked; the CLI's faces of all this.
// (The plugin against the same plant compiled in: test_plant_plugin_compiled_in.cpp; the service
// and MPI ranks: test_service.cpp, test_mpi.cpp.)
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_runner.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/plant_plugin.hpp"
#include "ftc/tune/api/plant_check.hpp"
#include "ftc/tune/job/job.hpp"

namespace {

namespace fs = std::filesystem;
using ftc::testing::fresh_dir;
using ftc::testing::run_cli;

const fs::path kDir = FTC_PLUGIN_DIR;
const fs::path kPendulum = kDir / "ftctune_plant_reaction_wheel_pendulum.so";
const fs::path kJob = fs::path(FTC_SOURCE_DIR) / "examples/plant-plugin/job.json";
const std::string kJobArg = "'" + kJob.string() + "'";
const std::string kPathArg = " --plant-path '" + kDir.string() + "'";

fs::path broken(const std::string& name) {
  return kDir / "broken" / ("ftctune_plant_" + name + ".so");
}

// The message of the InputError `f` throws ("" when it throws none).
template <class F>
std::string input_error(F f) {
  try {
    f();
  } catch (const ftc::InputError& e) {
    return e.what();
  }
  return "";
}

TEST(PlantPlugin, LoadsTheExampleWithTheShapeAndParametersItDeclares) {
  const ftc::sim::PlantPlugin& p = ftc::sim::load_plant_plugin(kPendulum);
  EXPECT_EQ(&ftc::sim::load_plant_plugin(kPendulum), &p);  // loaded once
  EXPECT_EQ(p.name, "reaction_wheel_pendulum");
  const ftc::sim::PlantKind& k = *p.kind;
  EXPECT_EQ(k.model, "plugin:reaction_wheel_pendulum");
  EXPECT_EQ(k.axes, 1);
  EXPECT_EQ(k.actuators, 2);
  ASSERT_EQ(k.parameters.size(), 5u);
  EXPECT_EQ(k.parameters[0].name, "inertia");
  EXPECT_EQ(k.parameters[0].unit, "kg·m²");
  EXPECT_EQ(k.uncertain_names(), "inertia, mass_length");
  EXPECT_EQ(ftc::sim::find_plant_kind("plugin:reaction_wheel_pendulum"), &k);
  // Its plant simulates like any other: θ0 = 0.1 rad balanced by the default PI-FOSMC.
  ftc::sim::Scenario s;
  s.name = "balance";
  s.duration = 2.0;
  s.sample_time = 1e-3;
  s.initial_state = k.default_initial_state;
  const auto plant = ftc::sim::make_plant({k.model, {}});
  const ftc::sim::SimulationResult r = plant->simulate(ftc::sim::ControllerConfig{}, s);
  EXPECT_EQ(r.samples, 2000);
  EXPECT_LT(std::abs(r.final_state[0]), 1e-3);
}

TEST(PlantPlugin, CheckPassesWithLanesEqualToOneLaneOnEveryIsa) {
  const ftc::tune::PlantCheckReport r = ftc::tune::check_plant_plugin(kPendulum);
  EXPECT_TRUE(r.passed());
  std::size_t lane_checks = 0;
  for (const auto& i : r.items) {
    EXPECT_TRUE(i.passed) << i.name << ": " << i.detail;
    lane_checks += i.name.rfind("lanes equal one lane", 0) == 0;
  }
  EXPECT_EQ(lane_checks, ftc::sim::supported_isas().size());
}

TEST(PlantPlugin, LibrariesThatFailAreRefusedWithTheReason) {
  EXPECT_NE(input_error([] { ftc::sim::load_plant_plugin(broken("wrong_abi")); })
                .find("was built for plant ABI 2 (0.0.9-0123456789abcdef), but this ftctune has "
                      "ABI 1 ("),
            std::string::npos);
  EXPECT_NE(input_error([] {
              ftc::sim::load_plant_plugin(broken("no_entry"));
            }).find("has no entry point ftctune_plant_plugin"),
            std::string::npos);
  EXPECT_NE(input_error([] {
              ftc::sim::load_plant_plugin(broken("throws"));
            }).find("its kind() threw: this plant's parameters file is missing"),
            std::string::npos);
  EXPECT_NE(input_error([] { ftc::sim::load_plant_plugin(broken("misnamed")); })
                .find("its plant calls itself 'plugin:someone_else', but its file name makes it "
                      "'plugin:misnamed'"),
            std::string::npos);
  EXPECT_NE(input_error([] {
              ftc::sim::load_plant_plugin(kDir / "nothing_here.so");
            }).find("no such file"),
            std::string::npos);
  // Not a shared library at all.
  const fs::path dir = fresh_dir("plugin-text");
  std::ofstream(dir / "ftctune_plant_text.so") << "not a library\n";
  EXPECT_NE(input_error([&] {
              ftc::sim::load_plant_plugin(dir / "ftctune_plant_text.so");
            }).find("cannot be loaded ("),
            std::string::npos);
}

TEST(PlantPlugin, AJobFindsItOnTheSearchPathOrSaysWhereItLooked) {
  const std::string text = ftc::testing::slurp(kJob);
  std::string other = text;
  other.replace(other.find("reaction_wheel_pendulum"), 23, "no_such_plant");
  ftc::sim::set_plant_search_path({kDir / "broken", kDir});
  EXPECT_NE(input_error([&] { ftc::tune::parse_job_text(other, "job.json"); })
                .find("/plant/model: plugin:no_such_plant: ftctune_plant_no_such_plant.so is not "
                      "on the plant search path (searched " +
                      (kDir / "broken").string() + ", " + kDir.string() + ")"),
            std::string::npos);
  const ftc::tune::Job job = ftc::tune::parse_job_text(text, "job.json");
  EXPECT_EQ(job.plant.model, "plugin:reaction_wheel_pendulum");
  EXPECT_EQ(job.plant.values.size(), 6u);
  // Its parameters are checked with their paths, as a shipped plant's are.
  std::string bad = text;
  bad.replace(bad.find("\"inertia\": 0.04"), 15, "\"inertia\": -1");
  const std::string e = input_error([&] { ftc::tune::parse_job_text(bad, "job.json"); });
  EXPECT_NE(e.find("/plant/inertia: must be"), std::string::npos) << e;
  ftc::sim::set_plant_search_path({});
}

// Its own uncertain parameter (mass_length, which no shipped plant has): a scenario's true value
// (model mismatch) and an ensemble's scale, as for a shipped plant's.
TEST(PlantPlugin, ItsUncertainParametersTakeTrueValuesAndEnsembleScales) {
  ftc::sim::set_plant_search_path({kDir});
  nlohmann::json j = nlohmann::json::parse(ftc::testing::slurp(kJob));
  j["scenarios"][0]["mass_length"] = {0.15};
  j["ensemble"] = {{"count", 4}, {"seed", 3}, {"mass_length_scale", {{"uniform", {0.8, 1.2}}}}};
  const ftc::tune::Job job = ftc::tune::parse_job(j, "job.json");
  ASSERT_EQ(job.scenarios[0].true_values.size(), 1u);
  EXPECT_EQ(job.scenarios[0].true_values[0].parameter, "mass_length");
  ASSERT_TRUE(job.ensemble);
  // The simulated pendulum is the truer one: another run than with the model's m ℓ.
  const auto plant = ftc::sim::make_plant(job.plant);
  ftc::sim::Scenario nominal = job.scenarios[0];
  nominal.true_values.clear();
  const auto a = plant->simulate(ftc::sim::ControllerConfig{}, job.scenarios[0]);
  const auto b = plant->simulate(ftc::sim::ControllerConfig{}, nominal);
  EXPECT_NE(a.metrics.errors.ise, b.metrics.errors.ise);
  // A parameter it does not declare uncertain is refused with its path.
  j["scenarios"][0].erase("mass_length");
  j["scenarios"][0]["actuator_scale"] = {1.0, 0.5};  // a rigid body's
  j.erase("ensemble");
  const std::string e = input_error([&] { ftc::tune::parse_job(j, "job.json"); });
  EXPECT_NE(e.find("/scenarios/0/actuator_scale"), std::string::npos) << e;
  EXPECT_NE(e.find("does not declare actuator_scale uncertain (its uncertain parameters: inertia, "
                   "mass_length)"),
            std::string::npos)
      << e;
  ftc::sim::set_plant_search_path({});
}

TEST(PlantPlugin, CommandLineFindsItByPathOrEnvironmentAndChecksIt) {
  const fs::path dir = fresh_dir("plugin-cli");
  auto r = run_cli("validate " + kJobArg, dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("1 problem"), std::string::npos) << r.err;  // not a guessed state length
  EXPECT_EQ(run_cli("validate " + kJobArg + kPathArg, dir).exit_code, 0);
  r = run_cli("validate " + kJobArg, dir, "FTCTUNE_PLANT_PATH='" + kDir.string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  // The schema lists the plugins on the search path.
  r = run_cli("schema job" + kPathArg, dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("\"plugin:reaction_wheel_pendulum\""), std::string::npos);
  EXPECT_NE(r.out.find("mass_length"), std::string::npos);

  r = run_cli("plant check '" + kPendulum.string() + "'", dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("plugin:reaction_wheel_pendulum (n = 1, m = 2)"), std::string::npos);
  EXPECT_NE(r.out.find("ok   G(X) G⁺(X) = I"), std::string::npos) << r.out;
  // Another ABI: one line, exit 2.
  r = run_cli("plant check '" + broken("wrong_abi").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("rebuild it with ftctune_add_plant"), std::string::npos) << r.err;
}

TEST(PlantPlugin, CheckComparesWithAPythonModelAndFailsOnAWrongOne) {
  const fs::path dir = fresh_dir("plugin-python");
  // The README's equations, in Python.
  const std::string model = R"(import math
def f(x, p):
    return [(p["mass_length"] * p["gravity"] * math.sin(x[0]) - p["friction"] * x[1]) / p["inertia"]]
def G(x, p):
    return [[-k / p["inertia"] for k in p["wheel_gains"]]]
)";
  std::ofstream(dir / "model.py") << model;
  auto r =
      run_cli("plant check '" + kPendulum.string() + "' --python /usr/bin/python3 --against '" +
                  (dir / "model.py").string() + "'",
              dir);
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("ok   f and G against model.py: worst relative difference: f "),
            std::string::npos)
      << r.out;
  // g0 = 9.8 instead of the plant's 9.81: a relative 1e-3 off.
  std::string wrong = model;
  wrong.replace(wrong.find("p[\"gravity\"]"), 12, "9.8");
  std::ofstream(dir / "wrong.py") << wrong;
  r = run_cli("plant check '" + kPendulum.string() + "' --python /usr/bin/python3 --against '" +
                  (dir / "wrong.py").string() + "'",
              dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("FAIL f and G against wrong.py: worst relative difference: f 0.00"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.err.find("fails 1 of"), std::string::npos) << r.err;
}

}  // namespace
