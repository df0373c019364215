// libFuzzer target: an optimiser's saved state, as a checkpoint holds it (state.optimizer),
// restored by the Bat algorithm, random search or pagmo's pso_gen (the first byte picks which;
// the rest is the state's JSON). Checkpoints are input: whatever their digest, a bad state must be
// an InputError, and a state restore() accepts must continue to the end of the run without
// anything escaping, with the iteration and evaluation counts of a sound run.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "ftc/runtime/json_reader.hpp"
#include "ftc/tune/optimizers/optimizer.hpp"
#include "fuzz.hpp"
#include "json_mutator.hpp"

using namespace ftc;
using namespace ftc::tune;
using nlohmann::json;

namespace {

const SearchSpace& space() {
  static const SearchSpace s{{"a", "b"}, {-5.0, 0.0}, {5.0, 2.0}};
  return s;
}

const AlgorithmPtr& algorithm(unsigned which) {
  static const AlgorithmPtr all[] = {
      make_algorithm({{"type", "bat"}, {"population", 4}, {"iterations", 3}}),
      make_algorithm({{"type", "random"}, {"population", 4}, {"iterations", 3}}),
      make_algorithm(
          {{"type", "pagmo"}, {"name", "pso_gen"}, {"population", 4}, {"generations", 3}}),
  };
  return all[which % 3];
}

double sphere(const Decision& x) {
  double s = 0.0;
  for (double v : x) s += v * v;
  return 1.0 / (1.0 + s);
}

}  // namespace

// The first byte picks the algorithm; the state after it is mutated as a JSON document.
extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size,
                                               std::size_t max_size, unsigned int seed) {
  return ftc::fuzz::mutate_json(data, size, max_size, seed, /*offset=*/1);
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const AlgorithmPtr& a = algorithm(data[0]);
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  fuzz::input_errors_only([&] {
    const json state = json_io::parse_json_text(text, "fuzz");
    FunctionFitness fitness(sphere);
    // What restore() refuses is an InputError (run_optimizer turns a stray json::exception
    // into one); an accepted state runs on to the end of the run.
    const auto optimizer = a->make(1, space());
    const OptimizationResult r = run_optimizer(*optimizer, fitness, {}, &state, "/optimizer");
    // The whole input, selector byte included, so that a replay picks the same algorithm.
    fuzz::remember_accepted(std::string_view(reinterpret_cast<const char*>(data), size));
    fuzz::nothing_escapes("a run resumed from an accepted state", [&] {
      if (!r.completed || optimizer->iteration() != a->iterations())
        fuzz::finding("a resumed run stopped at iteration " +
                      std::to_string(optimizer->iteration()) + " of " +
                      std::to_string(a->iterations()));
      if (r.history.size() != static_cast<std::size_t>(a->iterations()) + 1)
        fuzz::finding("a resumed run has " + std::to_string(r.history.size()) +
                      " history rows, not " + std::to_string(a->iterations() + 1));
      if (r.evaluations < 0 || r.evaluations > a->evaluations())
        fuzz::finding("a resumed run counts " + std::to_string(r.evaluations) +
                      " evaluations, beyond its budget of " + std::to_string(a->evaluations()));
      if (r.best.size() != space().dimension())
        fuzz::finding("a resumed run's best point has " + std::to_string(r.best.size()) +
                      " coordinates");
    });
  });
  return 0;
}
