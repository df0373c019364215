#include "ftc/tune/evaluators/batch_evaluator.hpp"

#include <algorithm>
#include <atomic>
#include <exception>
#include <stdexcept>
#include <tuple>

namespace ftc::tune {
namespace {

std::uint64_t next_identity() {
  static std::atomic<std::uint64_t> counter{0};
  return ++counter;
}

}  // namespace

SimulationSet::SimulationSet(sim::PlantSpec plant, std::vector<sim::Scenario> scenarios,
                             std::vector<sim::SimulationOptions> options)
    : SimulationSet(plant, sim::make_plant(plant), std::move(scenarios), std::move(options)) {}

SimulationSet::SimulationSet(sim::PlantSpec spec, std::shared_ptr<const sim::AnyPlant> plant,
                             std::vector<sim::Scenario> scenarios,
                             std::vector<sim::SimulationOptions> options)
    : spec_(std::move(spec)),
      plant_(std::move(plant)),
      scenarios_(std::move(scenarios)),
      options_(std::move(options)),
      identity_(next_identity()) {
  if (options_.size() != scenarios_.size())
    throw std::invalid_argument("a simulation set needs one options per scenario (" +
                                std::to_string(scenarios_.size()) + " scenarios, " +
                                std::to_string(options_.size()) + " options)");
}

SimulationSet SimulationSet::with_scenarios(std::vector<sim::Scenario> scenarios,
                                            std::vector<sim::SimulationOptions> options) const {
  return SimulationSet(spec_, plant_, std::move(scenarios), std::move(options));
}

sim::SimulationOptions task_options(const SimulationBatch& batch, std::size_t k) {
  const SimulationTask& task = batch.tasks[k];
  sim::SimulationOptions o = batch.set.options(task.scenario);
  o.record_every = task.record ? batch.record_every : 0;
  return o;
}

TaskResult run_task(const SimulationBatch& batch, std::size_t k) {
  TaskResult r;
  const SimulationTask& task = batch.tasks[k];
  try {
    sim::SimulationResult s =
        batch.set.plant().simulate(batch.candidates[task.candidate],
                                   batch.set.scenario(task.scenario), task_options(batch, k));
    r.metrics = std::move(s.metrics);
    r.trajectory = std::move(s.trajectory);
    r.model_invalid = s.model_invalid;
  } catch (const std::exception& e) {
    r.error = e.what();
  } catch (...) {
    r.error = "unknown error";
  }
  return r;
}

void run_pack(const SimulationBatch& batch, std::span<const std::size_t> pack,
              std::span<TaskResult> results) {
  const std::size_t n = pack.size();
  try {
    std::vector<sim::SimulationOptions> options(n);
    std::vector<sim::PackTask> tasks(n);
    for (std::size_t i = 0; i < n; ++i) {
      const SimulationTask& t = batch.tasks[pack[i]];
      options[i] = task_options(batch, pack[i]);
      tasks[i] = {&batch.candidates[t.candidate], &batch.set.scenario(t.scenario), &options[i]};
    }
    std::vector<sim::SimulationResult> out(n);
    std::vector<std::string> errors(n);
    batch.set.plant().simulate_pack(tasks, out, errors);
    for (std::size_t i = 0; i < n; ++i) {
      TaskResult& r = results[pack[i]];
      r.error = std::move(errors[i]);
      if (!r.error.empty()) continue;
      r.metrics = std::move(out[i].metrics);
      r.trajectory = std::move(out[i].trajectory);
      r.model_invalid = out[i].model_invalid;
    }
  } catch (const std::exception& e) {  // out of memory: every task of the pack fails
    for (std::size_t k : pack) results[k].error = e.what();
  } catch (...) {
    for (std::size_t k : pack) results[k].error = "unknown error";
  }
}

std::vector<std::vector<std::size_t>> plan_packs(const SimulationBatch& batch, int workers) {
  const std::size_t width = static_cast<std::size_t>(std::max(1, batch.set.plant().pack_width()));
  // Groups of tasks whose loops have the same shape, in order of first appearance.
  using Key = std::tuple<double, int, std::int64_t>;
  std::vector<Key> keys;
  std::vector<std::vector<std::size_t>> groups;
  for (std::size_t k = 0; k < batch.tasks.size(); ++k) {
    const sim::Scenario& s = batch.set.scenario(batch.tasks[k].scenario);
    const Key key{s.sample_time, s.substeps, s.samples()};
    const auto it = std::find(keys.begin(), keys.end(), key);
    if (it == keys.end()) {
      keys.push_back(key);
      groups.push_back({k});
    } else {
      groups[static_cast<std::size_t>(it - keys.begin())].push_back(k);
    }
  }
  // Within a group, the tasks of one scenario next to each other: lanes of one scenario share its
  // disturbance and fault tables (sim_core/plants/lane_host.hpp), or broadcast them when a whole
  // pack has one scenario, so that several candidates on the same members cost less host work.
  for (auto& g : groups)
    std::stable_sort(g.begin(), g.end(), [&](std::size_t a, std::size_t b) {
      return batch.tasks[a].scenario < batch.tasks[b].scenario;
    });
  std::size_t full = 0;
  for (const auto& g : groups) full += (g.size() + width - 1) / width;
  // Fewer full packs than workers: split each group further, down to one task a pack.
  std::size_t size = width;
  while (size > 1 && full < static_cast<std::size_t>(std::max(1, workers))) {
    --size;
    full = 0;
    for (const auto& g : groups) full += (g.size() + size - 1) / size;
  }
  std::vector<std::vector<std::size_t>> packs;
  for (const auto& g : groups) {
    const std::size_t count = (g.size() + size - 1) / size;
    // Even sizes: count packs of ⌈|g|/count⌉ or one less.
    std::size_t first = 0;
    for (std::size_t p = 0; p < count; ++p) {
      const std::size_t take = (g.size() - first + (count - p) - 1) / (count - p);
      packs.emplace_back(g.begin() + static_cast<std::ptrdiff_t>(first),
                         g.begin() + static_cast<std::ptrdiff_t>(first + take));
      first += take;
    }
  }
  return packs;
}

std::vector<TaskResult> SerialEvaluator::run(const SimulationBatch& batch) {
  std::vector<TaskResult> results(batch.tasks.size());
  for (const std::vector<std::size_t>& pack : plan_packs(batch, 1)) {
    if (interrupted()) throw Interrupted();
    run_pack(batch, pack, results);
  }
  return results;
}

}  // namespace ftc::tune
