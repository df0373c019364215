#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "ftc/tune/api/api.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/report/evaluation.hpp"
#include "ftc/tune/report/report.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/evaluate.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "io/text.hpp"
#include "report/front_figures.hpp"
#include "report/gnuplot.hpp"
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
  for (const char* text : {"<table", "NFTSMC", "FOSMC", "PI-FOSMC (job)", "tuned PI-FOSMC",
                           "Tuned gains", "<td>Kp</td>", "ISE [2, 3.5)", "peak ‖e‖ after fault 2",
                           "&quot;schema&quot;: &quot;ftctune.job/1&quot;"})
    EXPECT_NE(html.find(text), std::string::npos) << text;
  EXPECT_EQ(html.find("src=\"figures/"), std::string::npos);  // nothing outside the page
  EXPECT_EQ(html.find("<h2>Goals</h2>"), std::string::npos);  // a job without goals
}

// report.html holds what comparison.md holds: the objective named by metric, window and
// aggregate, the noise-floor sentence, the robust table of an ensemble job; and the run's
// evaluation/ once there is one.
TEST(Report, PageLabelsTheObjectiveAndHoldsTheRobustTableAndTheEvaluation) {
  const auto dir = fresh_dir("report-robust");
  const tune::Job job = tune::parse_job(short_ensemble_job(), "robust");
  tune::TbbEvaluator evaluator(2);
  const tune::TuningOutcome outcome = tune::tune(job, evaluator);
  tune::write_outputs(outcome, dir / "run");
  const std::string label = "CVaR0.9 of ISE[first fault, +4 s] over 7 scenarios";
  const std::string md = slurp(dir / "run" / "comparison.md");
  EXPECT_NE(md.find("Objective: " + label), std::string::npos) << md;
  std::string html = slurp(tune::render_report(dir / "run").html);
  EXPECT_NE(html.find("); " + label + " = "), std::string::npos);
  EXPECT_EQ(html.find("objective ise ="), std::string::npos);
  EXPECT_NE(html.find("<h2>All 7 scenarios</h2>"), std::string::npos);
  EXPECT_NE(html.find("<th>" + label + "</th><th>mean</th><th>median</th><th>p90</th>"),
            std::string::npos);
  const std::string noise = tune::noise_floor_sentence(outcome);
  ASSERT_FALSE(noise.empty());
  EXPECT_NE(html.find("<p class=\"noise-floor\">" + noise + "</p>"), std::string::npos);
  EXPECT_EQ(html.find("Out-of-sample evaluation"), std::string::npos);
  // `ftctune evaluate`'s default place is the run's evaluation/.
  tune::EvaluateOptions eo;
  eo.count = 3;
  const tune::EvaluationResult ev = tune::evaluate_out_of_sample(job, eo, evaluator);
  tune::write_evaluation(ev, dir / "run" / "evaluation");
  html = slurp(tune::render_report(dir / "run").html);
  EXPECT_NE(html.find("<h2>Out-of-sample evaluation</h2>"), std::string::npos);
  EXPECT_NE(html.find("1 listed scenario(s) and 3 held-out ensemble members (seed 8)"),
            std::string::npos);
  const std::string row = "<tr><td>" + ev.controllers[0].label + "</td><td>job</td><td>" +
                          ftc::tune::detail::format_number(ev.controllers[0].aggregates.mean);
  EXPECT_NE(html.find(row), std::string::npos) << row;
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
  EXPECT_NE(gp.find("path.csv"), std::string::npos);
  // viridis, not a rainbow, and coloured by the relative excess over the lowest objective.
  EXPECT_NE(gp.find("set palette defined (0 '#440154'"), std::string::npos) << gp;
  EXPECT_EQ(gp.find("rgb 33,13,10"), std::string::npos);
  EXPECT_NE(gp.find("($3/" + detail_number(r.best_objective) + " - 1)"), std::string::npos) << gp;
  // Units on both axes and on the lowest value (the controllers' headers give them).
  EXPECT_NE(gp.find("set xlabel 'Kp (dimensionless)'"), std::string::npos) << gp;
  EXPECT_NE(gp.find("set ylabel 'Ki [1/s]'"), std::string::npos) << gp;
  EXPECT_NE(gp.find(" rad²·s at Kp = "), std::string::npos) << gp;

  o.params = {"Kp", "c1"};
  EXPECT_THROW(tune::compute_landscape(tune::parse_job(short_table1_job(), "short"), run / "l2", o,
                                       evaluator),
               InputError);
}

// Commands that take a job and look for its run take the latest one, the -2, -3 ... that `run`
// moves on to included, and say which.
TEST(Cli, LandscapeAndEvaluateUseTheJobsLatestRunAndSayWhich) {
  const auto dir = fresh_dir("latest-run");
  tune::write_file_atomic(dir / "job.json", tiny_job("latest").dump(2));
  const auto in_dir = [&](const std::string& args) {
    return run_cli("--help >/dev/null && cd '" + dir.string() + "' && '" FTC_CLI "' " + args, dir);
  };
  ASSERT_EQ(in_dir("run job.json -q").exit_code, 0);
  ASSERT_EQ(in_dir("run job.json -q").exit_code, 0);  // into out/latest-2
  ASSERT_TRUE(std::filesystem::exists(dir / "out" / "latest-2" / "gains.json"));
  CliResult r = in_dir("landscape job.json --grid 2x2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("the latest run of job latest is out/latest-2"), std::string::npos) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "latest-2" / "landscape" / "landscape.png"));
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "latest-2" / "landscape" / "history.csv"));
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "latest" / "landscape"));
  r = in_dir("evaluate job.json --no-figure");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "latest-2" / "evaluation" / "evaluation.json"));
  // --force replaces out/latest: now the newest run.
  ASSERT_EQ(in_dir("run job.json -q --force").exit_code, 0);
  r = in_dir("landscape job.json --grid 2x2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("the latest run of job latest is out/latest (newest gains.json of 2 runs)"),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "latest" / "landscape" / "landscape.png"));
  // report takes the job file too: its latest run.
  r = in_dir("report job.json --format png");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("the latest run of job latest is out/latest "), std::string::npos) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "latest" / "figures" / "fig3-attitude.png"));
  // A job without a run: the landscape goes to out/<name>/landscape, and the log says so.
  tune::write_file_atomic(dir / "other.json", tiny_job("other").dump(2));
  r = in_dir("landscape other.json --grid 2x2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("no run of job other in out"), std::string::npos) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "other" / "landscape" / "landscape.png"));
  r = in_dir("report other.json");  // a job with no run
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("no run of job other in out: run `ftctune run other.json` first"),
            std::string::npos)
      << r.err;
  // The help shows --no-figure as a flag, not with a default.
  r = in_dir("help evaluate");
  EXPECT_NE(r.out.find("--no-figure"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("{false}"), std::string::npos) << r.out;
}

// The landscape of a 3-parameter job holds the third at the values it is given (the tuned ones,
// in the CLI) and says so; colours within the noise floor of the lowest are one; the colour-bar
// tics are round; the optimiser's path is drawn projected where it does not lie on the map.
TEST(Report, LandscapeSaysWhatItFixesMarksTheNoiseAndProjectsThePath) {
  json j = short_table1_job();
  j["tuning"]["parameters"]["switching_gain"] = {{"bounds", {2, 200}}, {"scale", "log"}};
  const tune::Job job = tune::parse_job(j, "three");
  const auto dir = fresh_dir("landscape-three");
  tune::TbbEvaluator evaluator(2);
  const tune::TuningOutcome run = tune::tune(job, evaluator);
  tune::write_outputs(run, dir / "run");
  tune::LandscapeOptions o;
  o.n1 = 4;
  o.n2 = 3;
  o.params = {"Kp", "Ki"};
  o.history = dir / "run" / "history.csv";
  const double tuned_gain = run.tuned_controller.switching_gain;
  o.fixed = {{"switching_gain", tuned_gain}};
  o.fixed_source = "the tuned value, run/gains.json";
  o.noise_floor = 1e-3;
  tune::LandscapeResult r = tune::compute_landscape(job, dir / "tuned", o, evaluator);
  ASSERT_EQ(r.fixed.size(), 1u);
  EXPECT_EQ(r.fixed[0].first, "switching_gain");
  EXPECT_EQ(r.fixed[0].second, tuned_gain);
  const std::string gp = slurp(dir / "tuned" / "landscape.gp");
  EXPECT_NE(gp.find("\\nlowest on the grid "), std::string::npos) << gp;
  EXPECT_NE(gp.find("ISE[0 s, 5 s] of table1-short over Kp and Ki"), std::string::npos) << gp;
  EXPECT_NE(gp.find("switching_gain = " + ftc::tune::detail::format_number(tuned_gain, "%.5g") +
                    " held fixed (the tuned value, run/gains.json)"),
            std::string::npos)
      << gp;
  // Everything within the noise floor of the lowest takes the floor's colour.
  EXPECT_NE(gp.find(" - 1) : 0.001) with image"), std::string::npos) << gp;
  const std::size_t tics = gp.find("set cbtics (");
  ASSERT_NE(tics, std::string::npos);
  const std::string tic_list = gp.substr(tics, gp.find('\n', tics) - tics);
  EXPECT_EQ(tic_list.rfind("set cbtics ('≤ noise floor 0.001' 0.001", 0), 0u) << tic_list;
  // Every other tic is 1, 2, 3 or 5 times a power of ten, labelled as it is.
  std::istringstream labels(tic_list.substr(tic_list.find(", '") + 3));
  for (std::string label; std::getline(labels, label, '\'');) {
    const double v = std::stod(label);
    const double m = v / std::pow(10.0, std::floor(std::log10(v) + 1e-9));
    EXPECT_TRUE(std::abs(m - 1) < 1e-9 || std::abs(m - 2) < 1e-9 || std::abs(m - 3) < 1e-9 ||
                std::abs(m - 5) < 1e-9)
        << label << " in " << tic_list;
    std::string rest;
    std::getline(labels, rest, '\'');  // the value and the separator
  }
  // The path: rows whose switching_gain is not the tuned one lie off the map.
  EXPECT_GT(r.path_points, 0);
  EXPECT_GE(r.path_on_map, 1);  // the last row is the tuned point
  if (r.path_on_map < r.path_points)
    EXPECT_NE(gp.find("optimiser''s best so far, projected"), std::string::npos) << gp;
  else
    EXPECT_NE(gp.find("optimiser: best so far, by iteration"), std::string::npos) << gp;
  EXPECT_EQ(count_lines(slurp(dir / "tuned" / "path.csv")), 1 + r.path_points);

  // Without given values: the job's, and the path is off the map wherever the gain was tuned
  // away from it.
  o.fixed.clear();
  o.fixed_source = "the job's value";
  r = tune::compute_landscape(job, dir / "job", o, evaluator);
  ASSERT_EQ(r.fixed.size(), 1u);
  EXPECT_EQ(r.fixed[0].second, job.controller.switching_gain);
  EXPECT_NE(slurp(dir / "job" / "landscape.gp").find("held fixed (the job's value)"),
            std::string::npos);
  if (tuned_gain != job.controller.switching_gain) {
    EXPECT_LT(r.path_on_map, r.path_points);
  }
}

// The CLI holds the unplotted parameters at the latest run's tuned values, or at the job's with
// --at-job-values, and prints which.
TEST(Cli, LandscapeHoldsTheOtherParametersAtTheTunedValues) {
  const auto dir = fresh_dir("landscape-fixed");
  json j = tiny_job("three");
  j["tuning"]["parameters"]["switching_gain"] = {{"bounds", {2, 200}}, {"scale", "log"}};
  tune::write_file_atomic(dir / "job.json", j.dump(2));
  const auto in_dir = [&](const std::string& args) {
    return run_cli("--help >/dev/null && cd '" + dir.string() + "' && '" FTC_CLI "' " + args, dir);
  };
  ASSERT_EQ(in_dir("run job.json -q").exit_code, 0);
  const json gains = json::parse(slurp(dir / "out" / "three" / "gains.json"));
  char want[160];
  std::snprintf(want, sizeof want, "  switching_gain held fixed at %.6g (the tuned value, ",
                gains["tuned"]["switching_gain"].get<double>());
  CliResult r = in_dir("landscape job.json --grid 2x2 --params Kp,Ki");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find(want), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("lowest on the grid: ISE[0 s, 0.05 s] = "), std::string::npos) << r.out;
  r = in_dir("landscape job.json --grid 2x2 --params Kp,Ki --at-job-values --force");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("  switching_gain held fixed at 20 (the job's value)"), std::string::npos)
      << r.out;
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
// (the spacecraft's 3 + 3 + 4 + 4 layout read them wrongly before). The script's data blocks
// start with the first sample of the column each curve draws.
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
  const json comparison = json::parse(slurp(dir / "run" / "comparison.json"));
  const std::string csv = slurp(
      dir / "run" / comparison["controllers"][0]["scenarios"][0]["trajectory"].get<std::string>());
  ASSERT_EQ(csv.substr(0, csv.find('\n')), "time,x1,x2,x3,x4,ud1,ud2,ud3,u1,u2,u3");
  std::vector<std::string> first_row;
  std::stringstream row(
      csv.substr(csv.find('\n') + 1, csv.find('\n', csv.find('\n') + 1) - csv.find('\n') - 1));
  for (std::string cell; std::getline(row, cell, ',');) first_row.push_back(cell);
  ASSERT_EQ(first_row.size(), 11u);
  // Blocks in drawing order: per position panel, each controller's curve then its markers
  // (the tuned one's distances next); the first curve is controller 0's x1, the first curve
  // after the position and rate figures its ud1.
  const auto block = [&](int k) {
    const std::string head = "$c" + std::to_string(k) + " << EOD\n";
    const std::size_t at = gp.find(head);
    return at == std::string::npos
               ? std::string()
               : gp.substr(at + head.size(), gp.find('\n', at + head.size()) - at - head.size());
  };
  EXPECT_EQ(block(1), "0," + first_row[1]);  // x1
  const std::size_t fig6 = gp.find("fig6-inputs");
  ASSERT_NE(fig6, std::string::npos);
  const std::size_t first_u = gp.find("$c", gp.find("plot ", fig6));
  const int k = std::stoi(gp.substr(first_u + 2));
  EXPECT_EQ(block(k), "0," + first_row[5]);  // ud1
  EXPECT_NE(gp.find("q2 x_2 [rad]"), std::string::npos);
  EXPECT_NE(gp.find("'u_{d3}'"), std::string::npos);
  EXPECT_EQ(gp.find("'u_{d4}'"), std::string::npos);
}

namespace {

// A finished run of the paper's job at its full 30 s (3 000 samples per trajectory) with a
// token search, and its SVG figures.
std::filesystem::path full_length_run(const std::string& name) {
  const auto dir = fresh_dir(name);
  std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/table1.json");
  nlohmann::json j = nlohmann::json::parse(in);
  j["tuning"]["algorithm"]["population"] = 4;
  j["tuning"]["algorithm"]["iterations"] = 1;
  tune::TbbEvaluator evaluator(2);
  tune::write_outputs(tune::tune(tune::parse_job(j, "table1"), evaluator), dir / "run");
  tune::render_report(dir / "run", {.html = false, .format = tune::FigureFormat::svg});
  return dir / "run";
}

// The text of one figure's part of report.gp.
std::string figure_script(const std::string& gp, const std::string& figure) {
  const std::size_t at = gp.find("set output 'figures/" + figure);
  if (at == std::string::npos) return "";
  const std::size_t end = gp.find("set output", at + 1);
  return gp.substr(at, end == std::string::npos ? std::string::npos : end - at);
}

std::vector<double> column(const std::string& csv, int col) {
  std::vector<double> v;
  std::stringstream in(csv);
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::stringstream cells(line);
    std::string cell;
    for (int c = 0; c <= col; ++c) std::getline(cells, cell, ',');
    v.push_back(std::stod(cell));
  }
  return v;
}

}  // namespace

// fig6 shows saturation: the actuators' limits as lines, and with limits every actuator's applied
// output beside its command; its unit is the plant's command's (N for rotors). It drew commands
// only, in N·m for every plant (issue 41).
TEST(Report, ActuatorFigureDrawsTheLimitsTheAppliedOutputsAndThePlantsUnit) {
  const auto dir = fresh_dir("report-limits");
  json j = short_table1_job();
  j["scenarios"][0]["saturation"] = 5;
  j["tuning"]["algorithm"]["population"] = 3;
  j["tuning"]["algorithm"]["iterations"] = 1;
  tune::TbbEvaluator evaluator(2);
  tune::write_outputs(tune::tune(tune::parse_job(j, "sat"), evaluator), dir / "sat");
  tune::render_report(dir / "sat", {.html = false});
  std::string fig6 = figure_script(slurp(dir / "sat" / "figures" / "report.gp"), "fig6-inputs");
  EXPECT_NE(fig6.find("from graph 0, first -5 to graph 1, first -5 nohead"), std::string::npos)
      << fig6.substr(0, 2000);
  EXPECT_NE(fig6.find("from graph 0, first 5 to graph 1, first 5 nohead"), std::string::npos);
  for (int a = 1; a <= 4; ++a)  // no fault on 3 and 4: drawn for the limits
    EXPECT_NE(fig6.find("title 'applied u_" + std::to_string(a) + "'"), std::string::npos) << a;
  EXPECT_NE(fig6.find("actuator output u [N·m]"), std::string::npos);

  std::ifstream in(std::string(FTC_SOURCE_DIR) + "/jobs/quad-x.json");
  json q = json::parse(in);
  q["scenarios"][0]["duration"] = 4;
  q["objective"]["window"] = {3, 4};
  q["tuning"]["algorithm"]["population"] = 3;
  q["tuning"]["algorithm"]["iterations"] = 1;
  tune::write_outputs(tune::tune(tune::parse_job(q, "quad"), evaluator), dir / "quad");
  tune::render_report(dir / "quad", {.html = false});
  fig6 = figure_script(slurp(dir / "quad" / "figures" / "report.gp"), "fig6-inputs");
  EXPECT_NE(fig6.find("actuator output u [N]"), std::string::npos);
  // A rotor's deviation from hover lies in [-T_h, T_max - T_h] = [-3.679, 4.321] N: every rotor
  // gets its applied output, whether or not a line is within the drawn range.
  for (int a = 1; a <= 4; ++a)
    EXPECT_NE(fig6.find("title 'applied u_" + std::to_string(a) + "'"), std::string::npos) << a;
}

// SVGs carry what the eye can see: the 30 s run's fig6 was 1.2 MB with every sample.
TEST(Report, SvgFiguresAreDecimatedToWhatTheEyeCanSee) {
  const auto run = full_length_run("report-decimated");
  EXPECT_LE(std::filesystem::file_size(run / "figures" / "fig6-inputs.svg"), 200u * 1024);
  for (const char* name : kFigures)
    EXPECT_LE(std::filesystem::file_size(run / "figures" / (std::string(name) + ".svg")),
              400u * 1024)
        << name;
  // Nothing a reader would see is lost: a curve keeps its extremes (within half a pixel; here the
  // values themselves). The chattering NFTSMC's first command, a dense band after the first fault,
  // is the hard case.
  const std::string gp = slurp(run / "figures" / "report.gp");
  const json comparison = json::parse(slurp(run / "comparison.json"));
  const std::string csv =
      slurp(run / comparison["controllers"][0]["scenarios"][0]["trajectory"].get<std::string>());
  const std::vector<double> ud1 = column(csv, 7);
  ASSERT_EQ(ud1.size(), 3000u);
  const std::string fig6 = figure_script(gp, "fig6-inputs");
  const std::size_t first_u = fig6.find("$c", fig6.find("plot "));
  const std::string name = fig6.substr(first_u, fig6.find(' ', first_u) - first_u);
  const std::size_t at = gp.find(name + " << EOD\n");
  ASSERT_NE(at, std::string::npos) << name;
  const std::string data = gp.substr(at, gp.find("EOD\n", at + name.size() + 8) - at);
  const int points = count_lines(data) - 1;
  EXPECT_LT(points, 1200);  // of 3 000 samples
  EXPECT_GT(points, 100);   // the band is there
  for (double extreme :
       {*std::min_element(ud1.begin(), ud1.end()), *std::max_element(ud1.begin(), ud1.end())}) {
    char text[40];
    std::snprintf(text, sizeof text, ",%.9g\n", extreme);
    EXPECT_NE(data.find(text), std::string::npos) << "extreme " << text;
  }
}

// One palette everywhere (viridis, perceptually uniform and colour-blind safe), and curves told
// apart by dash and marker as well as colour; the actuator panels share one y scale; the
// convergence plot shows relative improvement; the state figures have panels of differences.
TEST(Report, FiguresReadWellInGreyAndForColourBlindReaders) {
  const auto run = full_length_run("report-styles");
  const std::string gp = slurp(run / "figures" / "report.gp");
  std::vector<std::string> viridis;
  for (int i = 0; i <= 1000; ++i) viridis.push_back(tune::plot::viridis(i / 1000.0));
  const auto near_viridis = [&](const std::string& hex) {
    const auto rgb = [](const std::string& h, int c) {
      return std::stoi(h.substr(1 + 2 * c, 2), nullptr, 16);
    };
    for (const std::string& v : viridis) {
      int d = 0;
      for (int c = 0; c < 3; ++c) d += std::abs(rgb(hex, c) - rgb(v, c));
      if (d <= 3) return true;
    }
    return false;
  };
  std::set<std::string> styles;
  std::size_t at = 0;
  int lines = 0;
  while ((at = gp.find("set style line ", at)) != std::string::npos) {
    const std::string line = gp.substr(at, gp.find('\n', at) - at);
    ++at;
    const std::size_t hash = line.find("'#");
    ASSERT_NE(hash, std::string::npos) << line;
    EXPECT_TRUE(near_viridis(line.substr(hash + 1, 7))) << line;
    EXPECT_NE(line.find(" dt "), std::string::npos) << line;
    EXPECT_NE(line.find(" pt "), std::string::npos) << line;
    styles.insert(line.substr(line.find(" lc ")));
    ++lines;
  }
  EXPECT_GE(lines, 4);
  // The controller style table: ten distinct (colour, dash, marker) styles, and the actuators'.
  EXPECT_GE(styles.size(), 10u);
  // Each controller type keeps its style in every report: the legend entries of fig3 and fig7
  // name the type's style, whatever the order of the comparison.
  for (const char* fig : {"fig3-attitude", "fig7-fault-zoom"}) {
    const std::string script = figure_script(gp, fig);
    for (const auto& [label, style] : std::vector<std::pair<std::string, int>>{
             {"NFTSMC", tune::plot::controller_style("nftsmc", false)},
             {"FOSMC", tune::plot::controller_style("fosmc", false)},
             {"PI-FOSMC (job)", tune::plot::controller_style("pi_fosmc", false)},
             {"tuned PI-FOSMC", 1}})
      EXPECT_NE(script.find("keyentry with linespoints ls " + std::to_string(style) + " title '" +
                            label + "'"),
                std::string::npos)
          << fig << ": " << label;
  }
  EXPECT_EQ(tune::plot::controller_style("nftsmc", false), 4);
  EXPECT_EQ(tune::plot::controller_style("fosmc", false), 3);
  EXPECT_EQ(tune::plot::controller_style("pi_fosmc", false), 2);
  EXPECT_EQ(tune::plot::controller_style("pi_fosmc", true), 1);
  EXPECT_NE(tune::plot::controller_style("fosmc", false, 1), 3);  // a second FOSMC differs
  // fig7: the tuned controller is drawn first, under the others (it chatters most).
  const std::string fig7 = figure_script(gp, "fig7-fault-zoom");
  const std::size_t first_curve = fig7.find("with lines ls ");
  ASSERT_NE(first_curve, std::string::npos);
  EXPECT_EQ(fig7.substr(first_curve, 16), "with lines ls 1 ") << fig7.substr(first_curve, 40);
  // fig6: units, one legend, labelled fault lines.
  const std::string fig6_script = figure_script(gp, "fig6-inputs");
  EXPECT_NE(fig6_script.find("actuator output u [N·m]"), std::string::npos);
  EXPECT_NE(fig6_script.find("set label 'fault 1'"), std::string::npos);
  int keys_off = 0;
  for (std::size_t p = 0; (p = fig6_script.find("unset key\n", p)) != std::string::npos; ++p)
    ++keys_off;
  EXPECT_EQ(keys_off, 3);  // four panels, one legend

  // fig6: one y range for every panel, and it holds every plotted value.
  const std::string fig6 = figure_script(gp, "fig6-inputs");
  ASSERT_FALSE(fig6.empty());
  const std::size_t yr = fig6.find("set yrange [");
  ASSERT_NE(yr, std::string::npos);
  EXPECT_EQ(fig6.find("set yrange", yr + 1), std::string::npos);
  const double lo = std::stod(fig6.substr(yr + 12)),
               hi = std::stod(fig6.substr(fig6.find(':', yr) + 1));
  const json comparison = json::parse(slurp(run / "comparison.json"));
  for (const json& c : comparison["controllers"]) {
    const std::string csv = slurp(run / c["scenarios"][0]["trajectory"].get<std::string>());
    for (int col = 7; col <= 14; ++col)
      for (double u : column(csv, col)) {
        ASSERT_GE(u, lo) << c["label"] << " column " << col;
        ASSERT_LE(u, hi) << c["label"] << " column " << col;
      }
  }

  // fig5: the improvement over the job's own controller as a ratio on a log axis, round tics
  // from 0.001 % to 10 000 times, and the noise floor marked.
  const json gains = json::parse(slurp(run / "gains.json"));
  char ref[64];
  std::snprintf(ref, sizeof ref, "(($2/%.9g - 1) > 0 ?",
                gains["baseline"]["fitness"].get<double>());
  const std::string fig5 = figure_script(gp, "fig5-fitness");
  EXPECT_NE(fig5.find(ref), std::string::npos) << ref << "\n" << fig5;
  for (const char* text : {"set logscale y", "'+0.1 %%' 1e-3", "'1 000×' 999",
                           "Improvement per iteration of ISE[0 s, ",
                           "objective / best so far − 1 (log scale)", "noise floor "})
    EXPECT_NE(fig5.find(text), std::string::npos) << text << "\n" << fig5;

  // fig3: beside each angle, the distance of the three others from the tuned controller.
  const std::string fig3 = figure_script(gp, "fig3-attitude");
  for (const char* label : {"|x_1 − x_1^{tuned}|", "|x_2 − x_2^{tuned}|", "|x_3 − x_3^{tuned}|"})
    EXPECT_NE(fig3.find(label), std::string::npos) << label;
  EXPECT_NE(fig3.find("keyentry with linespoints ls 1 title 'tuned PI-FOSMC'"), std::string::npos);
}

TEST(Report, PageShowsSettingsAsATableAndTheLandscape) {
  const auto run = finished_run("report-page");
  tune::LandscapeOptions o;
  o.n1 = o.n2 = 3;
  tune::TbbEvaluator evaluator(2);
  tune::compute_landscape(tune::parse_job(short_table1_job(), "short"), run / "landscape", o,
                          evaluator);
  const std::string html = slurp(tune::render_report(run).html);
  EXPECT_NE(html.find("<h2>Landscape</h2>"), std::string::npos);
  std::size_t images = 0;
  for (std::size_t p = 0; (p = html.find("data:image/png;base64,", p)) != std::string::npos; ++p)
    ++images;
  EXPECT_EQ(images, 6u);
  for (const char* row : {"<tr><td>controller.Kp</td><td>", "<tr><td>plant.inertia</td><td>[",
                          "<tr><td>scenarios[0].faults[0].actuator</td><td>1</td></tr>"})
    EXPECT_NE(html.find(row), std::string::npos) << row;
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

// A job with goals: comparison.json, comparison.md and report.html give each goal's value per
// compared controller, its limit, violation and feasibility; the values are the goals'
// aggregates of the per-scenario metrics (one scenario here: its metrics themselves).
TEST(Report, ComparisonAndPageShowEveryGoalPerController) {
  const auto dir = fresh_dir("report-goals");
  json j = short_table1_job();
  j.erase("objective");
  j["goals"] = json::array({{{"metric", "ise"}, {"window", {0, 5}}, {"minimize", true}},
                            {{"metric", "control_tv"}, {"at_most", 1e9}},
                            {{"metric", "peak_command"}, {"at_most", 1.0}}});
  const tune::Job job = tune::parse_job(j, "goals");
  tune::TbbEvaluator evaluator(2);
  const tune::TuningOutcome r = tune::tune(job, evaluator);
  tune::write_outputs(r, dir / "run");
  const json doc = json::parse(slurp(dir / "run" / "comparison.json"));
  const std::string md = slurp(dir / "run" / "comparison.md");
  ASSERT_EQ(doc["controllers"].size(), r.comparison.size());
  EXPECT_NE(md.find("| controller | ISE[0 s, 5 s], minimized | control TV <= 1e+09 | "
                    "peak command[0 s, end] <= 1 | total violation | feasible |"),
            std::string::npos)
      << md;
  for (std::size_t c = 0; c < r.comparison.size(); ++c) {
    const sim::Metrics& m = r.comparison[c].outcome.evaluation.scenarios.at(0);
    const json& g = doc["controllers"][c]["goals"];
    ASSERT_EQ(g["goals"].size(), 3u);
    EXPECT_EQ(g["goals"][0]["value"].get<double>(), m.errors.ise);  // the window [0, 5) is the run
    EXPECT_EQ(g["goals"][1]["value"].get<double>(), m.control_tv);
    EXPECT_EQ(g["goals"][2]["value"].get<double>(), m.max_abs_u);  // the whole run's peak
    EXPECT_EQ(g["goals"][2]["at_most"].get<double>(), 1.0);
    EXPECT_EQ(g["goals"][1]["violation"].get<double>(), 0.0);
    EXPECT_EQ(g["goals"][2]["violation"].get<double>(), m.max_abs_u / 1.0 - 1.0);
    EXPECT_FALSE(g["feasible"].get<bool>());  // no gains keep every command within 1
    EXPECT_EQ(g["total_violation"].get<double>(), m.max_abs_u - 1.0);
    const std::string row = "| " + r.comparison[c].label + " | " +
                            tune::detail::format_number(m.errors.ise) + " | " +
                            tune::detail::format_number(m.control_tv) + " | " +
                            tune::detail::format_number(m.max_abs_u) + " | ";
    EXPECT_NE(md.find(row), std::string::npos) << row << "\n" << md;
  }
  const std::string html = slurp(tune::render_report(dir / "run").html);
  EXPECT_NE(html.find("<h2>Goals</h2>"), std::string::npos);
  EXPECT_NE(html.find("<th>peak command[0 s, end] &lt;= 1</th>"), std::string::npos);
  const tune::ComparedController& first = r.comparison[0];
  const std::string cells =
      "<tr><td>" + first.label + "</td><td>" +
      tune::detail::format_number(first.outcome.evaluation.scenarios[0].errors.ise) + "</td>";
  EXPECT_NE(html.find(cells), std::string::npos) << cells;
  // With the run's evaluation/, the page's evaluation section gives the goals there too.
  const tune::EvaluationResult ev = tune::evaluate_out_of_sample(job, {}, evaluator);
  tune::write_evaluation(ev, dir / "run" / "evaluation");
  const std::string with_evaluation = slurp(tune::render_report(dir / "run").html);
  const std::size_t section = with_evaluation.find("<h2>Out-of-sample evaluation</h2>");
  ASSERT_NE(section, std::string::npos);
  const std::string row = "<tr><td>" + ev.controllers[0].label + "</td><td>" +
                          tune::detail::format_number(ev.controllers[0].goals[0]) + "</td><td>" +
                          tune::detail::format_number(ev.controllers[0].goals[1]) + "</td>";
  EXPECT_NE(with_evaluation.find(row, section), std::string::npos) << row;
}

// ---- The Pareto front of a run with two or more soft goals (front.json, issue 26) ----------

namespace {

// In the file's order: the parameters' order is the table's.
nlohmann::ordered_json front_fixture() {
  return nlohmann::ordered_json::parse(
      slurp(std::string(FTC_SOURCE_DIR) + "/tests/data/front-two-goals.json"));
}

// The job a front of `front`'s goals belongs to: the shortened Table 1 job (one scenario, Kp and
// Ki tuned) with those goals.
nlohmann::json front_job_json(const nlohmann::ordered_json& front) {
  json j = short_table1_job();
  j.erase("objective");
  j["goals"] = json::parse(front["goals"].dump());
  for (json& g : j["goals"]) {
    g.erase("label");
    g.erase("unit");
  }
  return j;
}

// front.json's text read as the report reads it, against its job.
tune::Front front_of(const nlohmann::ordered_json& front) {
  return tune::front_from_json(tune::parse_job(front_job_json(front), "front job"),
                               json::parse(front.dump()), "front.json");
}

void write_text(const std::filesystem::path& p, const std::string& text) {
  std::filesystem::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

// history.csv of a front run: the hypervolume of each iteration's front.
const char* kFrontHistory =
    "iteration,best_fitness,Kp,Ki,hypervolume,evaluations\n"
    "0,1,20,1.5,1.5,10\n1,0.9,21,1.5,2.125,20\n2,0.9,21,1.5,2.375,30\n";

// Adds a hypervolume column to a run's history.csv (a one-goal run has none), rising by 0.25.
void add_hypervolume_column(const std::filesystem::path& history) {
  std::stringstream in(slurp(history));
  std::string line, out;
  std::getline(in, line);
  out = line + ",hypervolume\n";
  for (int k = 0; std::getline(in, line); ++k)
    out += line + "," + tune::detail::format_number(1 + 0.25 * k, "%g") + "\n";
  write_text(history, out);
}

// Makes a finished run a run of the fixture's front: its front.json (with the run's job sha256),
// the front's job (the run's, with the fixture's goals) and a hypervolume column. Returns the
// front.json written.
nlohmann::ordered_json give_front(const std::filesystem::path& run) {
  const json gains = json::parse(slurp(run / "gains.json"));
  nlohmann::ordered_json j = front_fixture();
  j["job_sha256"] = gains["job"]["sha256"].get<std::string>();
  write_text(run / "front.json", j.dump(2));
  write_text(run / "job.json", front_job_json(j).dump(2));
  add_hypervolume_column(run / "history.csv");
  return j;
}

}  // namespace

// The scatter marks the front, its noise bands, the picked point, the job's gains and the
// compared controllers, each where front.json puts it, on log axes labelled with the goals'
// labels and units as front.json words them (metric, window, aggregate: here of a run of 7
// scenarios); the hypervolume figure states its reference point.
TEST(FrontReport, ScatterMarksPickedBaselineComparedAndNoiseAndHypervolumeStatesItsReference) {
  const auto dir = fresh_dir("front-figures");
  nlohmann::ordered_json j = front_fixture();
  j["goals"][0]["label"] = "CVaR0.9 of ISE[first fault, +4 s] over 7 scenarios";
  j["goals"][1]["label"] = "quantile0.5 of control TV over 7 scenarios";
  const tune::Front front = front_of(j);
  write_text(dir / "history.csv", kFrontHistory);
  std::filesystem::create_directories(dir / "figures");
  const auto figures = tune::report_detail::draw_front_figures(dir, front, tune::FigureFormat::png);
  ASSERT_EQ(figures.size(), 2u);
  EXPECT_EQ(figures[0].file, "figures/front-pareto.png");
  EXPECT_EQ(figures[1].file, "figures/front-hypervolume.png");
  for (const auto& f : figures) {
    EXPECT_TRUE(tune::figure_is_whole(dir / f.file)) << f.file;
    EXPECT_GT(std::filesystem::file_size(dir / f.file), 10000u) << f.file;
  }
  const std::string gp = slurp(dir / "figures" / "front.gp");
  // One panel for two soft goals; the hard goal (peak command) is no axis.
  EXPECT_NE(gp.find("set multiplot layout 1,1"), std::string::npos);
  EXPECT_NE(gp.find("set logscale x\n"), std::string::npos);
  EXPECT_NE(gp.find("set logscale y\n"), std::string::npos);
  EXPECT_NE(gp.find("set xlabel 'CVaR0.9 of ISE[first fault, +4 s] over 7 scenarios [rad²·s]'"),
            std::string::npos);
  EXPECT_NE(gp.find("set ylabel 'quantile0.5 of control TV over 7 scenarios [command''s unit]'"),
            std::string::npos);
  EXPECT_EQ(gp.find("peak command"), std::string::npos);
  // The marked points, where front.json has them: picked #2 (0.5, 2500), Table 1 (3.5, 1200),
  // the job's gains (1.5, 5000) marked infeasible.
  EXPECT_NE(gp.find("set label 'picked' at 0.5,2500"), std::string::npos);
  EXPECT_NE(gp.find("'picked (knee), #2'"), std::string::npos);
  EXPECT_NE(gp.find("set label 'Table 1' at 3.5,1200"), std::string::npos);
  EXPECT_NE(gp.find("set label 'job''s gains: PI-FOSMC (job) (infeasible)' at 1.5,5000"),
            std::string::npos);
  // The front's points, and the noise band of #3: ISE 2·(1 ± 0.03), TV 1077·(1 ± 0.005).
  for (const char* row : {"0.125,9000\n", "0.13,8950\n", "8,400\n",
                          "2,1077,1.94,2.06,1071.615,1082.385\n", "8,400,8,8,400,400\n"})
    EXPECT_NE(gp.find(row), std::string::npos) << row;
  // #0 and #1 are partners in front.json (within each other's floor on both soft goals): linked.
  EXPECT_NE(gp.find("0.125,9000\n0.13,8950\n\n"), std::string::npos);
  EXPECT_NE(gp.find("not a trade-off"), std::string::npos);
  EXPECT_NE(figures[0].caption.find("not a proven optimum"), std::string::npos);
  // The hypervolume per iteration, and the reference point in its title and caption.
  EXPECT_NE(gp.find("0,1.5\n1,2.125\n2,2.375\n"), std::string::npos);
  EXPECT_NE(gp.find("reference point (1.25, 4.5) in log10 of the soft goals"), std::string::npos);
  EXPECT_NE(figures[1].caption.find("CVaR0.9 of ISE[first fault, +4 s] over 7 scenarios = 10^1.25"),
            std::string::npos)
      << figures[1].caption;
  EXPECT_NE(figures[1].caption.find("Final front: 2.375."), std::string::npos);
}

// Three soft goals: a panel per pair. A goal with a zero value gets a linear axis. The links are
// front.json's partners, whatever the floors say; a front.json without labels (written before
// them) is labelled with the job's words.
TEST(FrontReport, PanelPerPairOfSoftGoalsAndLinearAxisForZeroValues) {
  const auto dir = fresh_dir("front-pairs");
  nlohmann::ordered_json j = front_fixture();
  j["goals"].push_back({{"metric", "saturation_fraction"},
                        {"window", {0, nullptr}},
                        {"aggregate", "mean"},
                        {"minimize", true}});
  for (auto& g : j["goals"]) {
    g.erase("label");
    g.erase("unit");
  }
  j["reference_point"].push_back(0.5);
  double v = 0;
  for (auto& p : j["points"]) {
    p["goals"].push_back(v);
    p["noise_floor"].push_back(nullptr);
    v += 0.125;
  }
  for (auto& c : j["compared"]) c["goals"].push_back(0.25);
  j["compared"][0]["goals"][0] = 1000;  // ISE more than a decade beyond the front's 0.125..8
  // The run's verdict that #3 and #4 are no trade-off, and none for #0 and #1.
  j["points"][3]["within_noise"] = {4};
  j["points"][4]["within_noise"] = {3};
  j["points"][0]["within_noise"] = nlohmann::ordered_json::array();
  j["points"][1]["within_noise"] = nlohmann::ordered_json::array();
  const tune::Front front = front_of(j);
  ASSERT_EQ(front.soft, (std::vector<std::size_t>{0, 1, 3}));
  write_text(dir / "history.csv", kFrontHistory);
  const auto figures = tune::report_detail::draw_front_figures(dir, front, tune::FigureFormat::svg);
  EXPECT_TRUE(tune::figure_is_whole(dir / "figures/front-pareto.svg"));
  const std::string gp = slurp(dir / "figures" / "front.gp");
  EXPECT_NE(gp.find("set multiplot layout 1,3"), std::string::npos);
  EXPECT_NE(gp.find("2,1077\n8,400\n\n"), std::string::npos);          // #3 and #4 linked
  EXPECT_EQ(gp.find("0.125,9000\n0.13,8950\n\n"), std::string::npos);  // #0 and #1 not
  // Table 1 off the ISE axis: at its right edge, labelled with its values.
  EXPECT_NE(gp.find("set label 'Table 1 (off scale: 1000, 1200)' at "), std::string::npos) << gp;
  EXPECT_NE(gp.find("set label 'Table 1 (off scale: 1000, 0.25)' at "), std::string::npos);
  EXPECT_NE(gp.find("set label 'Table 1' at 1200,0.25"), std::string::npos);  // TV vs saturation
  // One scenario: no aggregate in the labels.
  EXPECT_NE(gp.find("set xlabel 'ISE[first fault, +4 s] [rad²·s]'"), std::string::npos);
  EXPECT_NE(gp.find("set ylabel 'saturation fraction[0 s, end] [1]'"), std::string::npos);
  EXPECT_NE(gp.find("unset logscale y\n"), std::string::npos);
  EXPECT_NE(gp.find("reference point (1.25, 4.5, 0.5)"), std::string::npos);
}

// Two compared controllers far off the scale at one edge, their values close: their labels, each
// on its marker's row beside the edge, would print one over the other (docs/figures/robust-pareto-
// front.png did); they are set a row apart or more, in their markers' order, the upper one's
// above. A label with room keeps its place.
TEST(FrontReport, LabelsOfNearbyControllersAreSetApartInTheirMarkersOrder) {
  const auto dir = fresh_dir("front-labels");
  nlohmann::ordered_json j = front_fixture();
  j["compared"][0]["goals"] = {1000, 1090, 12};    // ISE far right of the front's 0.125..8
  j["compared"][1]["goals"] = {500, 1018, 19.25};  // TV 7 % lower: a third of a row on the axis
  const tune::Front front = front_of(j);
  write_text(dir / "history.csv", kFrontHistory);
  tune::report_detail::draw_front_figures(dir, front, tune::FigureFormat::svg);
  std::string gp = slurp(dir / "figures" / "front.gp");
  // A label's line of the script, "set label 'TEXT' at X,Y [right ]offset DX,ROWS ...", and its
  // vertical offset in rows.
  const auto line_of = [&](const std::string& text) {
    const std::size_t at = gp.find("set label '" + text + "' at ");
    EXPECT_NE(at, std::string::npos) << text << "\n" << gp;
    return at == std::string::npos ? std::string() : gp.substr(at, gp.find('\n', at) - at);
  };
  const auto rows_of = [&](const std::string& text) -> double {
    const std::string line = line_of(text);
    return line.empty() ? NAN : std::stod(line.substr(line.rfind(',') + 1));
  };
  const std::string table1 = "Table 1 (off scale: 1000, 1090)",
                    job = "job''s gains: PI-FOSMC (job) (infeasible) (off scale: 500, 1018)";
  for (const std::string& text : {table1, job})
    EXPECT_NE(line_of(text).find(" right offset -1,"), std::string::npos) << text;
  const double upper = rows_of(table1), lower = rows_of(job);
  EXPECT_EQ(upper, 0) << gp;  // on its marker's row, as nothing is in its way
  EXPECT_LE(lower, upper - 1) << gp;
  // The picked point's label is where it always is.
  EXPECT_NE(gp.find("set label 'picked' at 0.5,2500 offset 1.6,-1.2"), std::string::npos);
  // Two inside the scale, close together: the upper marker's label stays above the lower's.
  j["compared"][0]["goals"] = {1.0, 1200, 12};
  j["compared"][1]["goals"] = {1.05, 1150, 19.25};
  tune::report_detail::draw_front_figures(dir, front_of(j), tune::FigureFormat::svg);
  gp = slurp(dir / "figures" / "front.gp");
  // 1200 and 1150 are a fifth of a row apart on this axis: the lower label a row below.
  EXPECT_LE(rows_of("job''s gains: PI-FOSMC (job) (infeasible)"), rows_of("Table 1") - 1) << gp;
  // Off the top near the right edge: the label's text would run past the edge, so it ends at
  // its marker instead of starting there.
  j["compared"][0]["goals"] = {6, 1e6, 12};
  tune::report_detail::draw_front_figures(dir, front_of(j), tune::FigureFormat::svg);
  gp = slurp(dir / "figures" / "front.gp");
  EXPECT_NE(line_of("Table 1 (off scale: 6, 1e+06)").find(" right offset -1,"), std::string::npos);
}

// A held-out front (`evaluate --front`) is drawn with each point where the run put it and where
// the held-out members put it, joined by a line; the points that drop off the held-out front are
// drawn apart, the held-out knee ringed, and the title counts the points that stay (issue 42).
TEST(FrontReport, HeldOutFigureJoinsEachPointInSampleToHeldOut) {
  const auto dir = fresh_dir("front-held-out");
  tune::Front front = front_of(front_fixture());
  EXPECT_TRUE(tune::draw_held_out_front(front, dir).empty());  // not a held-out front
  front.held_out = tune::FrontHeldOut{"run", 8, 100, 2.375};
  for (tune::FrontPoint& p : front.points) {
    p.in_sample = p.goals;
    for (double& v : p.goals) v *= 2;
  }
  front.points[4].dominated = true;
  const std::filesystem::path figure =
      tune::draw_held_out_front(front, dir, tune::FigureFormat::svg);
  EXPECT_EQ(figure, dir / "front-held-out.svg");
  EXPECT_TRUE(tune::figure_is_whole(figure));
  const std::string gp = slurp(dir / "front-held-out.gp");
  EXPECT_NE(gp.find("on 100 held-out members (seed 8): 4 of 5 points stay on it"),
            std::string::npos)
      << gp;
  EXPECT_NE(gp.find("0.125,9000\n0.25,18000\n\n"), std::string::npos);  // point 0's link
  EXPECT_NE(gp.find("8,400\n16,800\n\n"), std::string::npos);           // point 4's
  // Point 4 off the held-out front: its held-out mark alone in the crosses' block.
  const std::size_t crosses = gp.find("'held out, off the front (dominated or infeasible)'");
  ASSERT_NE(crosses, std::string::npos);
  EXPECT_NE(gp.find("EOD\n$d4 << EOD\n16,800\nEOD\n"), std::string::npos) << gp;
  EXPECT_NE(gp.find("'held-out knee, #2'"), std::string::npos);
  EXPECT_NE(gp.find("'Table 1, held out'"), std::string::npos);
}

// evaluate --front's held-out front in the run's evaluation/ is shown on the page: each point's
// soft goals in sample and held out, their ratio beside the point's noise floor, whether it stays
// on the held-out front, and the held-out knee (issue 42).
TEST(FrontReport, PageShowsTheHeldOutFrontBesideTheRunsValues) {
  const auto run = finished_run("front-held-out-html");
  const nlohmann::ordered_json j = give_front(run);
  EXPECT_EQ(slurp(tune::render_report(run).html).find("The front held out"), std::string::npos);
  nlohmann::ordered_json held = j;
  held["held_out"] = {
      {"run", run.string()}, {"seed", 8}, {"count", 100}, {"in_sample_hypervolume", 2.375}};
  for (auto& p : held["points"]) {
    p["in_sample"] = p["goals"];
    for (auto& v : p["goals"]) v = v.get<double>() * 2;
    p["dominated"] = false;
  }
  held["points"][4]["dominated"] = true;
  write_text(run / "evaluation" / "front.json", held.dump(2));
  const std::string html = slurp(tune::render_report(run).html);
  for (const char* text :
       {"<h3>The front held out</h3>", "on 100 held-out members (seed 8); 4 stay on the front",
        "in sample 2.375, against the run's reference point. The held-out knee is point 2.",
        "<tr class=\"picked\"><td>2 ★</td><td class=\"note\">on the front (knee)</td>"
        "<td>0.5</td><td>1</td><td>2× (5 %)</td><td>2500</td><td>5000</td><td>2× (1 %)</td></tr>",
        "<td>4</td><td class=\"note\">off the front</td><td>8</td><td>16</td><td>2×</td>"})
    EXPECT_NE(html.find(text), std::string::npos) << text;
  // Another job's held-out front is not this run's.
  held["job_sha256"] = std::string(64, '0');
  write_text(run / "evaluation" / "front.json", held.dump(2));
  EXPECT_EQ(slurp(tune::render_report(run).html).find("The front held out"), std::string::npos);
}

// A front of another job (stale beside a re-run) is not this run's; a damaged front.json is
// refused by `report` at its JSON path (front_from_json's checks: test_front.cpp); a front without
// its history column is an error, not an empty plot.
TEST(FrontReport, BadOrStaleFrontsAreRefusedAtTheirPaths) {
  const auto dir = fresh_dir("front-stale");
  nlohmann::ordered_json j = front_fixture();
  j["job_sha256"] = "abc";
  write_text(dir / "front.json", j.dump());
  const tune::Job job = tune::parse_job(front_job_json(j), "front job");
  EXPECT_FALSE(tune::read_front(dir, job, std::string("def")));
  ASSERT_TRUE(tune::read_front(dir, job, std::string("abc")));
  j["picked"]["index"] = 5;
  write_text(dir / "front.json", j.dump());
  try {
    tune::read_front(dir, job, std::string("abc"));
    ADD_FAILURE() << "a picked point the front does not have was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.source(), (dir / "front.json").string());
    ASSERT_FALSE(e.errors().empty());
    EXPECT_EQ(e.errors()[0].path, "/picked/index");
  }
  write_text(dir / "history.csv", "iteration,best_fitness,evaluations\n0,1,10\n");
  const tune::Front front = front_of(front_fixture());
  EXPECT_THROW(tune::report_detail::draw_front_figures(dir, front, tune::FigureFormat::png),
               InputError);
  EXPECT_FALSE(std::filesystem::exists(dir / "figures" / "front-pareto.png"));
}

// report.html of a run with a front: the front's table (parameters, goals, feasibility, noise
// floor; the picked point marked, twins within the noise floor said to be so, compared rows)
// and both figures; `ftctune report` draws the same. A run without one shows neither.
TEST(FrontReport, PageHoldsTheFrontTableAndBothFigures) {
  const auto run = finished_run("front-html");
  std::string html = slurp(tune::render_report(run).html);
  EXPECT_EQ(html.find("Pareto front"), std::string::npos);
  give_front(run);
  const tune::ReportResult r = tune::render_report(run);
  EXPECT_EQ(r.figures.size(), 7u);
  EXPECT_TRUE(tune::figure_is_whole(run / "figures" / "front-pareto.png"));
  EXPECT_TRUE(tune::figure_is_whole(run / "figures" / "front-hypervolume.png"));
  html = slurp(r.html);
  std::size_t images = 0;
  for (std::size_t p = 0; (p = html.find("data:image/png;base64,", p)) != std::string::npos; ++p)
    ++images;
  EXPECT_EQ(images, 7u);
  for (const char* text :
       {"<h2>Pareto front</h2>", "not a proven optimum", "alt=\"Pareto front\"",
        "alt=\"Hypervolume\"", "reference point (1.25, 4.5), is 2.375",
        "gains.json holds point #2, picked by the rule <code>knee</code>",
        "<li>ISE[first fault, +4 s] [rad²·s], minimized</li>",
        "<li>peak command[0 s, end] [command's unit] ≤ 17.9</li></ol>",
        "<th>#</th><th>note</th><th>Kp</th><th>Ki</th>"
        "<th title=\"ISE[first fault, +4 s]\">goal 1 (min)</th>",
        "<th title=\"peak command[0 s, end]\">goal 3 ≤ 17.9</th><th title=\"yes, or no with the "
        "total violation of the hard goals\">feasible</th><th title=\"the noise floor of goal 1\">",
        "<th title=\"the noise floor of goal 3\">floor 3</th><th>trial</th></tr>",
        "<tr class=\"picked\"><td>2 ★</td><td class=\"note\">picked (knee)</td><td>20</td>"
        "<td>1.5</td><td>0.5</td><td>2500</td><td>15</td><td>yes</td><td>5 %</td>"
        "<td>1 %</td><td>–</td><td>5</td></tr>",
        "<td class=\"note\">within the noise floor of #1</td>",
        "<td class=\"note\">within the noise floor of #0</td>",
        "2 point(s) differ from another by no more than the noise floor of one of the two on "
        "every soft goal",
        "<tr class=\"compared\"><td>Table 1</td>", "<td>PI-FOSMC (job) (job's gains)</td>"})
    EXPECT_NE(html.find(text), std::string::npos) << text;
  EXPECT_EQ(html.find("optimal"), std::string::npos);
  // The command draws it too.
  std::filesystem::remove(run / "figures" / "front-pareto.png");
  const CliResult cli = run_cli("report '" + run.string() + "'", run.parent_path());
  EXPECT_EQ(cli.exit_code, 0) << cli.err;
  EXPECT_TRUE(tune::figure_is_whole(run / "figures" / "front-pareto.png"));
}

// A real run with two soft goals (ISE and control TV) and a hard goal: `ftctune report` draws its
// front.json, marking the point gains.json holds and every compared controller where the run put
// them.
TEST(FrontReport, RunWithTwoSoftGoalsGetsItsFrontDrawn) {
  const auto dir = fresh_dir("front-run");
  json j = short_table1_job();
  j.erase("objective");
  j["goals"] = {{{"metric", "ise"}, {"window", {2, 5}}, {"minimize", true}},
                {{"metric", "control_tv"}, {"minimize", true}},
                {{"metric", "peak_command"}, {"at_most", 1e6}}};
  j["tuning"]["algorithm"] = {
      {"type", "pagmo"}, {"name", "nsga2"}, {"population", 8}, {"generations", 2}};
  tune::TbbEvaluator evaluator(2);
  tune::write_outputs(tune::tune(tune::parse_job(j, "front"), evaluator), dir / "run");
  const tune::ReportResult r = tune::render_report(dir / "run");
  EXPECT_TRUE(tune::figure_is_whole(dir / "run" / "figures" / "front-pareto.png"));
  EXPECT_TRUE(tune::figure_is_whole(dir / "run" / "figures" / "front-hypervolume.png"));
  const json front = json::parse(slurp(dir / "run" / "front.json"));
  const std::string gp = slurp(dir / "run" / "figures" / "front.gp");
  const json& picked = front["points"][front["picked"]["index"].get<std::size_t>()];
  const auto at = [](const json& goals) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.9g,%.9g", goals[0].get<double>(), goals[1].get<double>());
    return std::string(buf);
  };
  EXPECT_NE(gp.find("set label 'picked' at " + at(picked["goals"])), std::string::npos) << gp;
  ASSERT_FALSE(front["compared"].empty());
  // Each compared controller where the run put it, or at the edge with its values when it lies
  // more than a decade off the front.
  for (const json& c : front["compared"])
    EXPECT_TRUE(gp.find(" at " + at(c["goals"]) + " offset") != std::string::npos ||
                gp.find(c["label"].get<std::string>() + " (off scale: ") != std::string::npos)
        << c.dump();
  const std::string html = slurp(r.html);
  EXPECT_NE(html.find("<h2>Pareto front</h2>"), std::string::npos);
  EXPECT_NE(html.find("<tr class=\"picked\"><td>" + front["picked"]["index"].dump() + " ★"),
            std::string::npos);
}
