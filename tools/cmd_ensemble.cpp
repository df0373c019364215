// ftctune ensemble JOB: the members of a job's ensemble as an ftctune.scenarios/1 file, which a
// job can name instead of listing its scenarios (to freeze a set, inspect it or edit it).
#include <cstdio>
#include <functional>
#include <string_view>
#include <nlohmann/json.hpp>

#include "cli.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/job/ensemble.hpp"

namespace ftc::cli {
namespace {

using nlohmann::json;

struct EnsembleOptions {
  std::string job;
  std::optional<std::uint64_t> seed;
  std::optional<std::int64_t> count;
  std::string out;
};

// The scenarios document, member by member: the bytes of json::dump(2) of the whole document
// (its keys in order: job, scenarios, schema, seed), but never more than one member in memory,
// so that a million members take no more memory than ten.
void write_members(const tune::Job& job, std::uint64_t seed, std::int64_t count,
                   const sim::AnyPlant& plant, int& unrecoverable,
                   const std::function<void(std::string_view)>& out) {
  out("{\n  \"job\": " + json(job.name).dump() + ",\n  \"scenarios\": [");
  std::string chunk;
  for (std::int64_t k = 0; k < count; ++k) {
    const sim::Scenario s = tune::ensemble_member(job, seed, k);
    json j = tune::to_json(s);
    const bool ok = plant.recoverable(s);
    unrecoverable += ok ? 0 : 1;
    j["recoverable"] = ok;
    // Each line of the member indented by the two levels it sits at.
    chunk += k == 0 ? "\n    " : ",\n    ";
    const std::string text = j.dump(2);
    for (char c : text) {
      chunk += c;
      if (c == '\n') chunk += "    ";
    }
    if (chunk.size() >= (1 << 16)) {
      out(chunk);
      chunk.clear();
    }
  }
  chunk += count > 0 ? "\n  ],\n" : "],\n";
  chunk += "  \"schema\": " + json(tune::kScenariosSchema).dump() + ",\n  \"seed\": " +
           json(seed).dump() + "\n}\n";
  out(chunk);
}

int run_ensemble(const EnsembleOptions& o, const Globals& g) {
  const tune::Job job = tune::load_job(o.job);
  if (!job.ensemble) throw InputError(o.job, "/ensemble", "the job has no ensemble to expand");
  const std::uint64_t seed = o.seed.value_or(job.ensemble->seed);
  const std::int64_t count = tune::ensemble_count(job, o.count);
  const std::unique_ptr<sim::AnyPlant> plant = sim::make_plant(job.plant);
  int unrecoverable = 0;
  if (o.out.empty()) {
    write_members(job, seed, count, *plant, unrecoverable, [](std::string_view chunk) {
      std::fwrite(chunk.data(), 1, chunk.size(), stdout);
    });
    return 0;
  }
  tune::write_file_atomic(o.out, [&](const tune::ChunkSink& sink) {
    write_members(job, seed, count, *plant, unrecoverable, sink);
  });
  if (!g.quiet)
    std::printf("wrote %lld members of %s (seed %llu, %d unrecoverable) to %s\n",
                static_cast<long long>(count), job.name.c_str(),
                static_cast<unsigned long long>(seed), unrecoverable, o.out.c_str());
  return 0;
}

}  // namespace

void add_ensemble_command(CLI::App& app, const Globals& g, Action& action) {
  auto opts = std::make_shared<EnsembleOptions>();
  CLI::App* sub = app.add_subcommand(
      "ensemble", "Expand a job's ensemble into a scenarios file (ftctune.scenarios/1)");
  sub->add_option("job", opts->job, "Job file with an ensemble (ftctune.job/1)")->required();
  sub->add_option("--seed", opts->seed, "Seed instead of the ensemble's own")->check(seed_value());
  sub->add_option("--count", opts->count, "Members instead of the ensemble's count");
  sub->add_option("--out", opts->out, "Write to this file (default: standard output)")
      ->check(output_file());
  sub->footer(
      "\nExamples:\n  ftctune ensemble jobs/robust-faults.json --out members.json\n"
      "  ftctune ensemble jobs/robust-faults.json --seed 8 --count 1000 --out held-out.json\n"
      "A job names such a file with \"scenarios\": {\"file\": \"members.json\"}.");
  sub->callback([&action, &g, opts] { action = [&g, opts] { return run_ensemble(*opts, g); }; });
}

}  // namespace ftc::cli
