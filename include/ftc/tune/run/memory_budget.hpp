#pragma once
// Memory by design: what a tuning run must hold is estimated up front, and a job over the budget
// is refused before any work (exit 2 in the CLI, 413 in the service), saying how much it would
// need. The figures are measured (docs/reliability.md): a run holds every scenario, its ensemble
// expanded, with its per-scenario state (about 3.5 kB each, the service's figure), and for every trial one objective per
// scenario (8 bytes). `evaluate` and `ensemble` stream their members and are not bounded by it.
#include <cstdint>
#include <string>

#include "ftc/tune/job/job.hpp"

namespace ftc::tune {

inline constexpr double kRunBaseBytes = 64.0 * (1 << 20);  // the process, the job, the pools
inline constexpr double kBytesPerScenario = 3584.0;  // measured: 1.98 kB in run, 3.2 kB served
inline constexpr double kBytesPerTrialObjective = 8.0;

// The bytes a tuning run of `job` holds at its peak (its trials: evaluations × scenarios
// objectives), by the figures above.
double estimated_run_bytes(const Job& job);
// The same for a run of `evaluations` evaluations (a study's budget) instead of the job's own.
double estimated_run_bytes(const Job& job, double evaluations);

// The memory a run may take: FTCTUNE_MEMORY_MIB (a positive number of MiB; anything else is an
// InputError) when set, else three
// quarters of the machine's physical memory.
double memory_budget_bytes();

// Throws InputError(source, "", ...) naming what the job would need and the budget when the
// estimate is above `budget`.
void check_memory_budget(const Job& job, double budget, const std::string& source);
void check_memory_budget(const Job& job, double evaluations, double budget,
                         const std::string& source);

// "1.9 GB", "650 MB": a byte count for messages.
std::string bytes_text(double bytes);

}  // namespace ftc::tune
