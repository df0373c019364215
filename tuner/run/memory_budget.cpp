#include "ftc/tune/run/memory_budget.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "ftc/sim/input_error.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/tune/job/ensemble.hpp"
#include "ftc/tune/run/tuning_run.hpp"

namespace ftc::tune {

namespace {

double members(const Job& job) {
  return job.ensemble ? static_cast<double>(job.ensemble->count) : 0.0;
}

// The scenarios whose objectives every trial keeps: those of a job without an ensemble.
double trial_scenarios(const Job& job) {
  return job.ensemble ? 0.0 : static_cast<double>(job.scenarios.size());
}

}  // namespace

double comparison_trajectory_numbers(const Job& job, std::int64_t max_rows) {
  if (job.scenarios.empty()) return 0.0;
  const sim::PlantKind* kind = sim::find_plant_kind(job.plant.model);
  const double width = kind ? 1.0 + 2.0 * (kind->axes + kind->actuators_of(job.plant.values)) : 1.0;
  const std::int64_t every = comparison_record_every(job, max_rows);
  double rows = 0;
  for (const sim::Scenario& s : job.scenarios)
    rows += static_cast<double>((s.samples() + every - 1) / every);
  return rows * width * (static_cast<double>(job.compare.size()) + 2.0);
}

double listed_scenario_bytes(const Job& job) {
  if (job.scenarios.empty()) return 0.0;
  const double controllers = static_cast<double>(job.compare.size()) + 2.0;
  double faults = 0;
  for (const sim::Scenario& s : job.scenarios) faults += static_cast<double>(s.faults.size());
  return static_cast<double>(job.scenarios.size()) *
             (kBytesPerScenario + controllers * kBytesPerScenarioController) +
         faults * (kBytesPerFault + controllers * kBytesPerFaultController) +
         comparison_trajectory_numbers(job) * kBytesPerTrajectoryNumber;
}

double noise_table_bytes(const Job& job, bool with_noise_floor) {
  const sim::PlantKind* kind = sim::find_plant_kind(job.plant.model);
  if (!kind) return 0.0;
  const double cache = static_cast<double>(sim::kNoiseCacheBytes);
  const auto table = [&](const sim::Scenario& s) {
    const double bytes = static_cast<double>(s.samples()) * 3.0 * kind->axes * sizeof(double);
    return bytes > cache / 4 ? 0.0 : bytes + kBytesPerNoiseTable;
  };
  double bytes = 0;
  for (const sim::Scenario& s : job.scenarios)
    if (s.active_sensors()) bytes += table(s);
  // Members copy their base's sensors or draw their own, and its run length.
  const sim::Scenario* base = job.ensemble ? find_ensemble_base(job) : nullptr;
  if (base && (job.ensemble->sensors || base->active_sensors()))
    bytes += members(job) * table(*base);
  // The noise floor reruns the tuned gains with as many other sensor seeds: other tables.
  if (with_noise_floor) bytes *= 1.0 + NoiseFloor{}.repeats;
  return std::min(bytes, cache);
}

double bytes_per_trial(const Job& job) {
  const double numbers =
      static_cast<double>((job.tuning ? job.tuning->parameters.size() : 0) + job.goals.size());
  return kBytesPerTrial + numbers * kBytesPerTrialNumber +
         trial_scenarios(job) * kBytesPerTrialObjective;
}

std::size_t controllers_at_once(const Job& job) {
  const std::size_t population =
      job.tuning ? static_cast<std::size_t>(job.tuning->algorithm->population()) : 0;
  return population + 1 + job.compare.size() + 2;
}

double bytes_per_member(const Job& job) {
  return kBytesPerMemberValue * static_cast<double>(controllers_at_once(job)) *
         (1.0 + static_cast<double>(job.goals.size()));
}

double estimated_run_bytes(const Job& job, double evaluations) {
  return kRunBaseBytes + listed_scenario_bytes(job) + members(job) * bytes_per_member(job) +
         evaluations * bytes_per_trial(job) + noise_table_bytes(job, job.tuning.has_value());
}

double estimated_run_bytes(const Job& job) {
  return estimated_run_bytes(
      job, job.tuning ? static_cast<double>(job.tuning->algorithm->evaluations()) : 1.0);
}

double estimated_scoring_bytes(const Job& job, double candidates, bool members_listed,
                               bool members_metrics) {
  double listed = static_cast<double>(job.scenarios.size());
  // Members scored without their metrics keep a value each per candidate (Evaluation::values).
  const double scored = members_metrics ? 0.0 : members(job);
  double held = bytes_per_member(job);  // a member generated block by block, as a run does
  if (members_listed && job.ensemble) {
    // A member held is a scenario with its faults (no comparison runs on it).
    const double faults =
        job.ensemble->faults ? static_cast<double>(std::max(job.ensemble->faults->count_hi, 0))
                             : static_cast<double>(ensemble_base(job).faults.size());
    held = kBytesPerScenario + faults * kBytesPerFault;
    if (members_metrics) listed += members(job);
  }
  const double bytes = kRunBaseBytes + listed_scenario_bytes(job) + members(job) * held +
                       noise_table_bytes(job, false);
  return bytes + candidates * (kBytesPerCandidate + listed * kBytesPerScoredScenario +
                               scored * kBytesPerMemberValue);
}

void check_memory_need(double need, double budget, const std::string& source,
                       const std::string& what) {
  if (need <= budget) return;
  throw InputError(source, "",
                   what + " would need about " + bytes_text(need) +
                       " of memory, more than the budget of " + bytes_text(budget) +
                       " (FTCTUNE_MEMORY_MIB sets it)");
}

double memory_budget_bytes() {
  if (const char* e = std::getenv("FTCTUNE_MEMORY_MIB"); e && *e) {
    char* end = nullptr;
    const double mib = std::strtod(e, &end);
    if (*end == '\0' && std::isfinite(mib) && mib > 0) return mib * (1 << 20);
    throw InputError("FTCTUNE_MEMORY_MIB", "",
                     std::string("must be a positive number of MiB (got \"") + e + "\")");
  }
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  if (pages <= 0 || page <= 0) return 4.0 * (1u << 30);  // unknown: 4 GiB
  return 0.75 * static_cast<double>(pages) * static_cast<double>(page);
}

std::string bytes_text(double bytes) {
  char buf[32];
  if (bytes >= 1e9)
    std::snprintf(buf, sizeof buf, "%.3g GB", bytes / 1e9);
  else
    std::snprintf(buf, sizeof buf, "%.3g MB", bytes / 1e6);
  return buf;
}

void check_memory_budget(const Job& job, double evaluations, double budget,
                         const std::string& source) {
  const double need = estimated_run_bytes(job, evaluations);
  if (need <= budget) return;
  throw InputError(source, "",
                   "the job would need about " + bytes_text(need) + " of memory (" +
                       memory_need_text(job, evaluations) + "), more than the budget of " +
                       bytes_text(budget) +
                       ": give fewer ensemble members, scenarios or evaluations, or a smaller "
                       "population (FTCTUNE_MEMORY_MIB sets the budget)");
}

std::string memory_need_text(const Job& job, double evaluations) {
  const std::size_t listed = job.scenarios.size();
  std::string out = std::to_string(listed) +
                    (listed == 1 ? " listed scenario and its" : " listed scenarios and their") +
                    " comparison at about " +
                    bytes_text(listed_scenario_bytes(job));
  if (job.ensemble) {
    char each[64];
    std::snprintf(each, sizeof each, "%.0f bytes each", bytes_per_member(job));
    out += ", " + std::to_string(job.ensemble->count) + " ensemble members at about " + each;
  }
  char trials[96];
  std::snprintf(trials, sizeof trials, ", %.15g trials at about %.0f bytes each", evaluations,
                bytes_per_trial(job));
  return out + trials;
}

void check_memory_budget(const Job& job, double budget, const std::string& source) {
  check_memory_budget(
      job, job.tuning ? static_cast<double>(job.tuning->algorithm->evaluations()) : 1.0, budget,
      source);
}

}  // namespace ftc::tune
