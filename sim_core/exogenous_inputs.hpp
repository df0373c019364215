#pragma once
// The exogenous inputs of a simulation, the disturbance Δ(t) and the fault effects, on the grid
// of RK4's stage times: the host's side of the closed loop (plants/lane_host.hpp writes them
// into the rows a kernel reads, lanes/pack.hpp's ExoRows). Private to sim_core.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "ftc/sim/disturbance.hpp"
#include "ftc/sim/faults.hpp"
#include "ftc/sim/types.hpp"
#include "sincos.hpp"

namespace ftc::sim::detail {

// Δ(t) and the fault effect depend on time only, and RK4 asks for them on the grid of half
// steps t_k, t_k + h/2, t_k + h, ... (the midpoint serves two stages, the end of a step is the
// next step's start). They are filled a block of Phasor::kMaxSteps half steps at a time: the
// sinusoids advance along the grid by rotation from an anchor (lanes/elementary.hpp) at the block's
// first instant, into one table per sinusoid, and Disturbance::evaluate and FaultSet::evaluate then
// run each term over the whole block. Term by term over a block is a few instructions per instant,
// where one instant at a time spent about 300 on bookkeeping. The block is of fixed size, so
// memory does not grow with the duration.
template <int N, int M>
class ExogenousInputs {
 public:
  struct Entry {
    Vec<N> disturbance = Vec<N>::Zero();
    FaultEffect<M> fault;
  };

  ExogenousInputs(const Disturbance& d, const FaultSet& f, double sample_time, int substeps)
      : dist_(d),
        faults_(f),
        Ts_(sample_time),
        h_(sample_time / substeps),
        substeps_(substeps),
        phasors_(phasors_of(d.terms(), 0.5 * h_)),
        n_dist_(phasors_.size()) {
    for (const Phasor& p : phasors_of(f.faults(), 0.5 * h_)) phasors_.push_back(p);
    sin_.resize(phasors_.size() * kInstants);
    cos_.resize(phasors_.size() * kInstants);
    // Only a bias fault reads its cosine (FaultSet::evaluate), and only from its onset on.
    for (std::size_t i = 0; i < f.faults().size(); ++i)
      if (f.faults()[i].type == FaultType::bias) bias_.push_back(i);
    active_.reserve(phasors_.size());  // the loop allocates nothing
  }

  // The inputs at the start, midpoint and end of substep j of sample k: three consecutive
  // entries. Steps must be asked for in order, each once.
  const Entry* step(std::int64_t k, int j) {
    if (used_ == kSteps) {
      fill(k, j);
      used_ = 0;
    }
    return &entries_[2 * used_++];
  }

 private:
  static constexpr int kSteps = Phasor::kMaxSteps / 2;  // RK4 steps per block
  static constexpr int kInstants = 2 * kSteps + 1;      // half-step instants per block

  // The instants of the block's steps from substep j of sample k on: each step's start
  // k·Ts + j·h, midpoint and end, the end of a sample's last substep formed as (k+1)·Ts so that
  // it is the very double at which the next sample starts.
  void fill(std::int64_t k, int j) {
    for (int s = 0; s < kSteps; ++s) {
      const double t = static_cast<double>(k) * Ts_;
      const double tj = t + j * h_;
      if (s == 0) t_[0] = tj;
      t_[2 * s + 1] = tj + 0.5 * h_;
      t_[2 * s + 2] = j == substeps_ - 1 ? static_cast<double>(k + 1) * Ts_ : tj + h_;
      if (++j == substeps_) {
        j = 0;
        ++k;
      }
    }
    // The phasors whose values the block reads: every disturbance term's, and a bias fault's
    // once the block reaches its onset (before it, ρ = 0 and FaultSet::evaluate reads no
    // cosine; t < onset for every instant of the block when it holds for the last one). Each
    // phasor is anchored at the block's first instant, so a table left out changes no other.
    active_.clear();
    for (std::size_t i = 0; i < n_dist_; ++i) active_.push_back(i);
    for (const std::size_t i : bias_)
      if (!(t_[kInstants - 1] < faults_.faults()[i].onset)) active_.push_back(n_dist_ + i);
    std::size_t first = 0;
    for (; first + 4 <= active_.size(); first += 4) tabulate<4>(first);
    for (; first + 2 <= active_.size(); first += 2) tabulate<2>(first);
    if (first < active_.size()) tabulate<1>(first);

    dist_.evaluate(
        kInstants,
        [&](std::size_t i, std::size_t n, Shape shape) {
          return (shape == Shape::sin ? sin_ : cos_)[i * kInstants + n];
        },
        [&](std::size_t n) -> Vec<N>& { return entries_[n].disturbance; });
    faults_.evaluate(
        t_, [&](std::size_t i, std::size_t n) { return cos_[(n_dist_ + i) * kInstants + n]; },
        [&](std::size_t n) -> FaultEffect<M>& { return entries_[n].fault; });
  }

  // The phasors active_[a .. a + G - 1] over the block. Local copies keep each rotation in
  // registers, and a group advances together so that the CPU overlaps their dependency chains.
  template <int G>
  void tabulate(std::size_t a) {
    std::array<Phasor, G> q;
    double* sin_of[G];
    double* cos_of[G];
    for (int g = 0; g < G; ++g) {
      const std::size_t i = active_[a + g];
      q[g] = phasors_[i];
      q[g].anchor(t_[0]);
      sin_of[g] = &sin_[i * kInstants];
      cos_of[g] = &cos_[i * kInstants];
    }
    for (int n = 0; n < kInstants; ++n)
      for (int g = 0; g < G; ++g) {
        if (n > 0) q[g].advance();
        sin_of[g][n] = q[g].sin();
        cos_of[g][n] = q[g].cos();
      }
  }

  const Disturbance& dist_;
  const FaultSet& faults_;
  double Ts_, h_;
  int substeps_;
  std::vector<Phasor> phasors_;  // the disturbance terms', then the faults'; sized once
  std::size_t n_dist_;
  std::vector<double> sin_, cos_;    // per phasor, its values at the block's instants
  std::vector<std::size_t> bias_;    // the bias faults' indices
  std::vector<std::size_t> active_;  // the phasors tabulated for the current block
  std::array<double, kInstants> t_{};
  std::array<Entry, kInstants> entries_;
  int used_ = kSteps;  // steps of the current block handed out
};

}  // namespace ftc::sim::detail
