// The algorithms a job can name under tuning.algorithm.type. To add one: give it a settings
// struct with a schema::Object (or an AlgorithmSettings of its own), an Optimizer, and a line
// here.
#include "ftc/tune/optimizers/bat.hpp"
#include "ftc/tune/optimizers/optimizer.hpp"
#include "ftc/tune/optimizers/pagmo.hpp"
#include "ftc/tune/optimizers/pareto_bat.hpp"
#include "ftc/tune/optimizers/random_search.hpp"

namespace ftc::tune {

const std::vector<AlgorithmInfo>& algorithms() {
  static const std::vector<AlgorithmInfo> all = {
      pareto_bat_info(),  // "bat": the Bat algorithm, and its Pareto form for fronts
      // Random search samples a front as it samples a best point: its draws ignore the fitness.
      with_front(random_search_info(),
                 [](const AlgorithmSettings& s, std::uint64_t seed, const SearchSpace& space,
                    std::size_t) { return s.make(seed, space); }),
      pagmo_algorithm_info()};
  return all;
}

}  // namespace ftc::tune
