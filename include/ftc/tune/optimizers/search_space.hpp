#pragma once
// A box-bounded continuous search space: the decision vector x ∈ [lower, upper]^d, one named
// coordinate per tuned parameter.
#include <algorithm>
#include <cstddef>
#include <string>
#include <vector>

namespace ftc::tune {

using Decision = std::vector<double>;

struct SearchSpace {
  std::vector<std::string> names;
  std::vector<double> lower;
  std::vector<double> upper;

  std::size_t dimension() const { return lower.size(); }
  double clamp(std::size_t j, double v) const { return std::clamp(v, lower[j], upper[j]); }
  bool contains(const Decision& x) const {
    for (std::size_t j = 0; j < x.size(); ++j)
      if (!(x[j] >= lower[j] && x[j] <= upper[j])) return false;
    return x.size() == dimension();
  }
};

}  // namespace ftc::tune
