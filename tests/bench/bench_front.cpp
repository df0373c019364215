// Front quality (issue 26, "Must hold"): on jobs/post-fault.json with Kp in [1, 50] and the
// switching gain in [2, 200] (log scale), goals ISE over [10, 30] s and control TV, the front the
// Pareto Bat algorithm finds with 200 evaluations against the front of a 41 x 41 grid of the same
// job (1 681 simulations; Kp linear, the switching gain log-spaced), and, for scale, fronts of
// 200 points drawn at random from that grid. Hypervolume on log10 of each goal against the
// reference point 0.1 decade beyond the grid front's worst value of each goal.
//
//   build/tests/ftc_bench_front [threads] [seeds] [at_least]
//                                  (default: all hardware threads, 5 seeds, no check)
//
// Prints each hypervolume and its ratio to the grid's; with at_least (a percentage), exits 1
// when a seed's ratio is below it (ctest: Bench.ParetoBatFrontKeeps99PercentOfTheGridsHypervolume). Not a Google Benchmark: it measures
// quality, not time.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/optimizers/hypervolume.hpp"
#include "ftc/tune/problem/problem.hpp"
#include "ftc/tune/run/front.hpp"
#include "ftc/tune/run/tuning_run.hpp"

using namespace ftc;
using nlohmann::json;

namespace {

json bench_job(int population, int iterations, std::uint64_t seed) {
  json j = to_json(tune::load_job(std::string(FTC_SOURCE_DIR) + "/jobs/post-fault.json"));
  j.erase("objective");
  j["name"] = "post-fault-front";
  j["goals"] = {{{"metric", "ise"}, {"window", {10, 30}}, {"minimize", true}},
                {{"metric", "control_tv"}, {"minimize", true}}};
  j["tuning"]["parameters"] = {{"Kp", {1, 50}},
                               {"switching_gain", {{"bounds", {2, 200}}, {"scale", "log"}}}};
  j["tuning"]["algorithm"]["population"] = population;
  j["tuning"]["algorithm"]["iterations"] = iterations;
  j["tuning"]["seed"] = seed;
  j["compare"] = json::array();
  return j;
}

// log10 (ISE, TV) of the front of a set of trials.
std::vector<std::vector<double>> front_points(const tune::Job& job,
                                              const std::vector<tune::Trial>& trials) {
  std::vector<std::vector<double>> p;
  for (std::size_t i : tune::front_trials(job, trials, trials.size()))
    p.push_back(tune::log_soft_goals(trials[i].goals, {0, 1}));
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  const int threads = argc > 1 ? std::atoi(argv[1]) : 0;
  const int seeds = argc > 2 ? std::atoi(argv[2]) : 5;
  // A third argument makes it a check (ctest): exit 1 when a seed's front has less than that
  // percentage of the grid's hypervolume.
  const double at_least = argc > 3 ? std::atof(argv[3]) : 0.0;
  tune::TbbEvaluator evaluator(threads);

  // The grid: 41 x 41, Kp linear in [1, 50], the switching gain log-spaced in [2, 200].
  const tune::Job job = tune::parse_job(bench_job(10, 19, 1), "bench");
  const tune::TuningProblem problem(job);
  std::vector<std::vector<double>> grid_params;
  std::vector<sim::ControllerConfig> controllers;
  for (int a = 0; a <= 40; ++a)
    for (int b = 0; b <= 40; ++b) {
      const double kp = 1.0 + 49.0 * a / 40.0;
      const double k = 2.0 * std::pow(100.0, b / 40.0);
      grid_params.push_back({kp, std::min(k, 200.0)});
    }
  std::vector<tune::Trial> grid;
  for (const auto& x : grid_params) controllers.push_back(problem.controller_with(x));
  const std::vector<tune::CandidateOutcome> out = problem.evaluate(controllers, evaluator);
  for (std::size_t i = 0; i < out.size(); ++i) {
    tune::Trial t;
    t.parameters = grid_params[i];
    t.goals = out[i].evaluation.goals;
    t.violation = out[i].evaluation.violation;
    grid.push_back(std::move(t));
  }
  const std::vector<std::vector<double>> grid_front = front_points(job, grid);
  const std::vector<double> ref = tune::reference_point(grid_front);
  const double hv_grid = tune::hypervolume(grid_front, ref);
  std::printf("grid 41x41 (1681 simulations): front of %zu points, reference (log10 ISE, log10 TV) "
              "= (%.4f, %.4f), hypervolume %.6f\n",
              grid_front.size(), ref[0], ref[1], hv_grid);

  double lo = 1e9, hi = -1e9, sum = 0;
  for (int s = 1; s <= seeds; ++s) {
    const tune::Job j = tune::parse_job(bench_job(10, 19, static_cast<std::uint64_t>(s)), "bench");
    tune::RunOptions o;
    o.compare = false;
    const tune::TuningOutcome r = tune::tune(j, evaluator, o);
    const double hv = tune::hypervolume(front_points(j, r.trials), ref);
    lo = std::min(lo, hv / hv_grid);
    hi = std::max(hi, hv / hv_grid);
    sum += hv / hv_grid;
    std::printf("pareto bat, seed %d (%lld evaluations): front of %zu points, hypervolume %.6f, "
                "ratio %.2f %%\n",
                s, static_cast<long long>(r.optimization.evaluations),
                front_trials(j, r.trials, r.trials.size()).size(), hv, 100 * hv / hv_grid);
  }
  std::printf("pareto bat: ratio %.2f-%.2f %% (mean %.2f %%) over %d seeds\n", 100 * lo, 100 * hi,
              100 * sum / seeds, seeds);
  if (argc > 3) {
    const bool holds = seeds > 0 && 100 * lo >= at_least;
    std::printf("%s: the least ratio %.2f %% is %s %.2f %%\n", holds ? "ok" : "FAILED", 100 * lo,
                holds ? "at least" : "below", at_least);
    return holds ? 0 : 1;
  }

  // For scale: 200 grid points drawn at random (without replacement), many draws.
  std::mt19937_64 rng(12345);
  double rlo = 1e9, rhi = -1e9, rsum = 0;
  const int draws = 100;
  for (int d = 0; d < draws; ++d) {
    std::vector<std::size_t> idx(grid.size());
    for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = i;
    std::shuffle(idx.begin(), idx.end(), rng);
    std::vector<tune::Trial> sample;
    for (std::size_t i = 0; i < 200; ++i) sample.push_back(grid[idx[i]]);
    const double ratio = tune::hypervolume(front_points(job, sample), ref) / hv_grid;
    rlo = std::min(rlo, ratio);
    rhi = std::max(rhi, ratio);
    rsum += ratio;
  }
  std::printf("200 random grid points: ratio %.2f-%.2f %% (mean %.2f %%) over %d draws\n",
              100 * rlo, 100 * rhi, 100 * rsum / draws, draws);
  return 0;
}
