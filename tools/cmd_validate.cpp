// ftctune validate JOB: check a job file and say what running it would cost. `-` reads the job
// from standard input; --json prints what was found as one JSON document.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <iterator>
#include <nlohmann/json.hpp>

#include "cli.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/tune/job/ensemble.hpp"

namespace ftc::cli {
namespace {

using nlohmann::json;

// How errors name a job read from standard input.
constexpr const char* kStdinSource = "(stdin)";

struct ValidateCli {
  std::string file;
  bool json_output = false;
};

tune::Job read_job(const std::string& file) {
  if (file != "-") return tune::load_job(file);
  // A scenarios file the job names is read relative to the working directory.
  const std::string text{std::istreambuf_iterator<char>(std::cin),
                         std::istreambuf_iterator<char>()};
  if (std::cin.bad()) throw InputError(kStdinSource, "", "cannot read standard input");
  return tune::parse_job_text(text, kStdinSource, std::filesystem::current_path());
}

int run_validate(const ValidateCli& o, const Globals& g) {
  const std::string& file = o.file;
  const std::string name = file == "-" ? kStdinSource : file;
  try {
    const tune::Job job = read_job(file);
    const std::int64_t evals = job.tuning ? job.tuning->algorithm->evaluations() : 1;
    const std::int64_t steps = job.steps_per_evaluation();
    const std::string members = job.ensemble
                                    ? " (" + std::to_string(job.scenarios.size()) + " listed + " +
                                          std::to_string(job.ensemble->count) + " ensemble members)"
                                    : "";
    // A listed scenario no gains can control once its faults start is valid, but the objective
    // leaves it out (a run refuses a job of nothing else): say so before anyone runs it.
    json unrecoverable = json::array();
    {
      const std::unique_ptr<sim::AnyPlant> plant = sim::make_plant(job.plant);
      for (std::size_t i = 0; i < job.scenarios.size(); ++i)
        if (!plant->recoverable(job.scenarios[i])) {
          unrecoverable.push_back(job.scenarios[i].name);
          if (!o.json_output)
            std::fprintf(stderr,
                         "ftctune: warning: /scenarios/%zu: scenario \"%s\" is unrecoverable: no "
                         "gains can control it once its faults start, so the objective leaves it "
                         "out\n",
                         i, job.scenarios[i].name.c_str());
        }
    }
    if (o.json_output) {
      const json doc = {{"command", "validate"},
                        {"file", name},
                        {"valid", true},
                        {"job", job.name},
                        {"tuning", static_cast<bool>(job.tuning)},
                        {"evaluations", evals},
                        {"scenarios", job.scenario_count()},
                        {"listed_scenarios", job.scenarios.size()},
                        {"ensemble_members", job.ensemble ? job.ensemble->count : 0},
                        {"unrecoverable_scenarios", unrecoverable},
                        {"steps_per_evaluation", steps},
                        {"steps", static_cast<double>(evals) * static_cast<double>(steps)},
                        {"step_cost_per_evaluation", job.step_cost_per_evaluation()},
                        {"step_cost", static_cast<double>(evals) * job.step_cost_per_evaluation()}};
      std::printf("%s\n", doc.dump(2).c_str());
    } else if (!g.quiet) {
      // Faults make a step dearer (tune::kFaultStepCost): the cost the service's budget counts.
      const double cost = static_cast<double>(evals) * job.step_cost_per_evaluation();
      std::string priced;
      if (cost > static_cast<double>(evals) * static_cast<double>(steps)) {
        char buf[160];
        std::snprintf(buf, sizeof buf,
                      " (with its faults, a step with f faults costing 1 + f/%.0f steps: %.3g)",
                      1.0 / tune::kFaultStepCost, cost);
        priced = buf;
      }
      std::printf(
          "%s: valid job \"%s\": %lld evaluation%s x %zu scenario%s%s, %lld simulated steps "
          "per evaluation, %.3g in all%s%s\n",
          name.c_str(), job.name.c_str(), static_cast<long long>(evals), evals == 1 ? "" : "s",
          job.scenario_count(), job.scenario_count() == 1 ? "" : "s", members.c_str(),
          static_cast<long long>(steps), static_cast<double>(evals) * static_cast<double>(steps),
          priced.c_str(), job.tuning ? "" : " (no tuning section: simulate only)");
    }
    return 0;
  } catch (const InputError& e) {
    std::fprintf(stderr, "ftctune: error: %s: %zu problem%s\n", e.source().c_str(),
                 e.errors().size(), e.errors().size() == 1 ? "" : "s");
    // The first kMaxReportedErrors, the rest counted.
    const std::size_t listed = std::min(e.errors().size(), tune::kMaxReportedErrors);
    for (std::size_t i = 0; i < listed; ++i)
      std::fprintf(stderr, "  %s\n", to_string(e.errors()[i]).c_str());
    if (listed < e.errors().size())
      std::fprintf(stderr, "  ... and %zu more (the first %zu are listed)\n",
                   e.errors().size() - listed, listed);
    if (o.json_output) {
      json errors = json::array();
      for (std::size_t i = 0; i < listed; ++i)
        errors.push_back({{"path", e.errors()[i].path}, {"message", e.errors()[i].message}});
      json doc = {{"command", "validate"},
                  {"file", name},
                  {"valid", false},
                  {"source", e.source()},
                  {"errors", errors}};
      if (listed < e.errors().size()) doc["errors_omitted"] = e.errors().size() - listed;
      std::printf("%s\n", doc.dump(2).c_str());
    }
    return 2;
  }
}

}  // namespace

void add_validate_command(CLI::App& app, const Globals& g, Action& action) {
  auto o = std::make_shared<ValidateCli>();
  CLI::App* sub = app.add_subcommand("validate", "Check a job file and list every problem");
  sub->add_option("job", o->file, "Job file (ftctune.job/1), or - to read it from standard input")
      ->required();
  sub->add_flag("--json", o->json_output,
                "Print the result as one JSON document on standard output (also when the job is "
                "invalid: valid false and its errors)");
  sub->callback([&action, &g, o] { action = [&g, o] { return run_validate(*o, g); }; });
}

}  // namespace ftc::cli
