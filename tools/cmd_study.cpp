// ftctune study JOB: the job's tuning with several algorithms and seeds at one budget of
// evaluations, so that algorithms are compared at equal cost. Writes study.csv (one row per run),
// study.md (per algorithm: median, best and worst objective, parameters ended on a bound,
// median wall time) and study.png.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>

#include "cli.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/optimizers/pagmo.hpp"
#include "ftc/tune/report/study.hpp"
#include "ftc/tune/run/memory_budget.hpp"

#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/tuning_run.hpp"

namespace ftc::cli {
namespace {

using nlohmann::json;

struct StudyCli {
  std::string job;
  std::string algorithms;
  std::string seeds;
  std::int64_t budget = 0;
  int threads = 0;
  std::string out;
};

// A parameter "on a bound" ended within this fraction of its range from the bound: the optimum
// may lie outside the range the job gives.
constexpr double kOnBound = 0.001;

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> parts;
  std::size_t i = 0;
  while (true) {
    const std::size_t j = std::min(s.find(',', i), s.size());
    parts.push_back(s.substr(i, j - i));
    if (j == s.size()) return parts;
    i = j + 1;
  }
}

std::string known_algorithms() {
  std::string s = "bat, random";
  for (const tune::PagmoAlgorithmInfo& a : tune::pagmo_algorithms()) s += ", pagmo:" + a.name;
  return s;
}

// "bat,random,pagmo:cmaes": the names, each known and given once.
std::vector<std::string> parse_algorithm_list(const std::string& text) {
  std::vector<FieldError> errs;
  std::vector<std::string> names;
  if (text.empty())
    throw InputError("--algorithms", "", "is empty (known: " + known_algorithms() + ")");
  for (const std::string& n : split(text)) {
    const bool known = n == "bat" || n == "random" ||
                       (n.rfind("pagmo:", 0) == 0 && tune::find_pagmo_algorithm(n.substr(6)));
    if (!known)
      errs.push_back({"", "unknown algorithm \"" + n + "\" (known: " + known_algorithms() + ")"});
    else if (std::find(names.begin(), names.end(), n) != names.end())
      errs.push_back({"", "\"" + n + "\" is given twice"});
    else
      names.push_back(n);
  }
  throw_if_errors("--algorithms", std::move(errs));
  return names;
}

// At most this many seeds in all, over every range.
constexpr std::uint64_t kMaxSeeds = 100000;

// "1-10", "1,3,5", "1-3,7": the seeds in the order given, each once. The ranges are checked as
// ranges (their total against kMaxSeeds, their overlaps after sorting) before any is expanded,
// so `1-10000000` is refused at once rather than after filling memory.
std::vector<std::uint64_t> parse_seeds(const std::string& text) {
  const auto number = [&](const std::string& s, std::uint64_t& v) {
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    return !s.empty() && ec == std::errc() && end == s.data() + s.size();
  };
  std::vector<FieldError> errs;
  if (text.empty()) throw InputError("--seeds", "", "is empty (e.g. 1-10 or 1,3,5)");
  std::vector<std::pair<std::uint64_t, std::uint64_t>> ranges;  // [lo, hi], in the order given
  std::uint64_t total = 0;
  for (const std::string& part : split(text)) {
    const std::size_t dash = part.find('-');
    std::uint64_t lo = 0, hi = 0;
    const bool ok = dash == std::string::npos
                        ? number(part, lo) && number(part, hi)
                        : number(part.substr(0, dash), lo) && number(part.substr(dash + 1), hi);
    if (!ok) {
      errs.push_back({"", "\"" + part + "\" is not a seed or a range of seeds like 1-10"});
      continue;
    }
    if (hi < lo) {
      errs.push_back({"", "range \"" + part + "\" runs backwards"});
      continue;
    }
    // hi - lo + 1 without overflow: a range past the cap counts as the cap plus one.
    total += std::min(hi - lo, kMaxSeeds) + 1;
    if (total > kMaxSeeds) {
      errs.push_back({"", "gives more than " + std::to_string(kMaxSeeds) +
                              " seeds in all (a study runs every algorithm once per seed)"});
      throw_if_errors("--seeds", std::move(errs));
    }
    ranges.emplace_back(lo, hi);
  }
  throw_if_errors("--seeds", std::move(errs));
  std::vector<std::pair<std::uint64_t, std::uint64_t>> sorted = ranges;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 1; i < sorted.size(); ++i)
    if (sorted[i].first <= sorted[i - 1].second)
      throw InputError("--seeds", "",
                       "seed " + std::to_string(sorted[i].first) + " is given twice");
  std::vector<std::uint64_t> seeds;
  seeds.reserve(static_cast<std::size_t>(total));
  for (const auto& [lo, hi] : ranges)
    for (std::uint64_t s = lo;; ++s) {
      seeds.push_back(s);
      if (s == hi) break;
    }
  return seeds;
}

// The algorithm `name` sized to `budget` evaluations: the job's own settings when it names the
// same algorithm, else the defaults with the job's population (or the smallest the algorithm
// takes).
tune::AlgorithmPtr sized(const std::string& name, const tune::AlgorithmSettings& job_algorithm,
                         std::int64_t budget) {
  const int population = job_algorithm.population();
  const json own = job_algorithm.to_json();
  json settings;
  if (name == "bat" || name == "random") {
    settings = own["type"] == name ? own : json{{"type", name}, {"population", population}};
  } else {
    const std::string pagmo = name.substr(6);
    const int least = tune::find_pagmo_algorithm(pagmo)->min_population;
    settings =
        own["type"] == "pagmo" && own["name"] == pagmo
            ? own
            : json{{"type", "pagmo"}, {"name", pagmo}, {"population", std::max(population, least)}};
  }
  const tune::AlgorithmPtr a = tune::make_algorithm(settings)->with_budget(budget);
  if (!a)
    throw InputError("--budget", "",
                     std::to_string(budget) + " evaluations do not pay for one generation of " +
                         name + " after its initial population of " +
                         std::to_string(settings["population"].get<int>()));
  std::vector<FieldError> errs = a->validate("");
  for (FieldError& e : errs) e.message = name + " with this budget: " + e.message;
  throw_if_errors("--budget", std::move(errs));
  return a;
}

struct Run {
  std::string algorithm;
  std::uint64_t seed = 0;
  double objective = 0.0;  // of the best candidate, 1/J; +inf when every candidate diverged
  tune::Decision best;
  int on_bound = 0;
  std::int64_t evaluations = 0;
  double wall = 0.0;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string num(double v, const char* format = "%.6g") {
  if (std::isinf(v)) return "diverged";
  char buf[40];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

struct Summary {
  std::string algorithm;
  int rank = 1;  // entries whose medians lie within the noise floor of each other share one
  double median = 0, best = 0, worst = 0, wall = 0;
  int on_bound = 0, parameters = 0;
  std::int64_t evaluations = 0;  // the most any run spent
};

std::string noise_sentence(double noise) {
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "Noise floor: nudging the initial state by a relative 1e-12 moves the best run's "
                "objective by up to %.2g %% (8 runs). Algorithms whose medians lie within that of "
                "one another share a rank (\"=\"): their order is not merit.",
                100 * noise);
  return buf;
}

std::string table(const std::vector<Summary>& rows) {
  std::string t =
      "| rank | algorithm | median | best | worst | on a bound | evaluations | median wall [s] "
      "|\n"
      "| ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Summary& s = rows[i];
    // "2=" where the entry ties with another inside the noise.
    bool tied = false;
    for (std::size_t j = 0; j < rows.size(); ++j) tied = tied || (j != i && rows[j].rank == s.rank);
    t += "| " + std::to_string(s.rank) + (tied ? "=" : "") + " | " + s.algorithm + " | " +
         num(s.median) + " | " + num(s.best) + " | " + num(s.worst) + " | " +
         std::to_string(s.on_bound) + "/" + std::to_string(s.parameters) + " | " +
         std::to_string(s.evaluations) + " | " + num(s.wall, "%.2f") + " |\n";
  }
  return t;
}

int run_study(const StudyCli& o, const Globals& g) {
  namespace fs = std::filesystem;
  using clock = std::chrono::steady_clock;
  const tune::Job job = tune::load_job(o.job);
  if (!job.tuning)
    throw InputError(o.job, "/tuning", "is required by ftctune study (what should be tuned?)");
  const std::vector<std::string> names = parse_algorithm_list(o.algorithms);
  const std::vector<std::uint64_t> seeds = parse_seeds(o.seeds);
  if (o.budget < 1) throw InputError("--budget", "", "must be a positive number of evaluations");
  // Every algorithm sized before anything runs, so a bad budget costs nothing.
  std::vector<tune::AlgorithmPtr> algorithms;
  for (const std::string& n : names)
    algorithms.push_back(sized(n, *job.tuning->algorithm, o.budget));
  // Memory by design: the runs go one at a time, each holding what a run of the budget holds.
  tune::check_memory_budget(job, static_cast<double>(o.budget), tune::memory_budget_bytes(),
                            o.job);
  const fs::path out = o.out.empty() ? default_out_dir(job) / "study" : fs::path(o.out);
  const tune::TuningProblem problem(job);
  const tune::SearchSpace& space = problem.space();

  const std::unique_ptr<tune::BatchEvaluator> evaluator = make_evaluator(o.threads);
  spdlog::info("study of job {}: {} algorithm(s) x {} seed(s), {} evaluations each, {} thread(s)",
               job.name, names.size(), seeds.size(), o.budget, evaluator->concurrency());
  std::vector<Run> runs;
  const std::size_t total = names.size() * seeds.size();
  for (std::size_t a = 0; a < names.size(); ++a)
    for (std::uint64_t seed : seeds) {
      tune::RunOptions ro;
      ro.seed = seed;
      ro.compare = false;
      const auto t0 = clock::now();
      const std::unique_ptr<tune::Optimizer> optimizer = algorithms[a]->make(seed, space);
      const tune::TuningOutcome r =
          tune::tune(problem, *optimizer, algorithms[a], seed, *evaluator, ro);
      Run run;
      run.algorithm = names[a];
      run.seed = seed;
      run.wall = std::chrono::duration<double>(clock::now() - t0).count();
      run.best = r.optimization.best;
      run.objective = r.optimization.best_fitness > 0 ? 1.0 / r.optimization.best_fitness
                                                      : std::numeric_limits<double>::infinity();
      run.evaluations = r.optimization.evaluations;
      for (std::size_t j = 0; j < space.dimension(); ++j) {
        const double margin = kOnBound * (space.upper[j] - space.lower[j]);
        if (run.best[j] <= space.lower[j] + margin || run.best[j] >= space.upper[j] - margin)
          ++run.on_bound;
      }
      std::string params;
      for (std::size_t j = 0; j < space.dimension(); ++j)
        params += (j ? ", " : "") + space.names[j] + " = " + num(run.best[j], "%.5g");
      spdlog::info("[{}/{}] {} seed {}: {} = {} ({}), {} evaluations, {:.2f} s", runs.size() + 1,
                   total, run.algorithm, seed, sim::to_string(job.objective.metric),
                   num(run.objective), params, run.evaluations, run.wall);
      runs.push_back(std::move(run));
    }

  std::string csv = "algorithm,seed,objective";
  for (const std::string& n : space.names) csv += "," + n;
  csv += ",on_bound,evaluations,wall_seconds\n";
  for (const Run& r : runs) {
    csv += r.algorithm + "," + std::to_string(r.seed) + "," + num(r.objective, "%.17g");
    for (double x : r.best) csv += "," + num(x, "%.17g");
    csv += "," + std::to_string(r.on_bound) + "," + std::to_string(r.evaluations) + "," +
           num(r.wall, "%.3f") + "\n";
  }

  std::vector<Summary> rows;
  for (const std::string& n : names) {
    Summary s;
    s.algorithm = n;
    std::vector<double> objectives, walls;
    for (const Run& r : runs)
      if (r.algorithm == n) {
        objectives.push_back(r.objective);
        walls.push_back(r.wall);
        s.on_bound += r.on_bound;
        s.parameters += static_cast<int>(space.dimension());
        s.evaluations = std::max(s.evaluations, r.evaluations);
      }
    s.median = median(objectives);
    s.best = *std::min_element(objectives.begin(), objectives.end());
    s.worst = *std::max_element(objectives.begin(), objectives.end());
    s.wall = median(walls);
    rows.push_back(s);
  }
  std::stable_sort(rows.begin(), rows.end(),
                   [](const Summary& a, const Summary& b) { return a.median < b.median; });

  // The noise floor (SPEC §14): the best run's winner re-evaluated with its initial states nudged
  // by a relative 1e-12. Medians closer than that are not told apart by merit: they tie.
  const Run* winner = nullptr;
  for (const Run& r : runs)
    if (std::isfinite(r.objective) && (!winner || r.objective < winner->objective)) winner = &r;
  double noise = 0.0;
  if (winner) {
    const sim::ControllerConfig c = problem.controller_with(winner->best);
    tune::NoiseFloor nf;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int k = 0; k < nf.repeats; ++k) {
      const double v =
          problem
              .perturbed(winner->seed, tune::kNoiseFloorStream + static_cast<std::uint64_t>(k),
                         nf.perturbation)
              .evaluate(std::span<const sim::ControllerConfig>(&c, 1), *evaluator)[0]
              .evaluation.objective;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    noise = std::isfinite(hi - lo) ? (hi - lo) / winner->objective : 0.0;
  }
  for (Summary& s : rows) {
    s.rank = 1;
    for (const Summary& other : rows)
      if (other.median < s.median && (s.median - other.median) > noise * std::abs(other.median))
        ++s.rank;
  }

  const std::string metric = sim::to_string(job.objective.metric);
  std::string md = "# Study of job " + job.name + "\n\n" + std::to_string(names.size()) +
                   " algorithms × " + std::to_string(seeds.size()) + " seeds (" + o.seeds + "), " +
                   std::to_string(o.budget) + " evaluations each; the objective is the job's " +
                   metric + " of the best candidate of a run (lower is better), " +
                   tune::objective_label(job) +
                   ". Sorted by median. \"On a bound\": tuned parameters that ended within 0.1 % "
                   "of their range from a bound, over all runs.\n\n" +
                   noise_sentence(noise) + "\n\n" + table(rows) + "\n## Settings\n\n";
  for (std::size_t a = 0; a < names.size(); ++a)
    md += "- " + names[a] + ": `" + algorithms[a]->to_json().dump() + "`\n";
  md += "\nObjectives of every run: study.csv. Command: `ftctune study " + o.job +
        " --algorithms " + o.algorithms + " --seeds " + o.seeds + " --budget " +
        std::to_string(o.budget) + "`\n";
  tune::write_file_atomic(out / "study.csv", csv);
  tune::write_file_atomic(out / "study.md", md);

  std::vector<tune::StudySeries> series;
  for (const Summary& s : rows) {
    tune::StudySeries ss{s.algorithm, {}};
    for (const Run& r : runs)
      if (r.algorithm == s.algorithm) ss.objectives.push_back(r.objective);
    series.push_back(std::move(ss));
  }
  const char* unit = job.objective.metric == sim::Metric::ise   ? "rad²·s"
                     : job.objective.metric == sim::Metric::iae ? "rad·s"
                                                                : "rad·s²";
  const fs::path figure = tune::draw_study(
      out,
      "Best objective per seed: " + job.name + ", " + std::to_string(o.budget) + " evaluations",
      tune::objective_label(job) + " of the best candidate [" + unit + "] (lower is better)",
      series, tune::FigureFormat::png, rows.empty() ? 0.0 : rows.front().median, noise);
  if (!g.quiet) {
    std::printf("%s", table(rows).c_str());
    std::printf("wrote %s, %s, %s\n", (out / "study.csv").c_str(), (out / "study.md").c_str(),
                figure.c_str());
  }
  return 0;
}

}  // namespace

void add_study_command(CLI::App& app, const Globals& g, Action& action) {
  auto o = std::make_shared<StudyCli>();
  CLI::App* sub = app.add_subcommand(
      "study", "Compare algorithms on a job over seeds at one budget of evaluations");
  sub->add_option("job", o->job, "Job file (ftctune.job/1)")->required();
  sub->add_option("--algorithms", o->algorithms,
                  "Comma-separated: bat, random, pagmo:<name> (e.g. bat,random,pagmo:cmaes)")
      ->required();
  sub->add_option("--seeds", o->seeds, "Seeds: 1-10, 1,3,5 or a mix such as 1-3,7")->required();
  sub->add_option("--budget", o->budget, "Evaluations per run, the initial population included")
      ->required();
  sub->add_option("--threads", o->threads, "Worker threads (default: all cores)")
      ->check(CLI::Range(0, 4096));
  sub->add_option("--out", o->out, "Output directory (default out/<job name>/study)")
      ->check(output_directory());
  sub->callback([&action, &g, o] { action = [&g, o] { return run_study(*o, g); }; });
}

}  // namespace ftc::cli
