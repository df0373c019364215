#pragma once
// ftctune's own multi-objective Bat algorithm, for a job with two or more soft goals (issue 26):
// "type": "bat" with the Bat settings of bat.hpp runs it. It follows Yang's multi-objective bat
// algorithm (X.-S. Yang, "Bat algorithm for multi-objective optimisation", Int. J. Bio-Inspired
// Computation 3(5), 267-274, 2011) for the bats' moves, and NSGA-II (K. Deb, A. Pratap,
// S. Agarwal, T. Meyarivan, "A fast and elitist multiobjective genetic algorithm: NSGA-II",
// IEEE Trans. Evol. Comput. 6(2), 182-197, 2002) for non-dominated sorting, crowding distance
// and constrained domination. Where it departs from Yang (who scalarises the goals with random
// weights each iteration and keeps one best per weight):
//   - the point a bat flies toward (x* of eq. 37 and 39) is a leader drawn per bat from an
//     external archive of non-dominated feasible points by a binary tournament on crowding
//     distance (the less crowded wins, as in multi-objective particle swarms), or, while no
//     feasible point is known, from the population's first front under constrained domination;
//   - a bat accepts its candidate (loudness test as in bat.hpp) when the candidate is not
//     constrained-dominated by the bat's position (the analogue of J(c) >= J(x));
//   - crowding distances are measured on log10 of each goal (goals span decades; the
//     hypervolume is measured there too), values at or below kLogFloor counting as kLogFloor.
//
// One iteration t = 1..T, with the archive and the population as they are at its start:
//   per bat i (in order): two draws k1, k2 = floor(U n) into the leader pool of n points; the
//     leader L_i is the one of larger crowding distance (k1 on a tie); then f_i (β), the pulse
//     test and (if taken) ε as in bat.hpp, with L_i in place of x*;
//   per bat i (in order): the loudness draw U_i, drawn before the evaluation so that the
//     fitness may cap the candidates whose value changes nothing (FrontCap, issue 42);
//   all candidates are evaluated as one batch (BatchFitness::objective_vectors_capped);
//   per bat i (in order): the loudness test U_i < A_i, acceptance as above (A_i *= decay,
//     r_i = r(t));
//     then the candidate enters the archive (in bat order) if it is feasible, finite and not
//     dominated by (or equal to) a member; members it dominates leave; above the capacity
//     max(100, M) the member of least crowding distance (the first such) leaves.
// The best point x* of the history is the archive's point of least first soft goal (without
// an archive: the population's least violation, then least first goal), its fitness
// constrained_fitness(1/f1, V).
#include <cstddef>
#include <string>
#include <vector>

#include "ftc/tune/optimizers/bat.hpp"
#include "ftc/tune/optimizers/optimizer.hpp"

namespace ftc::tune {

namespace pareto {

// Values at or below this count as it on a log scale (a goal that can be 0: saturation).
inline constexpr double kLogFloor = 1e-300;
// log10(max(v, kLogFloor)); +inf for +inf or NaN.
double log_value(double v);
// Constrained domination (Deb et al. 2002): a feasible point dominates an infeasible one; of two
// infeasible ones the smaller violation dominates; of two feasible ones, a dominates b when it is
// no worse in every value and better in one (NaN counts as +inf).
bool dominates(const ObjectiveVector& a, const ObjectiveVector& b);
// Fast non-dominated sorting (Deb et al. 2002) under dominates(): the fronts, first (the
// non-dominated points) first, each in ascending index order.
std::vector<std::vector<std::size_t>> nondominated_sort(const std::vector<ObjectiveVector>& points);
// NSGA-II's crowding distance of the points `front` (indices into points), in front's order, on
// log_value of each goal: +inf for the extremes of each goal; an objective whose range over the
// front is 0 or not finite adds nothing (but still marks its extremes).
std::vector<double> crowding_distance(const std::vector<ObjectiveVector>& points,
                                      const std::vector<std::size_t>& front);

}  // namespace pareto

class ParetoBatAlgorithm final : public GenerationalOptimizer {
 public:
  struct Bat : BatMotion {
    ObjectiveVector f;
  };
  struct Member {
    Decision x;
    ObjectiveVector f;
  };

  // The settings must be valid (BatSettings::validate); objectives >= 2.
  ParetoBatAlgorithm(const BatSettings& settings, std::uint64_t seed, const SearchSpace& space,
                     std::size_t objectives);

  void initialize(BatchFitness& fitness) override;
  void iterate(BatchFitness& fitness) override;
  nlohmann::json state() const override;
  void restore(const nlohmann::json& state) override;

  const std::vector<Bat>& bats() const { return bats_; }
  const std::vector<Member>& archive() const { return archive_; }
  std::size_t capacity() const { return capacity_; }

 private:
  // Offers a point to the archive (the rule above).
  void offer(const Decision& x, const ObjectiveVector& f);
  // x* and its fitness from the archive (or the population), then the history row.
  void record_iteration();

  BatSettings settings_;
  std::size_t objectives_;
  std::size_t capacity_;
  std::vector<Bat> bats_;
  std::vector<Member> archive_;
};

// The registry entry "bat": the Bat algorithm of bat.hpp, which runs this one for a front.
AlgorithmInfo pareto_bat_info();

}  // namespace ftc::tune
