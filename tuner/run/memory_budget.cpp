#include "ftc/tune/run/memory_budget.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "ftc/sim/input_error.hpp"

namespace ftc::tune {

double estimated_run_bytes(const Job& job, double evaluations) {
  const auto scenarios = static_cast<double>(job.scenario_count());
  return kRunBaseBytes + scenarios * kBytesPerScenario +
         evaluations * scenarios * kBytesPerTrialObjective;
}

double estimated_run_bytes(const Job& job) {
  return estimated_run_bytes(
      job, job.tuning ? static_cast<double>(job.tuning->algorithm->evaluations()) : 1.0);
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
  char evals[32];
  std::snprintf(evals, sizeof evals, "%.15g", evaluations);
  throw InputError(
      source, "",
      "the job would need about " + bytes_text(need) + " of memory (" +
          std::to_string(job.scenario_count()) + " scenarios at about 3.5 kB each, and one " +
          "objective per scenario for each of its " + evals +
          " evaluations), more than the budget of " + bytes_text(budget) +
          ": give fewer ensemble members or evaluations (FTCTUNE_MEMORY_MIB sets the budget)");
}

void check_memory_budget(const Job& job, double budget, const std::string& source) {
  check_memory_budget(
      job, job.tuning ? static_cast<double>(job.tuning->algorithm->evaluations()) : 1.0, budget,
      source);
}

}  // namespace ftc::tune
