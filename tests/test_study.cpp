#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_runner.hpp"
#include "short_job.hpp"

using nlohmann::json;
using namespace ftc::testing;

namespace {

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

// The short Table 1 job in `dir`, quoted for the shell.
std::string job_file(const std::filesystem::path& dir) {
  std::ofstream f(dir / "job.json");
  f << short_table1_job().dump(2);
  // Built by appends: GCC 12 warned -Wrestrict on the concatenation.
  std::string quoted = "'";
  quoted += (dir / "job.json").string();
  quoted += "'";
  return quoted;
}

}  // namespace

TEST(Study, WritesOneRowPerRunTheTableAndTheFigure) {
  const auto dir = fresh_dir("study");
  const std::string out = (dir / "study").string();
  // The short job's Bat algorithm has 3 bats: 20 evaluations pay for 5 iterations (18); pagmo's
  // CMA-ES needs 5 members, so 3 generations (20).
  const CliResult r = run_cli("study " + job_file(dir) +
                                  " --algorithms bat,pagmo:cmaes --seeds 1,2 --budget 20 "
                                  "--threads 2 --out '" +
                                  out + "'",
                              dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("[4/4] pagmo:cmaes seed 2: ise = "), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("| rank | algorithm | median | best | worst |"), std::string::npos) << r.out;

  const std::vector<std::string> csv = lines(slurp(dir / "study" / "study.csv"));
  ASSERT_EQ(csv.size(), 5u);
  EXPECT_EQ(csv[0], "algorithm,seed,objective,Kp,Ki,on_bound,evaluations,wall_seconds");
  EXPECT_EQ(csv[1].rfind("bat,1,", 0), 0u) << csv[1];
  EXPECT_EQ(csv[4].rfind("pagmo:cmaes,2,", 0), 0u) << csv[4];
  EXPECT_NE(csv[1].find(",18,"), std::string::npos) << csv[1];
  EXPECT_NE(csv[3].find(",20,"), std::string::npos) << csv[3];

  const std::string md = slurp(dir / "study" / "study.md");
  int rows = 0;
  std::vector<std::pair<int, double>> ranked;  // rank, median in table order
  for (const std::string& l : lines(md))
    if (l.find(" | bat |") != std::string::npos ||
        l.find(" | pagmo:cmaes |") != std::string::npos) {
      ++rows;
      const std::size_t a = l.find(" | ", l.find(" | ") + 3) + 3;  // the median cell
      ranked.emplace_back(std::stoi(l.substr(2)), std::stod(l.substr(a)));
    }
  EXPECT_EQ(rows, 2) << md;
  // Medians inside the noise floor tie; a rank below another is only ever beyond it.
  const std::size_t nf = md.find("moves the best run's objective by up to ");
  ASSERT_NE(nf, std::string::npos) << md;
  const double noise = std::stod(md.substr(nf + 40)) / 100;
  ASSERT_EQ(ranked.size(), 2u);
  // The medians to the last bit, from study.csv (two seeds: their mean).
  std::map<std::string, double> median;
  for (std::size_t i = 1; i < csv.size(); ++i) {
    const std::string name = csv[i].substr(0, csv[i].find(','));
    const std::size_t at = csv[i].find(',', csv[i].find(',') + 1) + 1;
    median[name] += 0.5 * std::stod(csv[i].substr(at));
  }
  const double m0 = std::min(median["bat"], median["pagmo:cmaes"]),
               m1 = std::max(median["bat"], median["pagmo:cmaes"]);
  const bool tie = m1 - m0 <= noise * m0;
  EXPECT_EQ(ranked[1].first, tie ? 1 : 2) << md;
  EXPECT_NE(md.find(tie ? "| 1= | " : "| 2 | "), std::string::npos) << md;
  // The figure: the objective with its unit, and the noise band.
  const std::string gp = slurp(dir / "study" / "study.gp");
  EXPECT_NE(gp.find("of the best candidate [rad²·s]"), std::string::npos) << gp;
  EXPECT_NE(gp.find("set object 1 rect from graph 0, first "), std::string::npos) << gp;
  EXPECT_NE(gp.find("within the noise floor ("), std::string::npos) << gp;
  EXPECT_NE(md.find("\"name\":\"cmaes\""), std::string::npos) << md;
  const std::string png = slurp(dir / "study" / "study.png");
  ASSERT_GT(png.size(), 8u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
}

// Memory by design: a study whose runs would not fit the budget is refused before any run.
TEST(Study, StudyAboveTheMemoryBudgetIsRefusedBeforeAnyRun) {
  const auto dir = fresh_dir("study-memory");
  nlohmann::json j = short_table1_job();
  j["ensemble"] = {{"count", 1000000}, {"seed", 1}};
  std::ofstream(dir / "job.json") << j.dump();
  ::setenv("FTCTUNE_MEMORY_MIB", "100", 1);
  const CliResult r = run_cli("study '" + (dir / "job.json").string() +
                                  "' --algorithms bat --seeds 1-3 --budget 100 --out '" +
                                  (dir / "o").string() + "'",
                              dir);
  ::unsetenv("FTCTUNE_MEMORY_MIB");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("would need about 261 MB of memory (1 listed scenario and its "
                       "comparison at about 1.28 MB, 1000000 ensemble members "
                       "at about 192 bytes each, 100 trials at about 1344 bytes each)"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "o"));
}

TEST(Study, AJobOfAParetoFrontIsRefused) {
  const auto dir = fresh_dir("study-front");
  nlohmann::json j = short_table1_job();
  j.erase("objective");
  j["goals"] = {{{"metric", "ise"}, {"minimize", true}}, {{"metric", "control_tv"}, {"minimize", true}}};
  std::ofstream(dir / "job.json") << j.dump();
  const CliResult r = run_cli("study '" + (dir / "job.json").string() +
                                  "' --algorithms bat --seeds 1 --budget 20 --out '" +
                                  (dir / "o").string() + "'",
                              dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("/goals"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("Pareto front"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "o"));
}

TEST(Study, BadAlgorithmsSeedsAndBudgetsExitTwo) {
  const auto dir = fresh_dir("study-errors");
  const std::string job = job_file(dir);
  const auto study = [&](const std::string& args) {
    return run_cli("study " + job + " " + args + " --out '" + (dir / "o").string() + "'", dir);
  };
  const struct {
    std::string args, message;
  } cases[] = {
      {"--algorithms '' --seeds 1 --budget 20", "--algorithms: is empty"},
      {"--algorithms bat,pagmo:pso2 --seeds 1 --budget 20",
       "--algorithms: unknown algorithm \"pagmo:pso2\" (known: bat, random, pagmo:bee_colony"},
      {"--algorithms bat,cmaes --seeds 1 --budget 20", "unknown algorithm \"cmaes\""},
      {"--algorithms bat,bat --seeds 1 --budget 20", "\"bat\" is given twice"},
      {"--algorithms bat --seeds 3-1 --budget 20", "--seeds: range \"3-1\" runs backwards"},
      {"--algorithms bat --seeds 1,x --budget 20", "\"x\" is not a seed or a range"},
      {"--algorithms bat --seeds 1-3,2 --budget 20", "seed 2 is given twice"},
      {"--algorithms bat --seeds 5,1-10 --budget 20", "seed 5 is given twice"},
      // The cap is on the total, and ranges are not expanded to check it.
      {"--algorithms bat --seeds 1-100000,100001-200000 --budget 20",
       "--seeds: gives more than 100000 seeds in all"},
      {"--algorithms bat --seeds 1-10000000 --budget 20", "gives more than 100000 seeds in all"},
      {"--algorithms bat --seeds 0-18446744073709551615 --budget 20",
       "gives more than 100000 seeds in all"},
      {"--algorithms bat --seeds -1 --budget 20", "\"-1\" is not a seed"},
      {"--algorithms bat --seeds 1 --budget 5",
       "--budget: 5 evaluations do not pay for one generation of bat"},
      {"--algorithms pagmo:gaco --seeds 1 --budget 100",
       "do not pay for one generation of pagmo:gaco after its initial population of 63"},
  };
  for (const auto& c : cases) {
    const CliResult r = study(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << "\n" << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "o"));  // nothing ran
}
