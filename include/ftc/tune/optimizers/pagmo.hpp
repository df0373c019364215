#pragma once
// The algorithms of pagmo2 as ftctune optimisers (job: tuning.algorithm with "type": "pagmo"):
//
//   {"type": "pagmo", "name": "pso_gen", "population": 10, "generations": 10,
//    "settings": {"omega": 0.7298, ...}}
//
// `settings` holds the pagmo algorithm's own constructor options by their pagmo names, with
// pagmo's defaults; the generation count (`generations`, pagmo's gen), the seed and the
// verbosity are ftctune's. pagmo minimises, so the adapter hands it the objective f = 1/J (the
// job's objective) of each candidate, and kDivergedObjective for a candidate that diverged or
// could not be simulated. Each iterate() delivers one more generation of one uninterrupted pagmo
// run (replayed from the run's log of fitness values, see tuner/optimizers/pagmo.cpp), so
// progress lines, history rows and per-iteration checkpoints work as for the Bat algorithm.
// pagmo's algorithm and population are seeded from the run's seed; the checkpoint is the log.
//
// For a job with two or more soft goals the multi-objective algorithms (nsga2, moead, nspso, maco
// = MHACO) search the front: pagmo minimises log10 of each soft goal (the space the front's
// hypervolume is measured in), kDivergedObjective for a goal that is not finite. They take no
// constraints, so hard goals are constrained domination (Deb et al. 2002) written into the
// objectives: an infeasible candidate gets kDivergedObjective·(2 + V/(1 + V)) in every
// coordinate, which any feasible candidate dominates and which orders infeasible ones by their
// violation V. The checkpoint is the log of objective vectors.
//
// pagmo and Boost stay inside tuner/optimizers/pagmo.cpp: nothing here includes them.
#include <cstdint>
#include <string>
#include <vector>

#include "ftc/tune/optimizers/optimizer.hpp"

namespace ftc::tune {

// The objective pagmo sees for a candidate that diverged or could not be simulated (J = 0).
// Finite because several pagmo algorithms compute differences and ratios of objectives, which
// turn NaN on infinities.
inline constexpr double kDivergedObjective = 1e30;

// One supported pagmo algorithm, with its default settings.
struct PagmoAlgorithmInfo {
  std::string name;         // pagmo's class name: "cmaes", "pso_gen", ...
  std::string description;  // one line
  bool batch = false;       // evaluates each generation as one batch (pagmo's bfe)
  int min_population = 1;   // smallest population pagmo accepts with the default settings
  // Evaluations per generation: population × per_member + fixed.
  int per_member = 1;
  int fixed = 0;
  // A multi-objective algorithm (NSGA-II, MOEA/D, NSPSO, MHACO): it searches the Pareto front of
  // a job with two or more soft goals, and only that.
  bool front = false;
};

// The supported algorithms, sorted by name.
const std::vector<PagmoAlgorithmInfo>& pagmo_algorithms();
const PagmoAlgorithmInfo* find_pagmo_algorithm(const std::string& name);

// The registry entry ("pagmo").
AlgorithmInfo pagmo_algorithm_info();

}  // namespace ftc::tune
