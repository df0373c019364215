#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "ftc/runtime/gains.hpp"
#include "ftc/sim/manipulator.hpp"
#include "ftc/sim/simulation.hpp"
#include "ftc/sim/spacecraft.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/problem/problem.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "short_job.hpp"

using nlohmann::json;
using namespace ftc;
using namespace ftc::testing;

TEST(GainsFile, RoundTripAndReproducesTunedMetrics) {
  const tune::TuningOutcome r = tuned(short_job(), 2);
  const json doc = tune::gains_document(r);
  EXPECT_EQ(doc["schema"], "ftctune.gains/1");
  EXPECT_EQ(doc["job"]["sha256"].get<std::string>().size(), 64u);
  EXPECT_EQ(doc["history"].size(), 3u);
  const runtime::Gains g = runtime::parse_gains(doc, "gains.json");
  EXPECT_EQ(g.controller.Kp, r.tuned_controller.Kp);
  EXPECT_EQ(g.controller.Ki, r.tuned_controller.Ki);
  ASSERT_EQ(g.tuned.size(), 2u);
  EXPECT_EQ(g.tuned[0].first, "Ki");  // JSON objects come back key-sorted
  EXPECT_EQ(g.sample_time, 0.001);

  // The runtime-loaded controller reproduces the tuned run bit for bit.
  const tune::Job& job = r.job;
  ASSERT_EQ(job.plant.values, (std::vector<double>{20, 17, 15, 1.1e-3}));
  const sim::Spacecraft plant;  // the job's
  auto c = runtime::make_controller(g, plant, 0.001);
  const sim::SimulationResult sr =
      sim::simulate(plant, *c, job.scenarios[0], tune::TuningProblem(job).simulation_options(0));
  EXPECT_EQ(sr.metrics.errors.ise, r.best().outcome.evaluation.scenarios[0].errors.ise);
}

TEST(GainsFile, LoaderRejectsBadFilesClearly) {
  const json doc = tune::gains_document(tuned(short_job(), 2));
  const auto message = [](const json& d) {
    try {
      runtime::parse_gains(d, "g.json");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  json other = doc;
  other["schema"] = "ftctune.gains/2";
  EXPECT_NE(message(other).find(
                "/schema: this file is \"ftctune.gains/2\", expected \"ftctune.gains/1\""),
            std::string::npos)
      << message(other);
  json missing = doc;
  missing.erase("sample_time");
  EXPECT_NE(message(missing).find("/sample_time: is required"), std::string::npos)
      << message(missing);
  json extra = doc;
  extra["notes"] = "x";
  EXPECT_NE(message(extra).find("/notes: unknown key"), std::string::npos);
  json mismatch = doc;
  mismatch["tuned"]["Kp"] = 99.0;
  EXPECT_NE(message(mismatch).find("/tuned/Kp: value 99 differs from /controller/Kp"),
            std::string::npos)
      << message(mismatch);
  json bad_value = doc;
  bad_value["controller"]["Kp"] = 0;
  EXPECT_NE(message(bad_value).find("/controller/Kp"), std::string::npos);

  const runtime::Gains g = runtime::parse_gains(doc, "g.json");
  const sim::Spacecraft plant;
  try {
    runtime::make_controller(g, plant, 0.002);
    FAIL() << "accepted a sample-time mismatch";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "tuned for Ts = 0.001 s, but the controller is to run at Ts = 0.002 s"),
              std::string::npos)
        << e.what();
  }
}

// The README's "Using the gains in flight software" example, verbatim but for the file name.
TEST(Runtime, ReadmeExampleLoadsAndSteps) {
  const auto dir = fresh_dir("runtime");
  tune::write_outputs(tuned(short_job(), 2), dir);
  const std::string file = (dir / "gains.json").string();
  const double t = 0.0;
  const ftc::sim::Vec3 X1(0.1, -0.2, 0.3), X2(0.0, 0.1, 0.0), a(0.0, 0.0, 0.0);

  const ftc::sim::Spacecraft plant({.inertia = {20, 17, 15}, .orbital_rate = 1.1e-3});
  std::unique_ptr<ftc::sim::Controller<3, 4>> ctl =
      ftc::runtime::load_controller(file, plant, /*sample_time=*/0.001);  // throws ftc::InputError
  ctl->reset();
  ftc::sim::Vec4 u_d = ctl->step(t, X1, X2, a);

  EXPECT_TRUE(u_d.allFinite());
  EXPECT_NE(u_d, ftc::sim::Vec4::Zero());
  EXPECT_THROW(ftc::runtime::load_controller(file, plant, 0.002), ftc::InputError);
  EXPECT_THROW(ftc::runtime::load_controller(dir / "missing.json", plant, 0.001), ftc::InputError);
}

TEST(GainsFile, NumbersOutOfRangeAndDuplicateKeysAreInputErrorsWithThePath) {
  const auto dir = fresh_dir("gains-strict");
  std::string text = tune::gains_document(tuned(short_job(), 2)).dump(2);
  const auto load = [&](const std::string& t) -> FieldError {
    std::ofstream(dir / "g.json") << t;
    try {
      runtime::read_gains(dir / "g.json");
    } catch (const InputError& e) {
      EXPECT_EQ(e.source(), (dir / "g.json").string());
      return e.errors().front();
    }
    ADD_FAILURE() << "accepted";
    return {};
  };
  const std::string ts = "\"sample_time\": 0.001";
  ASSERT_NE(text.find(ts), std::string::npos);
  std::string big = text;
  big.replace(big.find(ts), ts.size(), "\"sample_time\": 1e400");
  FieldError e = load(big);
  EXPECT_EQ(e.path, "/sample_time");
  EXPECT_NE(e.message.find("out of the range of a double"), std::string::npos) << e.message;

  std::string twice = text;
  twice.replace(twice.find(ts), ts.size(), ts + ", \"sample_time\": 0.002");
  e = load(twice);
  EXPECT_EQ(e.path, "/sample_time");
  EXPECT_NE(e.message.find("duplicate key"), std::string::npos) << e.message;
}

// A crude fuzzer of the flight-software contract: whatever a gains file holds, the loader and
// make_controller either succeed or throw InputError, never another exception.
TEST(GainsFile, EveryMalformedDocumentIsAnInputError) {
  const json doc = tune::gains_document(tuned(short_job(), 2));
  const std::vector<json> replacements = {json(nullptr),
                                          json(true),
                                          json(0),
                                          json(-1),
                                          json(0.5),
                                          json(1e308),
                                          json(-1e308),
                                          json(5e-324),
                                          json(std::numeric_limits<std::int64_t>::min()),
                                          json(std::numeric_limits<std::uint64_t>::max()),
                                          json(""),
                                          json("x"),
                                          json::array(),
                                          json::array({1, 2, 3}),
                                          json::object(),
                                          json({{"a", 1}})};
  const sim::Spacecraft plant;
  int cases = 0;
  const auto check = [&](const json& d, const std::string& what) {
    ++cases;
    try {
      const runtime::Gains g = runtime::parse_gains(d, "g.json");
      auto c = runtime::make_controller(g, plant, g.sample_time);
      c->reset();
      (void)c->step(0.0, sim::Vec3(0.1, 0, 0), sim::Vec3::Zero(), sim::Vec3::Zero());
    } catch (const InputError&) {
    } catch (const std::exception& e) {
      ADD_FAILURE() << what << ": " << e.what();
    }
  };
  const json flat = doc.flatten();
  for (auto it = flat.begin(); it != flat.end(); ++it) {
    const json::json_pointer p(it.key());
    for (const json& r : replacements) {
      json d = doc;
      d[p] = r;
      check(d, it.key() + " = " + r.dump());
    }
    json d = doc;
    if (json& parent = d[p.parent_pointer()]; parent.is_object()) {
      parent.erase(p.back());
      check(d, it.key() + " removed");
    }
  }
  for (auto it = doc.begin(); it != doc.end(); ++it)
    for (const json& r : replacements) {
      json d = doc;
      d[it.key()] = r;
      check(d, it.key() + " = " + r.dump());
    }
  EXPECT_GT(cases, 500);
}

TEST(GainsFile, GainsOfATuningWhereEveryCandidateDivergedAreRefused) {
  json doc = tune::gains_document(tuned(short_job(), 2));
  for (const json& fitness : {json(0.0), json(nullptr), json(-1.0)}) {
    doc["fitness"] = fitness;
    try {
      runtime::parse_gains(doc, "g.json");
      ADD_FAILURE() << "accepted fitness " << fitness.dump();
    } catch (const InputError& e) {
      ASSERT_EQ(e.errors().size(), 1u) << e.what();
      EXPECT_EQ(e.errors()[0].path, "/fitness");
      EXPECT_NE(e.errors()[0].message.find("every candidate diverged"), std::string::npos)
          << e.what();
    }
  }
}

TEST(GainsFile, GainsForAnotherPlantAreRefused) {
  const runtime::Gains g = runtime::parse_gains(tune::gains_document(tuned(short_job(), 2)), "g");
  ASSERT_EQ(g.plant.model, "spacecraft");
  try {
    runtime::make_controller(g, sim::Manipulator(), g.sample_time);
    ADD_FAILURE() << "spacecraft gains accepted for a manipulator";
  } catch (const InputError& e) {
    EXPECT_EQ(e.errors()[0].path, "/plant/model");
    EXPECT_NE(std::string(e.what()).find(
                  "tuned for a \"spacecraft\" plant, but the controller is to run on a "
                  "\"manipulator\" plant"),
              std::string::npos)
        << e.what();
  }

  // The parameters are compared when the caller states them.
  EXPECT_NO_THROW(runtime::check_plant(g, {"spacecraft", {}}));  // the defaults, as tuned
  EXPECT_NO_THROW(runtime::check_plant(g, {"spacecraft", {20, 17, 15, 1.1e-3}}));
  try {
    runtime::check_plant(g, {"spacecraft", {25, 17, 15, 1.1e-3}});
    ADD_FAILURE() << "accepted another inertia";
  } catch (const InputError& e) {
    ASSERT_EQ(e.errors().size(), 1u) << e.what();
    EXPECT_EQ(e.errors()[0].path, "/plant/inertia/0");
    EXPECT_NE(e.errors()[0].message.find("tuned for 20, the plant has 25"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(runtime::check_plant(g, {"manipulator", {}}), InputError);
  EXPECT_THROW(runtime::check_plant(g, {"spacecraft", {20, 17}}), InputError);
}

// Gains of a run stopped before its last iteration are the best of a partial search.
TEST(GainsFile, GainsOfAnUnfinishedTuningAreRefused) {
  json doc = tune::gains_document(tuned(short_job(), 2));
  ASSERT_EQ(doc["optimizer"]["completed"], true);
  EXPECT_NO_THROW(runtime::parse_gains(doc, "g.json"));
  doc["optimizer"]["completed"] = false;
  try {
    runtime::parse_gains(doc, "g.json");
    ADD_FAILURE() << "gains of an unfinished run accepted";
  } catch (const InputError& e) {
    ASSERT_EQ(e.errors().size(), 1u) << e.what();
    EXPECT_EQ(e.errors()[0].path, "/optimizer/completed");
    EXPECT_NE(e.errors()[0].message.find("stopped before its last iteration"), std::string::npos)
        << e.what();
  }
}

// check_job tells gains from the job they were tuned on; `simulate --gains` on another job
// warns that its metrics are not the tuned objective.
TEST(GainsFile, CheckJobComparesTheJobsSha256) {
  const tune::Job job = short_job();
  const runtime::Gains g = runtime::parse_gains(tune::gains_document(tuned(job, 2)), "g");
  EXPECT_NO_THROW(runtime::check_job(g, tune::canonical_job_sha256(job)));
  tune::Job other = job;
  other.scenarios[0].disturbance.clear();
  try {
    runtime::check_job(g, tune::canonical_job_sha256(other));
    ADD_FAILURE() << "gains accepted for another job";
  } catch (const InputError& e) {
    EXPECT_EQ(e.errors()[0].path, "/job/sha256");
    EXPECT_NE(std::string(e.what()).find("tuned on job \"table1-short\""), std::string::npos)
        << e.what();
  }

  const auto dir = fresh_dir("gains-other-job");
  std::ofstream(dir / "gains.json") << tune::gains_document(tuned(job, 2)).dump(2);
  json j = short_table1_job();
  std::ofstream(dir / "same.json") << j.dump(2);
  j["scenarios"][0]["disturbance"] = json::array();
  std::ofstream(dir / "other.json") << j.dump(2);
  const auto same =
      run_cli("simulate '" + (dir / "same.json").string() + "' --gains '" +
                  (dir / "gains.json").string() + "' --out '" + (dir / "s1").string() + "'",
              dir);
  ASSERT_EQ(same.exit_code, 0) << same.err;
  EXPECT_EQ(same.err.find("not the objective"), std::string::npos) << same.err;
  const auto other_run =
      run_cli("simulate '" + (dir / "other.json").string() + "' --gains '" +
                  (dir / "gains.json").string() + "' --out '" + (dir / "s2").string() + "'",
              dir);
  ASSERT_EQ(other_run.exit_code, 0) << other_run.err;
  EXPECT_NE(other_run.err.find("the metrics below are not the objective they were tuned to"),
            std::string::npos)
      << other_run.err;
}
