// The algorithms a job can name under tuning.algorithm.type. To add one: give it a settings
// struct with a schema::Object (or an AlgorithmSettings of its own), an Optimizer, and a line
// here.
#include "ftc/tune/optimizers/bat.hpp"
#include "ftc/tune/optimizers/optimizer.hpp"
#include "ftc/tune/optimizers/pagmo.hpp"
#include "ftc/tune/optimizers/random_search.hpp"

namespace ftc::tune {

const std::vector<AlgorithmInfo>& algorithms() {
  static const std::vector<AlgorithmInfo> all = {bat_algorithm_info(), random_search_info(),
                                                  pagmo_algorithm_info()};
  return all;
}

}  // namespace ftc::tune
