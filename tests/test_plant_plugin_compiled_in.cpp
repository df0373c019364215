// The example plant plugin (examples/plant-plugin) against the same plant compiled into this
// program: a job tuned with the plugin, loaded by `ftctune run` from the build's plugin directory
// on every instruction set, with 1 and 2 threads writes the same
// bytes as the job tuned here with the plant registered under the plugin's name. (3 MPI ranks
// with the plugin against one process: tests/test_mpi.cpp.)
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <string>

#include "../examples/plant-plugin/pendulum.hpp"
#include "cli_runner.hpp"
#include "ftc/sim/isa.hpp"
#include "ftc/sim/plant_plugin.hpp"
#include "ftc/tune/api/api.hpp"
#include "ftc/tune/job/job.hpp"
#include "plants/plugin_entry.hpp"

namespace {

namespace fs = std::filesystem;

const fs::path kJob = fs::path(FTC_SOURCE_DIR) / "examples/plant-plugin/job.json";

// The files that carry results (run.json records times and paths).
const char* const kFiles[] = {"gains.json", "history.csv", "comparison.json", "trials.csv"};

// The job tuned here, with the pendulum compiled in.
std::map<std::string, std::string> compiled_in(int threads) {
  static bool registered = false;
  if (!registered) {
    ftc::sim::register_plant_kind(
        ftc::sim::plugin::kind_of<pendulum::Pendulum>(pendulum::kind(), pendulum::build));
    registered = true;
  }
  const ftc::tune::Job job = ftc::tune::load_job(kJob);
  ftc::tune::RunJobOptions o;
  o.write = false;
  o.threads = threads;
  return ftc::tune::run_files(ftc::tune::run_job(job, o));
}

// `ftctune run` of the job with the plugin, under the environment `env`.
fs::path plugin_run(const std::string& name, const std::string& env, const std::string& args) {
  const fs::path dir = ftc::testing::fresh_dir("plugin-" + name);
  const auto r = ftc::testing::run_cli("run '" + kJob.string() +
                                           "' --plant-path '" FTC_PLUGIN_DIR "' --out '" +
                                           (dir / "run").string() + "' -q " + args,
                                       dir, env);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return dir / "run";
}

void expect_same_files(const std::map<std::string, std::string>& expected, const fs::path& dir) {
  for (const char* f : kFiles) {
    const auto it = expected.find(f);
    ASSERT_NE(it, expected.end()) << f;
    EXPECT_TRUE(ftc::testing::slurp(dir / f) == it->second) << f << " differs in " << dir;
  }
}

TEST(PlantPlugin, TunesToTheBytesOfTheSamePlantCompiledInOnEveryIsaAndThreadCount) {
  const auto one = compiled_in(1);
  const auto two = compiled_in(2);
  for (const char* f : kFiles) EXPECT_TRUE(two.at(f) == one.at(f)) << f << " differs on 2 threads";
  EXPECT_NE(one.at("gains.json").find("plugin:reaction_wheel_pendulum"), std::string::npos);
  for (const ftc::sim::Isa isa : ftc::sim::supported_isas())
    for (const int threads : {1, 2}) {
      SCOPED_TRACE(std::string(ftc::sim::to_string(isa)) + ", " + std::to_string(threads) +
                   " threads");
      expect_same_files(one,
                        plugin_run(std::string(ftc::sim::to_string(isa)) + std::to_string(threads),
                                   std::string("FTCTUNE_ISA=") + ftc::sim::to_string(isa),
                                   "--threads " + std::to_string(threads)));
    }
}

}  // namespace
