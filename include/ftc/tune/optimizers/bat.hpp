#pragma once
// The Bat algorithm (paper §5, Appendix A) in the generational form of the ftctune spec.
//
// Per bat i: position x_i, velocity v_i, loudness A_i, pulse rate r_i, fitness J_i; x* the best
// position found. Initialisation: x_i ~ U(lb, ub), v_i ~ U(0, 1)^d, A_i = A0, r_i = r0, and the
// population is evaluated as one batch. Each iteration t = 1..T, with x* as it was at the start:
//
//   f_i = f_min + (f_max - f_min) β,  β ~ U(0, 1)
//   v_i += (x* - x_i) f_i                    (eq. 37 with the sign that moves bats toward x*)
//   c_i  = clamp(x_i + v_i)
//   if U(0,1) > r_i:  c_i = clamp(x* + ε Ā),  ε ~ U(-1, 1)^d, Ā the mean loudness   (eq. 39)
//
// then all c_i are evaluated as one batch and, in bat order,
//
//   if U(0,1) < A_i and J(c_i) ≥ J_i:  x_i = c_i, J_i = J(c_i), A_i *= loudness_decay,
//                                       r_i = r0 (1 - exp(-pulse_rate_growth · t))   (eqs. 40, 41)
//   if J(c_i) > J(x*):  x* = c_i   (whether or not the bat accepted it: the best point found is
//                                   never lost)
//
// Random numbers are drawn in exactly this order: for initialisation, per bat x_i then v_i; per
// iteration, per bat β, the pulse test and (if taken) ε; then per bat the loudness test. The
// loudness tests are drawn before the batch is evaluated (nothing is drawn in between, so they
// are the same numbers), which gives each candidate its cap (issue 27): its bat's J_i when the
// test passes, J(x*) at the start of the iteration otherwise.
#include <string>
#include <utility>
#include <vector>

#include "ftc/tune/optimizers/optimizer.hpp"

namespace ftc::tune {

// Settings of the Bat algorithm (job: tuning.algorithm with "type": "bat"); the defaults are the
// paper's Table 1.
struct BatSettings {
  int population = 10;  // M
  int iterations = 10;  // T
  double f_min = 0.0;
  double f_max = 2.0;
  double loudness = 0.95;   // A0
  double pulse_rate = 0.9;  // r0
  double loudness_decay = 0.9;
  double pulse_rate_growth = 0.9;

  // Every bad field, each with `path` + "/" + its name.
  std::vector<FieldError> validate(const std::string& path = "") const;
};

// The frequency move of one bat: v += (best - x) f, returns clamp(x + v). Public for testing.
Decision bat_frequency_move(const SearchSpace& space, const Decision& x, Decision& v,
                            const Decision& best, double f);

// What moves a bat, in the Bat algorithm and in the Pareto Bat algorithm (pareto_bat.hpp) alike:
// its position, velocity, loudness and pulse rate, and the steps above on them. Each draws its
// random numbers in the order given at the top of this file.
struct BatMotion {
  Decision x, v;
  double loudness = 0.0, pulse_rate = 0.0;

  // Initialisation: x ~ U(lb, ub), then v ~ U(0, 1)^d; A = A0, r = r0.
  void start(const BatSettings& s, const SearchSpace& space, Rng& rng);
  // The candidate: β, the frequency move toward `leader` (x* or, for a front, a leader from the
  // archive), then the pulse test and, when taken, the walk clamp(leader + ε Ā) (eq. 39).
  Decision candidate(const BatSettings& s, const SearchSpace& space, Rng& rng,
                     const Decision& leader, double mean_loudness);
  // Moving to an accepted candidate: x = c, A *= loudness_decay, r = `pulse` (eqs. 40, 41).
  void accept(const Decision& c, const BatSettings& s, double pulse);
  // The checkpoint's fields (x, v, loudness, pulse_rate) and their inverse, which checks each
  // (a position inside the space, a finite velocity, A in [0, A0], r in [0, r0]) at `at`.
  nlohmann::json to_json() const;
  static BatMotion from_json(const nlohmann::json& b, const std::string& at,
                             const BatSettings& s, const SearchSpace& space);
};
// r0 (1 - exp(-γ t)), with ftctune's exp so that the schedule is the same bits on every CPU.
double bat_pulse_rate(const BatSettings& s, int t);
// The mean loudness Ā and pulse rate of a population, summed in bat order.
template <class B>
std::pair<double, double> bat_means(const std::vector<B>& bats) {
  double loudness = 0.0, pulse_rate = 0.0;
  for (const B& b : bats) {
    loudness += b.loudness;
    pulse_rate += b.pulse_rate;
  }
  const double n = static_cast<double>(bats.size());
  return {loudness / n, pulse_rate / n};
}

class BatAlgorithm final : public GenerationalOptimizer {
 public:
  struct Bat : BatMotion {
    double fitness = 0.0;
  };

  // The settings must be valid (BatSettings::validate).
  BatAlgorithm(const BatSettings& settings, std::uint64_t seed, const SearchSpace& space);

  void initialize(BatchFitness& fitness) override;
  void iterate(BatchFitness& fitness) override;
  nlohmann::json state() const override;
  void restore(const nlohmann::json& state) override;

  const std::vector<Bat>& bats() const { return bats_; }
  const Decision& best() const { return best_; }
  double best_fitness() const { return best_fitness_; }

 private:
  void record_iteration();

  BatSettings settings_;
  std::vector<Bat> bats_;
};

// The registry entry ("bat").
AlgorithmInfo bat_algorithm_info();

}  // namespace ftc::tune
