#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/report/landscape.hpp"
#include "ftc/tune/report/report.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "short_job.hpp"

using nlohmann::json;
using namespace ftc;
using namespace ftc::testing;

namespace {

// A finished run of the shortened Table 1 job, as `ftctune run` leaves it.
std::filesystem::path finished_run(const std::string& name) {
  const auto dir = fresh_dir(name);
  tune::TbbEvaluator evaluator(2);
  tune::write_outputs(tune::tune(tune::parse_job(short_table1_job(), "short"), evaluator),
                      dir / "run");
  return dir / "run";
}

int count_lines(const std::string& s) {
  return static_cast<int>(std::count(s.begin(), s.end(), '\n'));
}

const char* kFigures[] = {"fig3-attitude", "fig4-rates", "fig5-fitness", "fig6-inputs",
                          "fig7-fault-zoom"};

}  // namespace

TEST(Report, RendersEveryFigureAndASelfContainedPage) {
  const auto run = finished_run("report-html");
  const tune::ReportResult r = tune::render_report(run);
  ASSERT_EQ(r.figures.size(), 5u);
  for (const char* name : kFigures) {
    const auto file = run / "figures" / (std::string(name) + ".png");
    const std::string png = slurp(file);
    EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << name;
    EXPECT_GT(png.size(), 10000u) << name;  // a drawn figure, not an empty canvas
    EXPECT_LT(png.size(), 2000000u) << name;
  }
  const std::string html = slurp(r.html);
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  std::size_t images = 0;
  for (std::size_t p = 0; (p = html.find("data:image/png;base64,", p)) != std::string::npos; ++p)
    ++images;
  EXPECT_EQ(images, 5u);
  for (const char* text : {"<table", "NFTSMC", "FOSMC", "PI-FOSMC (job)", "optimal PI-FOSMC",
                           "Tuned gains", "<td>Kp</td>", "ISE [2, 3.5)", "peak ‖e‖ after fault 2",
                           "&quot;schema&quot;: &quot;ftctune.job/1&quot;"})
    EXPECT_NE(html.find(text), std::string::npos) << text;
  EXPECT_EQ(html.find("src=\"figures/"), std::string::npos);  // nothing outside the page
}

TEST(Report, DataFilesHaveTheExpectedColumnsAndRows) {
  const auto run = finished_run("report-data");
  const json comparison = json::parse(slurp(run / "comparison.json"));
  ASSERT_EQ(comparison["controllers"].size(), 4u);
  for (const json& c : comparison["controllers"]) {
    const std::string csv = slurp(run / c["scenarios"][0]["trajectory"].get<std::string>());
    EXPECT_EQ(csv.substr(0, csv.find('\n')), "time,x1,x2,x3,x4,x5,x6,ud1,ud2,ud3,ud4,u1,u2,u3,u4");
    EXPECT_EQ(count_lines(csv), 1 + 500);  // header + 5 s every 10 ms
  }
  EXPECT_EQ(count_lines(slurp(run / "history.csv")), 1 + 3);  // header + iterations 0..2
}

TEST(Report, FigureFilesInSvgAndPng) {
  const auto run = finished_run("report-formats");
  tune::ReportOptions svg;
  svg.html = false;
  svg.format = tune::FigureFormat::svg;
  const tune::ReportResult r = tune::render_report(run, svg);
  EXPECT_TRUE(r.html.empty());
  for (const auto& f : r.figures) {
    const std::string s = slurp(f);
    EXPECT_EQ(f.extension(), ".svg");
    EXPECT_EQ(s.rfind("<?xml", 0), 0u) << f;
    EXPECT_NE(s.find("<svg"), std::string::npos) << f;
    const char* xlabel = f.filename() == "fig5-fitness.svg" ? "iteration" : "time [s]";
    EXPECT_NE(s.find(xlabel), std::string::npos) << f.filename() << ": axis label";
  }
}

namespace {
std::string detail_number(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}
}  // namespace

TEST(Report, LandscapeGridAndHeatmap) {
  const auto run = finished_run("landscape");
  tune::LandscapeOptions o;
  o.n1 = 5;
  o.n2 = 4;
  tune::TbbEvaluator evaluator(2);
  o.history = run / "history.csv";
  const tune::LandscapeResult r = tune::compute_landscape(
      tune::parse_job(short_table1_job(), "short"), run / "landscape", o, evaluator);
  EXPECT_EQ(r.simulations, 20);
  EXPECT_EQ(r.params, (std::vector<std::string>{"Kp", "Ki"}));
  std::istringstream csv(slurp(r.csv));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "Kp,Ki,objective,fitness,diverged");
  int rows = 0;
  double lowest = 1e300;
  while (std::getline(csv, line)) {
    if (line.empty()) continue;  // row separators for gnuplot
    ++rows;
    double kp, ki, obj, fit;
    int div;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%d", &kp, &ki, &obj, &fit, &div), 5)
        << line;
    EXPECT_GE(kp, 1.0);
    EXPECT_LE(kp, 50.0);
    EXPECT_NEAR(fit, 1.0 / obj, 1e-6 * fit);
    lowest = std::min(lowest, obj);
  }
  EXPECT_EQ(rows, 20);
  EXPECT_NEAR(r.best_objective, lowest, 1e-8 * lowest);
  EXPECT_EQ(slurp(r.figure).substr(0, 4), std::string("\x89PNG", 4));
  const std::string gp = slurp(run / "landscape" / "landscape.gp");
  EXPECT_NE(gp.find("history.csv"), std::string::npos);
  // viridis, not a rainbow, and coloured by the relative excess over the lowest objective.
  EXPECT_NE(gp.find("set palette defined (0 '#440154'"), std::string::npos) << gp;
  EXPECT_EQ(gp.find("rgb 33,13,10"), std::string::npos);
  EXPECT_NE(gp.find("($3/" + detail_number(r.best_objective) + " - 1)"), std::string::npos) << gp;

  o.params = {"Kp", "c1"};
  EXPECT_THROW(tune::compute_landscape(tune::parse_job(short_table1_job(), "short"), run / "l2", o,
                                       evaluator),
               InputError);
}

TEST(Cli, ReportRejectsMissingOrBrokenRunDirectories) {
  const auto dir = fresh_dir("report-errors");
  CliResult r = run_cli("report '" + (dir / "nope").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("is not a directory"), std::string::npos) << r.err;
  EXPECT_EQ(count_lines(r.err), 1);

  std::filesystem::create_directories(dir / "empty");
  r = run_cli("report '" + (dir / "empty").string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("missing gains.json: not the output directory of `ftctune run`"),
            std::string::npos)
      << r.err;

  const auto run = finished_run("report-broken");
  {
    std::ofstream f(run / "comparison.json");
    f << "{ truncated";
  }
  r = run_cli("report '" + run.string() + "'", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("comparison.json: is not a JSON object"), std::string::npos) << r.err;
  r = run_cli("report '" + run.string() + "' --format pdf", dir);
  EXPECT_EQ(r.exit_code, 2);
}

TEST(Cli, RunWithReportAndRandomBaseline) {
  const auto dir = fresh_dir("run-report");
  {
    std::ofstream f(dir / "job.json");
    f << short_table1_job().dump();
  }
  const CliResult r = run_cli("run '" + (dir / "job.json").string() +
                                  "' --baseline --report -q --out '" + (dir / "out").string() + "'",
                              dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "report.html"));
  const std::string random = slurp(dir / "out" / "history-random.csv");
  EXPECT_EQ(count_lines(random), count_lines(slurp(dir / "out" / "history.csv")));
  EXPECT_NE(slurp(dir / "out" / "figures" / "report.gp").find("random search, same budget"),
            std::string::npos);
}

// The figures read the trajectory's columns by the plant's shape: for the two-joint,
// three-actuator arm, positions are columns 2-3, rates 4-5, commands 6-8 and applied outputs 9-11
// (the spacecraft's 3 + 3 + 4 + 4 layout read them wrongly before).
TEST(Report, FiguresFollowThePlantsShape) {
  const auto dir = fresh_dir("report-arm");
  std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/manipulator.json");
  nlohmann::json j = nlohmann::json::parse(in);
  j["scenarios"][0]["duration"] = 7;
  j["objective"]["window"] = {3, 7};
  j["tuning"]["algorithm"]["population"] = 3;
  j["tuning"]["algorithm"]["iterations"] = 1;
  tune::TbbEvaluator evaluator(2);
  tune::write_outputs(tune::tune(tune::parse_job(j, "arm"), evaluator), dir / "run");
  const tune::ReportResult r = tune::render_report(dir / "run", {.html = false});
  ASSERT_EQ(r.figures.size(), 5u);
  const std::string gp = slurp(dir / "run" / "figures" / "report.gp");
  for (const char* col : {"using 1:2 ", "using 1:3 ", "using 1:4 ", "using 1:5 ", "using 1:6 ",
                          "using 1:8 ", "using 1:9 ", "using 1:11 "})
    EXPECT_NE(gp.find(col), std::string::npos) << col;
  for (const char* col : {"using 1:12 ", "using 1:13 ", "using 1:14 ", "using 1:15 "})
    EXPECT_EQ(gp.find(col), std::string::npos) << col;           // the spacecraft's columns
  EXPECT_NE(gp.find("sqrt($2**2 + $3**2)"), std::string::npos);  // ‖X1‖ of two joints
  EXPECT_NE(gp.find("q2 x_2 [rad]"), std::string::npos);
  EXPECT_NE(gp.find("'u_{d3}'"), std::string::npos);
  EXPECT_EQ(gp.find("'u_{d4}'"), std::string::npos);
}

TEST(Report, LandscapeOfALogScaleParameterIsEvenInItsLogarithm) {
  json j = short_table1_job();
  j["tuning"]["parameters"] = {{"Kp", {1, 50}},
                               {"switching_gain", {{"bounds", {2, 200}}, {"scale", "log"}}}};
  const tune::Job job = tune::parse_job(j, "short");
  tune::LandscapeOptions o;
  o.n1 = 3;  // switching_gain 2, 20, 200 (the problem's field order puts it first)
  o.n2 = 2;
  o.params = {"switching_gain", "Kp"};
  tune::TbbEvaluator evaluator(2);
  const auto dir = fresh_dir("landscape-log");
  const tune::LandscapeResult r = tune::compute_landscape(job, dir, o, evaluator);
  std::istringstream csv(slurp(r.csv));
  std::string line;
  std::getline(csv, line);
  std::vector<std::pair<double, double>> points;  // switching_gain, objective at Kp = 1
  while (std::getline(csv, line)) {
    double sg, kp, obj, fit;
    int div;
    if (std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%d", &sg, &kp, &obj, &fit, &div) == 5 &&
        kp == 1.0)
      points.emplace_back(sg, obj);
  }
  ASSERT_EQ(points.size(), 3u);
  EXPECT_EQ(points[0].first, 2.0);
  EXPECT_NEAR(points[1].first, 20.0, 1e-6);
  EXPECT_EQ(points[2].first, 200.0);
  // Each point is the controller with that value itself (not exp of it).
  const tune::TuningProblem p(job);
  for (const auto& [sg, obj] : points) {
    sim::ControllerConfig c = job.controller;
    c.switching_gain = sg;
    c.Kp = 1.0;
    EXPECT_NEAR(p.simulate(c, 0).metrics.errors.ise, obj, 1e-8 * obj) << sg;
  }
  EXPECT_NE(slurp(dir / "landscape.gp").find("log10($1)"), std::string::npos);
}

TEST(Report, LandscapeReportsItsProgressBlockByBlock) {
  tune::LandscapeOptions o;
  o.n1 = 12;
  o.n2 = 12;  // 144 points: three blocks of at most 64
  std::vector<std::pair<std::int64_t, std::int64_t>> calls;
  o.progress = [&](std::int64_t done, std::int64_t total) { calls.emplace_back(done, total); };
  tune::TbbEvaluator evaluator(2);
  const auto dir = fresh_dir("landscape-progress");
  json j = short_table1_job();
  j["scenarios"][0]["duration"] = 1;
  j["scenarios"][0]["faults"] = json::array();
  j["objective"]["window"] = {0, 1};
  tune::compute_landscape(tune::parse_job(j, "short"), dir, o, evaluator);
  ASSERT_GE(calls.size(), 3u);
  EXPECT_EQ(calls.back(), std::make_pair(std::int64_t{144}, std::int64_t{144}));
  for (std::size_t i = 1; i < calls.size(); ++i) EXPECT_GT(calls[i].first, calls[i - 1].first);
}
