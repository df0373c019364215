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
// trajectory file's buffers. Measured on scenarios of 20 ms with 2 faults each
// (MemoryBudget.AListedScenarioTakesNoMoreThanItIsCharged): 34.6 kB with 2 controllers, 56.0 kB
// with 4, 76.4 kB with 6; of which the faults' share is charged below.
inline constexpr double kBytesPerScenario = 12288.0;
inline constexpr double kBytesPerScenarioController = 8192.0;
// A fault of a listed scenario: the fault in every copy of the job and its documents, and for
// each compared controller its per-fault metrics, in comparison.json and comparison.md too.
// Measured (MemoryBudget.AFaultTakesNoMoreThanItIsCharged, 40 scenarios of 400 faults more):
// 7.2 kB with 2 controllers, 11.5 kB with 4.
inline constexpr double kBytesPerFault = 4096.0;
inline constexpr double kBytesPerFaultController = 3072.0;
// A member's numbers for one controller scored at once (and one more of each per goal): its
// value, whether it diverged, the counted values' copy as they are aggregated.
inline constexpr double kBytesPerMemberValue = 24.0;
inline constexpr double kBytesPerTrialObjective = 8.0;
// A number of a comparison trajectory's row: the double and its text in the trajectory file
// (MemoryBudget.ALongTrajectoryTakesNoMoreThanItIsCharged: 497 bytes a row of 15 numbers).
inline constexpr double kBytesPerTrajectoryNumber = 40.0;
// A trial: its record and its copy in the outcome, its row of trials.csv and its share of the
// optimiser's history (MemoryBudget.ATrialTakesNoMoreThanItIsCharged: 911 to 1 037 bytes in
// two runs, with two parameters), and for each parameter and goal value a number more.
inline constexpr double kBytesPerTrial = 1280.0;
inline constexpr double kBytesPerTrialNumber = 32.0;
// The bytes the job's listed scenarios take in a run: kBytesPerScenario each, kBytesPerFault a
// fault, and for each controller compared on them kBytesPerScenarioController,
// kBytesPerFaultController a fault and the rows of its trajectory (kBytesPerTrajectoryNumber a
// number).
double listed_scenario_bytes(const Job& job);
// The numbers of the comparison's trajectories of the listed scenarios: a row of one time and
// 2(n + m) numbers every comparison_record_every(job, max_rows) samples, per compared controller
// (its compare entries, the job's own and the tuned one).
double comparison_trajectory_numbers(const Job& job, std::int64_t max_rows = 0);
// The bytes a member takes in a run of the job: kBytesPerMemberValue for each controller scored
// at once (its population, the incumbent, its compare entries, the job's and the tuned
// controller), times one plus its goals.
double bytes_per_member(const Job& job);
// A noise table's own bytes beyond its samples: the cache's entry and key, the scenario's copy
// with its sensor seed moved, and the allocator's slack around a table of megabytes
// (MemoryBudget.SensorNoiseTablesTakeNoMoreThanTheyAreCharged, 18 tables of 21 000 samples:
// 0.05 % to 0.9 % over the samples' bytes from run to run, up to 14 kB a table).
inline constexpr double kBytesPerNoiseTable = 65536.0;
// The bytes of the sensors' noise tables a run of the job draws (sim::kNoiseCacheBytes): 3n
// doubles a sample of each scenario whose controller reads sensors, listed or member (but not a
// table larger than a quarter of the cache: drawn as it goes), once for the run's own seed and,
// `with_noise_floor` (a tuning run), once for each of the noise floor's other sensor seeds; at
// most the cache's size.
double noise_table_bytes(const Job& job, bool with_noise_floor);
// The bytes a trial takes: kBytesPerTrial, kBytesPerTrialNumber for each parameter and goal,
// and kBytesPerTrialObjective for each scenario whose objective a trial keeps (those of a job
// without an ensemble).
double bytes_per_trial(const Job& job);
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

// A candidate scored outside a run (a landscape's grid point, a Python call's row): its
// controller, its outcome and its output row, and its metrics of each listed scenario. Measured
// with `ftctune landscape jobs/table1.json` (one scenario): a peak of 61 344 kB at 200x200
// points and 565 552 kB at 700x700 (/usr/bin/time, kB of 1024 bytes), 1 147 bytes a point.
inline constexpr double kBytesPerCandidate = 512.0;
inline constexpr double kBytesPerScoredScenario = 1024.0;
// What scoring `candidates` controllers at once on every scenario of the job takes when each
// keeps its metrics of every listed scenario (a landscape's grid, a Python call's rows): the
// process, the listed scenarios and the members as a run holds them, and for each candidate
// kBytesPerCandidate and kBytesPerScoredScenario a listed scenario. With `members_listed` (the Python Problem holds the ensemble's members as
// listed scenarios, so that metrics() has a row for each), each member is charged
// kBytesPerScenario and kBytesPerFault for each fault of its distribution's largest count. For
// each candidate a member costs kBytesPerScoredScenario with `members_metrics` (Python's
// metrics()), else kBytesPerMemberValue (its value in Evaluation::values: a landscape, objective()).
double estimated_scoring_bytes(const Job& job, double candidates, bool members_listed,
                               bool members_metrics = false);
// Throws InputError(source, "", ...) when `need` is above `budget`, naming `what` needs it.
void check_memory_need(double need, double budget, const std::string& source,
                       const std::string& what);
// What the estimate counts, for messages: "1 listed scenario and its comparison at about
// 0.306 MB, 1000000 ensemble members at about 192 bytes each".
std::string memory_need_text(const Job& job, double evaluations);

// "1.9 GB", "650 MB": a byte count for messages.
std::string bytes_text(double bytes);

}  // namespace ftc::tune
