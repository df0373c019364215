#pragma once
// Memory by design: what a tuning run must hold is estimated up front, and a job over the budget
// is refused before any work (exit 2 in the CLI, 413 in the service), saying how much it would
// need. The figures are measured (docs/reliability.md). A run holds its listed scenarios, with
// their copies and the comparison's trajectories on them, but not its ensemble's members, which it generates block by
// block: for each member it holds a few numbers per controller it scores at once (a batch of the
// population, the incumbent, the comparison's controllers), one more per goal. A job without an
// ensemble keeps one objective per scenario (8 bytes) in every trial. `evaluate` and `ensemble`
// stream their members and are not bounded by it.
#include <cstdint>
#include <string>

#include "ftc/tune/job/job.hpp"

namespace ftc::tune {

// The process, the job, the pools and one block of generated members.
inline constexpr double kRunBaseBytes = 64.0 * (1 << 20);
// A listed scenario: the scenario, its entry in the job's documents (the job read, job.json) and
// its objectives; and for each controller the comparison runs on it (the job's, each compare
// entry, the tuned), its metrics, its entries in comparison.json and comparison.md and its
// trajectory file's buffers, besides the trajectory's rows. Measured on scenarios of 20 ms
// (MemoryBudget.AListedScenarioTakesNoMoreThanItIsCharged): 34.6 kB with 2 controllers, 56.0 kB
// with 4, 76.4 kB with 6, that is about 14 kB and 10.4 kB per controller.
inline constexpr double kBytesPerScenario = 16384.0;
inline constexpr double kBytesPerScenarioController = 12288.0;
// A member's numbers for one controller scored at once (and one more of each per goal): its
// value, whether it diverged, the counted values' copy as they are aggregated.
inline constexpr double kBytesPerMemberValue = 24.0;
inline constexpr double kBytesPerTrialObjective = 8.0;

// The bytes the job's listed scenarios take in a run: kBytesPerScenario each, and for each
// controller compared on them kBytesPerScenarioController and the rows of its trajectory
// (8 bytes a number).
double listed_scenario_bytes(const Job& job);
// The bytes a member takes in a run of the job: kBytesPerMemberValue for each controller scored
// at once (its population, the incumbent, its compare entries, the job's and the tuned
// controller), times one plus its goals.
double bytes_per_member(const Job& job);
// How many controllers the run scores at once (and bytes_per_member counts): the population,
// the incumbent, the compare entries, the job's and the tuned. The noise floor of a front's
// points is measured in groups of this many, so that a large front stays within the budget.
std::size_t controllers_at_once(const Job& job);
// The bytes a tuning run of `job` holds at its peak, by the figures above.
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

// What the estimate counts, for messages: "1 listed scenario and its comparison at about
// 0.306 MB, 1000000 ensemble members at about 192 bytes each".
std::string memory_need_text(const Job& job, double evaluations);

// "1.9 GB", "650 MB": a byte count for messages.
std::string bytes_text(double bytes);

}  // namespace ftc::tune
