#pragma once
// The hypervolume of a set of points (minimised objectives) against a reference point: the
// measure of the region the points dominate and the reference point bounds. Computed by pagmo2's
// hypervolume utilities (pagmo::hypervolume) in the pagmo adapter module
// (tuner/optimizers/pagmo_plugin.hpp), loaded on first use; exact in 2 and 3 dimensions.
// Points that are not strictly better than the reference in every coordinate (or not finite)
// add nothing and are left out; no point left gives 0. Throws InputError when the module is
// missing, std::invalid_argument for points of another dimension than the reference's.
#include <vector>

namespace ftc::tune {

double hypervolume(const std::vector<std::vector<double>>& points,
                   const std::vector<double>& reference);

}  // namespace ftc::tune
