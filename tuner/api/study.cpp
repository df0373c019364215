// The run API's study (api/api.hpp): the job's tuning with several algorithms and seeds at one
// budget of evaluations, so that algorithms are compared at equal cost. Writes study.csv (one row
// per run), study.md (per algorithm: median, best and worst objective, parameters ended on a
// bound, median wall time) and study.png.
#include "ftc/tune/report/study_figure.hpp"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>

#include "ftc/sim/input_error.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/optimizers/pagmo.hpp"
#include "ftc/tune/api/api.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/memory_budget.hpp"

namespace ftc::tune {
namespace {

using nlohmann::json;

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
  for (const PagmoAlgorithmInfo& a : pagmo_algorithms()) s += ", pagmo:" + a.name;
  return s;
}

// At most this many seeds in all, over every range.
constexpr std::uint64_t kMaxSeeds = 100000;

// The algorithm `name` sized to `budget` evaluations: the job's own settings when it names the
// same algorithm, else the defaults with the job's population (or the smallest the algorithm
// takes).
AlgorithmPtr sized(const std::string& name, const AlgorithmSettings& job_algorithm,
                   std::int64_t budget) {
  const int population = job_algorithm.population();
  const json own = job_algorithm.to_json();
  json settings;
  if (name == "bat" || name == "random") {
    settings = own["type"] == name ? own : json{{"type", name}, {"population", population}};
  } else {
    const std::string pagmo = name.substr(6);
    const int least = find_pagmo_algorithm(pagmo)->min_population;
    settings =
        own["type"] == "pagmo" && own["name"] == pagmo
            ? own
            : json{{"type", "pagmo"}, {"name", pagmo}, {"population", std::max(population, least)}};
  }
  const AlgorithmPtr a = make_algorithm(settings)->with_budget(budget);
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

std::string noise_sentence(double noise) {
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "Noise floor: nudging the initial state by a relative 1e-12 moves the best run's "
                "objective by up to %.2g %% (8 runs). Algorithms whose medians lie within that of "
                "one another share a rank (\"=\"): their order is not merit.",
                100 * noise);
  return buf;
}

}  // namespace

// "bat,random,pagmo:cmaes": the names, each known and given once.
std::vector<std::string> parse_algorithm_list(const std::string& text) {
  std::vector<FieldError> errs;
  std::vector<std::string> names;
  if (text.empty())
    throw InputError("--algorithms", "", "is empty (known: " + known_algorithms() + ")");
  for (const std::string& n : split(text)) {
    const bool known = n == "bat" || n == "random" ||
                       (n.rfind("pagmo:", 0) == 0 && find_pagmo_algorithm(n.substr(6)));
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

// "1-10", "1,3,5", "1-3,7": the seeds in the order given, each once. The ranges are checked as
// ranges (their total against kMaxSeeds, their overlaps after sorting) before any is expanded,
// so `1-10000000` is refused at once rather than after filling memory.
std::vector<std::uint64_t> parse_seed_list(const std::string& text) {
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

std::string study_table(const std::vector<StudyRow>& rows) {
  std::string t =
      "| rank | algorithm | median | best | worst | on a bound | evaluations | median wall [s] "
      "|\n"
      "| ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const StudyRow& s = rows[i];
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

namespace {

// The lists as the study takes them: not empty, each entry once, each algorithm known.
void check_lists(const std::vector<std::string>& names, const std::vector<std::uint64_t>& seeds) {
  std::string text;
  for (const std::string& n : names) text += (text.empty() ? "" : ",") + n;
  if (parse_algorithm_list(text) != names)
    throw InputError("--algorithms", "", "\"" + text + "\" is not a list of algorithms");
  if (seeds.empty()) throw InputError("--seeds", "", "is empty (e.g. 1-10 or 1,3,5)");
  std::vector<std::uint64_t> sorted = seeds;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 1; i < sorted.size(); ++i)
    if (sorted[i] == sorted[i - 1])
      throw InputError("--seeds", "", "seed " + std::to_string(sorted[i]) + " is given twice");
}

}  // namespace

StudyResult run_study(const Job& job, const StudyOptions& o) {
  namespace fs = std::filesystem;
  using clock = std::chrono::steady_clock;
  if (!job.tuning)
    throw InputError(o.job_file, "/tuning", "is required by ftctune study (what should be tuned?)");
  // A study ranks algorithms by the best objective; a front is not one number.
  if (front_objectives(job) >= 2)
    throw InputError(o.job_file, "/goals",
                     "ftctune study compares algorithms by one objective, and this job's two or "
                     "more soft goals ask for a Pareto front: keep one soft goal for a study");
  const std::vector<std::string>& names = o.algorithms;
  const std::vector<std::uint64_t>& seeds = o.seeds;
  check_lists(names, seeds);
  if (o.budget < 1) throw InputError("--budget", "", "must be a positive number of evaluations");
  // Every algorithm sized before anything runs, so a bad budget costs nothing.
  std::vector<AlgorithmPtr> algorithms;
  for (const std::string& n : names)
    algorithms.push_back(sized(n, *job.tuning->algorithm, o.budget));
  // Memory by design: the runs go one at a time, each holding what a run of the budget holds.
  check_memory_budget(job, static_cast<double>(o.budget), memory_budget_bytes(), o.job_file);
  StudyResult result;
  result.out = o.out.empty() ? default_out_dir(job.name) / "study" : o.out;
  const fs::path& out = result.out;
  const TuningProblem problem(job);
  const SearchSpace& space = problem.space();

  std::unique_ptr<BatchEvaluator> owned;
  BatchEvaluator* evaluator = o.evaluator;
  if (!evaluator) {
    owned = make_evaluator(o.threads);
    evaluator = owned.get();
  }
  say(o.log, LogLevel::info,
      "study of job " + job.name + ": " + std::to_string(names.size()) + " algorithm(s) x " +
          std::to_string(seeds.size()) + " seed(s), " + std::to_string(o.budget) +
          " evaluations each, " + std::to_string(evaluator->concurrency()) + " thread(s)");
  std::vector<StudyRun>& runs = result.runs;
  const std::size_t total = names.size() * seeds.size();
  for (std::size_t a = 0; a < names.size(); ++a)
    for (std::uint64_t seed : seeds) {
      RunOptions ro;
      ro.seed = seed;
      ro.compare = false;
      const auto t0 = clock::now();
      const std::unique_ptr<Optimizer> optimizer = algorithms[a]->make(seed, space);
      const TuningOutcome r = tune(problem, *optimizer, algorithms[a], seed, *evaluator, ro);
      StudyRun run;
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
      say(o.log, LogLevel::info,
          "[" + std::to_string(runs.size() + 1) + "/" + std::to_string(total) + "] " +
              run.algorithm + " seed " + std::to_string(seed) + ": " +
              std::string(job.objective.metric->name) + " = " + num(run.objective) + " (" + params +
              "), " + std::to_string(run.evaluations) + " evaluations, " + num(run.wall, "%.2f") +
              " s");
      runs.push_back(std::move(run));
    }

  std::string csv = "algorithm,seed,objective";
  for (const std::string& n : space.names) csv += "," + n;
  csv += ",on_bound,evaluations,wall_seconds\n";
  for (const StudyRun& r : runs) {
    csv += r.algorithm + "," + std::to_string(r.seed) + "," + num(r.objective, "%.17g");
    for (double x : r.best) csv += "," + num(x, "%.17g");
    csv += "," + std::to_string(r.on_bound) + "," + std::to_string(r.evaluations) + "," +
           num(r.wall, "%.3f") + "\n";
  }

  std::vector<StudyRow>& rows = result.rows;
  for (const std::string& n : names) {
    StudyRow s;
    s.algorithm = n;
    std::vector<double> objectives, walls;
    for (const StudyRun& r : runs)
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
                   [](const StudyRow& a, const StudyRow& b) { return a.median < b.median; });

  // The noise floor (SPEC §14): the best run's winner re-evaluated with its initial states nudged
  // by a relative 1e-12. Medians closer than that are not told apart by merit: they tie.
  const StudyRun* winner = nullptr;
  for (const StudyRun& r : runs)
    if (std::isfinite(r.objective) && (!winner || r.objective < winner->objective)) winner = &r;
  double& noise = result.noise;
  if (winner) {
    const sim::ControllerConfig c = problem.controller_with(winner->best);
    NoiseFloor nf;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int k = 0; k < nf.repeats; ++k) {
      const double v =
          problem
              .perturbed(winner->seed, kNoiseFloorStream + static_cast<std::uint64_t>(k),
                         nf.perturbation)
              .evaluate(std::span<const sim::ControllerConfig>(&c, 1), *evaluator)[0]
              .evaluation.objective;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    noise = std::isfinite(hi - lo) ? (hi - lo) / winner->objective : 0.0;
  }
  for (StudyRow& s : rows) {
    s.rank = 1;
    for (const StudyRow& other : rows)
      if (other.median < s.median && (s.median - other.median) > noise * std::abs(other.median))
        ++s.rank;
  }

  std::string seeds_text = o.seeds_text, algorithms_text;
  if (seeds_text.empty())
    for (std::uint64_t s : seeds) seeds_text += (seeds_text.empty() ? "" : ",") + std::to_string(s);
  for (const std::string& n : names) algorithms_text += (algorithms_text.empty() ? "" : ",") + n;
  const std::string command =
      !o.command.empty() ? o.command
                         : "ftctune study " + o.job_file + " --algorithms " + algorithms_text +
                               " --seeds " + seeds_text + " --budget " + std::to_string(o.budget);
  const std::string metric(job.objective.metric->name);
  std::string md = "# Study of job " + job.name + "\n\n" + std::to_string(names.size()) +
                   " algorithms × " + std::to_string(seeds.size()) + " seeds (" + seeds_text +
                   "), " + std::to_string(o.budget) +
                   " evaluations each; the objective is the job's " + metric +
                   " of the best candidate of a run (lower is better), " + objective_label(job) +
                   ". Sorted by median. \"On a bound\": tuned parameters that ended within 0.1 % "
                   "of their range from a bound, over all runs.\n\n" +
                   noise_sentence(noise) + "\n\n" + study_table(rows) + "\n## Settings\n\n";
  for (std::size_t a = 0; a < names.size(); ++a)
    md += "- " + names[a] + ": `" + algorithms[a]->to_json().dump() + "`\n";
  md += "\nObjectives of every run: study.csv. Command: `" + command + "`\n";
  write_file_atomic(out / "study.csv", csv);
  write_file_atomic(out / "study.md", md);

  std::vector<StudySeries> series;
  for (const StudyRow& s : rows) {
    StudySeries ss{s.algorithm, {}};
    for (const StudyRun& r : runs)
      if (r.algorithm == s.algorithm) ss.objectives.push_back(r.objective);
    series.push_back(std::move(ss));
  }
  const std::string unit(job.objective.metric->unit);
  result.csv = out / "study.csv";
  result.markdown = out / "study.md";
  result.figure = draw_study(
      out,
      "Best objective per seed: " + job.name + ", " + std::to_string(o.budget) + " evaluations",
      objective_label(job) + " of the best candidate [" + unit + "] (lower is better)", series,
      FigureFormat::png, rows.empty() ? 0.0 : rows.front().median, noise);
  return result;
}

}  // namespace ftc::tune
