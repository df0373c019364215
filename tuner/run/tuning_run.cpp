#include "ftc/tune/run/tuning_run.hpp"

#include <algorithm>
#include <cmath>

#include "ftc/tune/io/sha256.hpp"

namespace ftc::tune {

std::string display_name(sim::ControllerType t) {
  switch (t) {
    case sim::ControllerType::nftsmc:
      return "NFTSMC";
    case sim::ControllerType::fosmc:
      return "FOSMC";
    case sim::ControllerType::pi_fosmc:
      return "PI-FOSMC";
    case sim::ControllerType::adaptive_neural_pi_fosmc:
      return "adaptive neural PI-FOSMC";
  }
  return "?";
}

std::string canonical_job_sha256(const Job& job) { return sha256_hex(to_json(job).dump()); }

TuningOutcome tune(const TuningProblem& problem, Optimizer& optimizer, AlgorithmPtr algorithm,
                   std::uint64_t seed, BatchEvaluator& evaluator, const RunOptions& options) {
  const Job& job = problem.job();
  if (!job.tuning) throw InputError("job " + job.name, "/tuning", "is required to tune");
  TuningOutcome r;
  r.job = job;
  r.job_sha256 = canonical_job_sha256(job);
  r.seed = seed;
  r.algorithm = std::move(algorithm);
  r.threads = evaluator.concurrency();
  r.evaluator = evaluator.name();

  ProblemFitness fitness(problem, evaluator);
  r.optimization = run_optimizer(optimizer, fitness, options.observer, options.resume);
  r.simulations = fitness.simulations();
  if (!r.optimization.completed || !options.compare) return r;

  r.tuned_controller = problem.controller_for(r.optimization.best);
  for (std::size_t j = 0; j < problem.space().names.size(); ++j)
    r.tuned.emplace_back(problem.space().names[j], r.optimization.best[j]);

  std::vector<sim::ControllerConfig> controllers;
  for (const CompareEntry& c : job.compare) {
    r.comparison.push_back({c.label, "compare", c.controller, {}});
    controllers.push_back(c.controller);
  }
  const std::string name = display_name(job.controller.type);
  r.comparison.push_back({name + " (job)", "baseline", job.controller, {}});
  controllers.push_back(job.controller);
  r.comparison.push_back({"optimal " + name, "tuned", r.tuned_controller, {}});
  controllers.push_back(r.tuned_controller);

  const auto every = std::max<std::int64_t>(
      1, std::llround(kComparisonRecordInterval / job.scenarios.front().sample_time));
  std::vector<CandidateOutcome> outcomes = problem.evaluate(controllers, evaluator, every);
  for (std::size_t i = 0; i < outcomes.size(); ++i) r.comparison[i].outcome = std::move(outcomes[i]);
  r.simulations += static_cast<std::int64_t>(controllers.size() * problem.scenarios());
  return r;
}

TuningOutcome tune(const Job& job, BatchEvaluator& evaluator, const RunOptions& options) {
  if (!job.tuning) throw InputError("job " + job.name, "/tuning", "is required to tune");
  const TuningProblem problem(job);
  const std::uint64_t seed = options.seed.value_or(job.tuning->seed);
  const AlgorithmPtr& algorithm = job.tuning->algorithm;
  const std::unique_ptr<Optimizer> optimizer = algorithm->make(seed, problem.space());
  return tune(problem, *optimizer, algorithm, seed, evaluator, options);
}

}  // namespace ftc::tune
