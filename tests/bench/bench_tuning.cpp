// Whole tuning runs in process (what `ftctune run` does minus file output).
//   BM_TuneTable1/threads:N      the Table 1 job, 110 evaluations + 4 comparison runs
//   BM_TuneScaling/M/T/S         population M, iterations T, S copies of the scenario, 2 threads
// max_rss_MiB is the process high-water mark after the case: run small to large, it stays flat
// when memory does not grow with the job.
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <cmath>
#include <cstdio>
#include <span>
#include <string>

#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/tuning_run.hpp"

using namespace ftc;

namespace {

tune::Job table1() { return tune::load_job(std::string(FTC_SOURCE_DIR) + "/jobs/table1.json"); }

double max_rss_mib() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<double>(ru.ru_maxrss) / 1024.0;
}

void BM_TuneTable1(benchmark::State& state) {
  const tune::Job job = table1();
  tune::TbbEvaluator evaluator(static_cast<int>(state.range(0)));
  double J = 0;
  for (auto _ : state) J += tune::tune(job, evaluator).optimization.best_fitness;
  benchmark::DoNotOptimize(J);
  state.counters["max_rss_MiB"] = max_rss_mib();
}
BENCHMARK(BM_TuneTable1)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);

void BM_TuneScaling(benchmark::State& state) {
  tune::Job job = table1();
  job.compare.clear();
  job.tuning->algorithm = tune::make_algorithm(
      {{"type", "bat"}, {"population", state.range(0)}, {"iterations", state.range(1)}});
  const sim::Scenario base = job.scenarios.front();
  job.scenarios.clear();
  for (int s = 0; s < state.range(2); ++s) {
    job.scenarios.push_back(base);
    job.scenarios.back().name = "copy" + std::to_string(s);
  }
  tune::TbbEvaluator evaluator(2);
  double J = 0;
  for (auto _ : state) J += tune::tune(job, evaluator).optimization.best_fitness;
  benchmark::DoNotOptimize(J);
  const double sims = static_cast<double>(job.tuning->algorithm->evaluations() + 2) *
                      static_cast<double>(job.scenarios.size());
  state.counters["simulations"] = sims;
  // Seconds of wall time per simulation (shown with a unit prefix, e.g. 8.6m = 8.6 ms).
  state.counters["s_per_simulation"] = benchmark::Counter(
      sims, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["max_rss_MiB"] = max_rss_mib();
}
BENCHMARK(BM_TuneScaling)
    ->ArgNames({"M", "T", "S"})
    ->Args({10, 10, 1})
    ->Args({20, 10, 1})
    ->Args({40, 10, 1})
    ->Args({10, 20, 1})
    ->Args({10, 40, 1})
    ->Args({10, 10, 2})
    ->Args({10, 10, 4})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace

// Writing a recorded trajectory as CSV: 30 000 rows of the spacecraft (t, 6 states, 4 + 4
// actuator values), as `simulate --record-every 0.001` writes. The printf version is the one
// trajectory_csv replaced, kept here as the yardstick (io/decimal.cpp prints the same bytes).
ftc::sim::Trajectory sample_trajectory() {
  ftc::sim::Trajectory tr;
  tr.axes = 3;
  tr.actuators = 4;
  for (int k = 0; k < 30000; ++k) {
    const double t = 0.001 * k;
    tr.values.push_back(t);
    for (int i = 0; i < 14; ++i) tr.values.push_back(std::sin(0.37 * i + t) * std::exp(-0.1 * t));
  }
  return tr;
}

std::string printf_csv(const ftc::sim::Trajectory& tr) {
  std::string s;
  char buf[64];
  for (std::size_t r = 0; r < tr.rows(); ++r) {
    const std::span<const double> row = tr.row(r);
    std::snprintf(buf, sizeof buf, "%.6f", row[0]);
    s += buf;
    for (std::size_t i = 1; i < row.size(); ++i) {
      std::snprintf(buf, sizeof buf, ",%.9g", row[i]);
      s += buf;
    }
    s += '\n';
  }
  return s;
}

void BM_TrajectoryCsv(benchmark::State& state) {
  const ftc::sim::Trajectory tr = sample_trajectory();
  for (auto _ : state) benchmark::DoNotOptimize(ftc::tune::trajectory_csv(tr));
}
BENCHMARK(BM_TrajectoryCsv)->Unit(benchmark::kMillisecond);

void BM_TrajectoryCsvPrintf(benchmark::State& state) {
  const ftc::sim::Trajectory tr = sample_trajectory();
  for (auto _ : state) benchmark::DoNotOptimize(printf_csv(tr));
}
BENCHMARK(BM_TrajectoryCsvPrintf)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
