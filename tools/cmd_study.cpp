// ftctune study JOB: the job's tuning with several algorithms and seeds at one budget of
// evaluations, so that algorithms are compared at equal cost. Writes study.csv (one row per run),
// study.md (per algorithm: median, best and worst objective, parameters ended on a bound,
// median wall time) and study.png.
// The study itself is the run API's (api/api.hpp); this prints what it did.
#include <cstdio>

#include "cli.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/tune/api/api.hpp"

namespace ftc::cli {
namespace {

struct StudyCli {
  std::string job;
  std::string algorithms;
  std::string seeds;
  std::int64_t budget = 0;
  int threads = 0;
  std::string out;
};

int run_study(const StudyCli& o, const Globals& g) {
  const tune::Job job = tune::load_job(o.job);
  // Checked before the lists, as the study checks it.
  if (!job.tuning)
    throw InputError(o.job, "/tuning", "is required by ftctune study (what should be tuned?)");
  tune::StudyOptions so;
  so.job_file = o.job;
  so.algorithms = tune::parse_algorithm_list(o.algorithms);
  so.seeds = tune::parse_seed_list(o.seeds);
  so.budget = o.budget;
  so.threads = o.threads;
  so.out = o.out;
  so.seeds_text = o.seeds;
  so.command = "ftctune study " + o.job + " --algorithms " + o.algorithms + " --seeds " + o.seeds +
               " --budget " + std::to_string(o.budget);
  so.log = spdlog_log();
  const tune::StudyResult r = tune::run_study(job, so);
  if (!g.quiet) {
    std::printf("%s", tune::study_table(r.rows).c_str());
    std::printf("wrote %s, %s, %s\n", r.csv.c_str(), r.markdown.c_str(), r.figure.c_str());
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
