#pragma once
// The interface between ftctune and its pagmo2 adapter. The adapter is a loadable module
// (ftctune_pagmo.so, built from pagmo.cpp) that pagmo_loader.cpp opens the first time a job names
// a pagmo algorithm: Debian's libpagmo registers its classes with Boost.Serialization in static
// initialisers, which cost every process that links it about 60 ms and 36 MB before main().
// Private to tuner/.
#include <vector>

#include "ftc/tune/optimizers/optimizer.hpp"
#include "ftc/tune/optimizers/pagmo.hpp"

namespace ftc::tune::pagmo_plugin {

struct Api {
  // The module is only usable by the build it came from: the two sides share C++ types.
  const char* build_id;
  const std::vector<PagmoAlgorithmInfo>& (*algorithms)();
  AlgorithmInfo (*info)();
  // pagmo::hypervolume(points).compute(reference), for points each strictly better than the
  // reference in every coordinate (hypervolume.hpp filters them); at least one point.
  double (*hypervolume)(const std::vector<std::vector<double>>& points,
                        const std::vector<double>& reference);
};

inline constexpr const char* kEntryPoint = "ftctune_pagmo_plugin";
inline constexpr const char* kModuleName = "ftctune_pagmo.so";

}  // namespace ftc::tune::pagmo_plugin
