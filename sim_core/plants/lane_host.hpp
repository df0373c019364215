#pragma once
// Any plant's simulations through its batch kernels (lanes/pack.hpp, lanes/closed_loop.hpp):
// grouping into packs, and the host side of a pack (exogenous inputs, metrics, trajectories),
// in plain C++ compiled once, for plant class P. Private to sim_core (plants/plant_adapter.hpp).
#include <algorithm>
#include <bit>
#include <cstdint>
#include <cmath>
#include <array>
#include <span>
#include <deque>
#include <limits>
#include <memory>
#include <tuple>
#include <vector>

#include "ftc/sim/disturbance.hpp"
#include "ftc/sim/faults.hpp"
#include "ftc/sim/isa.hpp"
#include "ftc/sim/metrics.hpp"
#include "ftc/sim/scenario.hpp"
#include "ftc/sim/simulation.hpp"
#include "lanes/pack.hpp"
#include "metrics_accumulator.hpp"
#include "simulation_loop.hpp"

namespace ftc::sim::detail {

// One validated simulation: its controller (checked, α1 resolved), scenario and options, the
// constants of the simulated plant and of the controller's model (the plant's f_constants()).
struct LaneTask {
  ControllerConfig config;
  const Scenario* scenario = nullptr;
  const SimulationOptions* options = nullptr;
  std::array<double, kMaxPlantConstants> truth{}, model{};
  // The simulated plant's operating point and limits per actuator (PackSetup::u0, lo, hi), for
  // a plant that has them.
  std::array<double, kMaxActuators> u0{}, lo{}, hi{};
  SimulationResult* result = nullptr;
};

namespace lane_host {

// Plant P's kernel for an instruction set.
template <class P, int N, int M>
PackKernel<N, M> kernel_for(Isa isa) {
  switch (isa) {
#if defined(FTC_X86_KERNELS)
    case Isa::sse2:
      return &isa_sse2::pack_kernel<P, N, M>;
    case Isa::avx2:
      return &isa_avx2::pack_kernel<P, N, M>;
    case Isa::avx512:
      return &isa_avx512::pack_kernel<P, N, M>;
#endif
    default:
      return &isa_scalar::pack_kernel<P, N, M>;
  }
}

// Whether two disturbances are the same terms, bit for bit (ensemble members share their base's).
inline bool same_terms(const std::vector<DisturbanceTerm>& a,
                       const std::vector<DisturbanceTerm>& b) {
  const auto bits = [](double v) { return std::bit_cast<std::uint64_t>(v); };
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].axis != b[i].axis || a[i].shape != b[i].shape ||
        bits(a[i].amplitude) != bits(b[i].amplitude) ||
        bits(a[i].frequency) != bits(b[i].frequency) || bits(a[i].phase) != bits(b[i].phase))
      return false;
  return true;
}

// The host of one pack: per distinct scenario the faults' effects, per distinct disturbance Δ(t)
// that more than one of its scenarios has (each an ExogenousInputs with the other part empty:
// lanes of one scenario share the first, lanes whose scenarios have the same disturbance terms,
// as an ensemble's members do, the second), per lane its metrics and trajectory. A scenario
// whose disturbance no other scenario of the pack has steps both in one table: a pack of one
// scenario (Table 1's job, a landscape) builds one table, not two.
template <int N, int M>
class Host final : public PackHost<N, M> {
  using Exo = ExoRows<N, M>;

 public:
  Host(std::span<LaneTask* const> lanes, int width, const PackSetup<N, M>& setup)
      : lanes_(lanes.begin(), lanes.end()), width_(width), setup_(setup) {
    // The distinct scenarios and, for each, which distinct disturbance it has.
    std::vector<const Scenario*> scenarios, first_with;  // first_with[d]: d's first scenario
    std::vector<std::size_t> dist_of, users;
    for (std::size_t l = 0; l < lanes_.size(); ++l) {
      const Scenario& s = *lanes_[l]->scenario;
      std::size_t g = 0;
      while (g < scenarios.size() && scenarios[g] != &s) ++g;
      if (g == scenarios.size()) {
        std::size_t d = 0;
        while (d < first_with.size() && !same_terms(first_with[d]->disturbance, s.disturbance)) ++d;
        if (d == first_with.size()) {
          first_with.push_back(&s);
          users.push_back(0);
        }
        ++users[d];
        scenarios.push_back(&s);
        dist_of.push_back(d);
      }
      group_of_.push_back(g);
      std::vector<double> onsets;
      for (const Fault& f : s.faults) onsets.push_back(f.onset);
      const SimulationOptions& o = *lanes_[l]->options;
      MetricContext<M> context;
      context.duration = s.duration;
      for (int j = 0; j < M; ++j) {
        context.lo[j] = setup.limit_lo[j][l];
        context.hi[j] = setup.limit_hi[j][l];
      }
      context.settings = o.metrics;
      metrics_.emplace_back(s.sample_time, o.window, o.extra_windows, std::move(onsets), context);
      SimulationResult& r = *lanes_[l]->result;
      r = SimulationResult{};
      r.trajectory.axes = N;
      r.trajectory.actuators = M;
      if (o.record_every > 0)
        r.trajectory.values.reserve((setup.samples / o.record_every + 1) * r.trajectory.width());
    }
    // A table per disturbance shared by scenarios; the others go with their scenario's faults.
    std::vector<std::size_t> table(first_with.size(), Group::kOwn);
    for (std::size_t d = 0; d < first_with.size(); ++d)
      if (users[d] > 1) {
        table[d] = dists_.size();
        dists_.emplace_back(*first_with[d]);
      }
    for (std::size_t g = 0; g < scenarios.size(); ++g)
      groups_.emplace_back(*scenarios[g], table[dist_of[g]]);
    for (std::size_t l = 0; l < lanes_.size(); ++l)
      groups_[group_of_[l]].lanes.push_back(static_cast<int>(l));
    // Unused lanes repeat lane 0.
    for (int l = static_cast<int>(lanes_.size()); l < width; ++l) groups_[0].lanes.push_back(l);
    for (const Group& g : groups_)
      if (g.dist != Group::kOwn)
        for (const int l : g.lanes) dists_[g.dist].lanes.push_back(l);
    for (Dist& d : dists_) std::sort(d.lanes.begin(), d.lanes.end());
    done_.assign(lanes_.size(), false);
    buffer_.resize(static_cast<std::size_t>(setup.block) * setup.substeps * 3 * Exo::kCount *
                   Exo::stride(setup.shared_inputs, width));
  }

  const double* inputs(std::int64_t k0, int n) override {
    const int S = setup_.substeps;
    // With one scenario one value per row (PackSetup::shared_inputs), else one per lane.
    const bool shared = setup_.shared_inputs;
    const int stride = Exo::stride(shared, width_);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < S; ++j) {
        double* out =
            &buffer_[(static_cast<std::size_t>(i) * S + j) * 3 * Exo::kCount * stride];
        for (Dist& d : dists_) scatter(d.exo.step(k0 + i, j), d.lanes, out, true, false);
        for (Group& g : groups_)
          scatter(g.exo.step(k0 + i, j), g.lanes, out, g.dist == Group::kOwn, true);
      }
    return buffer_.data();
  }

  void samples(std::int64_t k0, int n, const SampleLanes<N, M>* out) override {
    const bool metrics = !setup_.kernel_metrics;
    const int S = setup_.substeps;
    for (std::size_t l = 0; l < lanes_.size(); ++l) {
      if (done_[l]) continue;
      const double Ts = setup_.Ts;
      const std::int64_t every = lanes_[l]->options->record_every;
      for (int i = 0; i < n; ++i) {
        const std::int64_t k = k0 + i;
        const double t = static_cast<double>(k) * Ts;
        StateOf<N> x;
        Vec<M> u;
        for (int r = 0; r < 2 * N; ++r) x[r] = out[i].x[r][l];
        for (int r = 0; r < M; ++r) u[r] = out[i].u[r][l];
        if (metrics) metrics_[l].sample(t, x, u);
        // The plant's input: the actuators' output with a model, else the command.
        Vec<M> drive = u;
        if (setup_.actuator)
          for (int r = 0; r < M; ++r) drive[r] = out[i].ua[r][l];
        if (every > 0 && k % every == 0) {
          const std::size_t stride = Exo::stride(setup_.shared_inputs, width_);
          const double* e =
              &buffer_[static_cast<std::size_t>(i) * S * 3 * Exo::kCount * stride];
          const std::size_t from = setup_.shared_inputs ? 0 : l;
          FaultEffect<M> effect;
          for (int r = 0; r < M; ++r) {
            effect.gain[r] = e[(Exo::kGain + r) * stride + from];
            effect.offset[r] = e[(Exo::kOffset + r) * stride + from];
          }
          append_row<N, M>(lanes_[l]->result->trajectory, t, x, u, applied(l, effect, drive));
        }
        if (out[i].diverged[l]) {
          if (metrics) metrics_[l].mark_diverged(t + Ts);
          done_[l] = true;
          break;
        }
      }
    }
  }

  // The command after the faults, the saturation and (for a plant with an operating point) the
  // limits, as the kernel forms it (lanes/closed_loop.hpp).
  Vec<M> applied(std::size_t l, const FaultEffect<M>& e, const Vec<M>& u_d) const {
    const FaultSet& faults = groups_[group_of_[l]].faults;
    if (!trimmed_) return faults.apply(e, u_d);
    return apply_trimmed<M>(*lanes_[l], faults, e, u_d);  // the Controller loop's operations
  }
  bool trimmed_ = false;

  void finish(const PackFinal<N, M>& fin) {
    for (std::size_t l = 0; l < lanes_.size(); ++l) {
      SimulationResult& r = *lanes_[l]->result;
      r.samples = fin.samples[l];
      r.final_state.resize(2 * N);
      for (int i = 0; i < 2 * N; ++i) r.final_state[i] = fin.x[i][l];
      if (!setup_.kernel_metrics) {
        r.metrics = metrics_[l].result();
        continue;
      }
      // The kernel's sums (lanes/metric_lanes.hpp), arranged as MetricsAccumulator arranges its
      // own: each field of the record from its slot (ftc/sim/metrics_record.hpp).
      Metrics m = metrics_[l].result();
      std::size_t slot[3] = {0, 0, 0};
      for (const MetricField& f : kMetricFields) {
        const std::size_t s = slot[static_cast<std::size_t>(f.scope)]++;
        switch (f.scope) {
          case MetricScope::window:
            m.errors.*f.in_window = fin.window_field[s][0][l];
            for (std::size_t w = 0; w < m.extra.size(); ++w)
              m.extra[w].*f.in_window = fin.window_field[s][w + 1][l];
            break;
          case MetricScope::run:
            m.*f.per_run = fin.run_field[s][l];
            break;
          case MetricScope::fault:
            for (std::size_t i = 0; i < (m.*f.per_fault).size(); ++i)
              (m.*f.per_fault)[i] = fin.fault_field[s][i][l];
            break;
        }
      }
      if (fin.diverged[l]) m.mark_diverged(fin.diverged_at[l]);
      r.metrics = std::move(m);
    }
  }

 private:
  // Writes a table's three entries (a substep's start, midpoint and end) into the rows of its
  // lanes (lane 0 only when the pack shares its inputs): Δ's rows when `disturbance`, the
  // faults' gain and offset rows when `faults`.
  void scatter(const typename ExogenousInputs<N, M>::Entry* e, const std::vector<int>& lanes,
               double* out, bool disturbance, bool faults) {
    const bool shared = setup_.shared_inputs;
    const int stride = Exo::stride(shared, width_);
    for (int q = 0; q < 3; ++q) {
      double* rows = out + q * Exo::kCount * stride;
      for (const int l : lanes) {
        if (shared && l > 0) break;
        if (disturbance)
          for (int r = 0; r < N; ++r) rows[(Exo::kDist + r) * stride + l] = e[q].disturbance[r];
        if (faults)
          for (int r = 0; r < M; ++r) {
            rows[(Exo::kGain + r) * stride + l] = e[q].fault.gain[r];
            rows[(Exo::kOffset + r) * stride + l] = e[q].fault.offset[r];
          }
      }
    }
  }

  // The lanes of one scenario: its faults' effects, and its disturbance too when no other
  // scenario of the pack has it (else exo's disturbance is empty and dists_ steps it).
  struct Group {
    static constexpr std::size_t kOwn = static_cast<std::size_t>(-1);
    Group(const Scenario& s, std::size_t d)
        : dist(d),
          disturbance(d == kOwn ? Disturbance(s.disturbance) : Disturbance()),
          faults(s.faults, s.saturation),
          exo(disturbance, faults, s.sample_time, s.substeps) {}
    std::size_t dist;        // its disturbance in dists_, or kOwn
    std::vector<int> lanes;  // in increasing order
    Disturbance disturbance;
    FaultSet faults;
    ExogenousInputs<N, M> exo;  // refers to the two above: groups never move (deque)
  };
  // The lanes of one disturbance: Δ(t) (exo's faults are empty). The lanes of a pack share the
  // sample time and the substeps, so the first scenario's serve every lane.
  struct Dist {
    explicit Dist(const Scenario& s)
        : disturbance(s.disturbance), exo(disturbance, none, s.sample_time, s.substeps) {}
    std::vector<int> lanes;  // in increasing order
    Disturbance disturbance;
    FaultSet none;
    ExogenousInputs<N, M> exo;  // refers to the two above: never moves (deque)
  };

  std::vector<LaneTask*> lanes_;
  int width_;
  const PackSetup<N, M>& setup_;
  std::deque<Group> groups_;
  std::deque<Dist> dists_;
  std::vector<std::size_t> group_of_;
  std::vector<MetricsAccumulator<N, M>> metrics_;
  std::vector<bool> done_;
  std::vector<double> buffer_;  // the inputs of a block (PackHost::inputs)
};

// G and G⁺ when the plant's are constant (else null: its lane code forms them).
template <class P, int N, int M>
void run_pack(std::span<LaneTask* const> lanes, const Mat<N, M>* G, const Mat<M, N>* G_pinv,
              bool trimmed, Isa isa) {
  const int width = lane_width(isa);
  PackSetup<N, M> su;
  su.lanes = static_cast<int>(lanes.size());
  const Scenario& s0 = *lanes[0]->scenario;
  su.Ts = s0.sample_time;
  su.substeps = s0.substeps;
  su.samples = s0.samples();
  su.block = std::max(1, 16 / su.substeps);
  if (G && G_pinv)
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < M; ++j) {
        su.G[i * M + j] = (*G)(i, j);
        su.G_pinv[j * N + i] = (*G_pinv)(j, i);
      }
  for (int l = 0; l < width; ++l) {
    const LaneTask& lane = *lanes[l < su.lanes ? l : 0];
    su.configs[l] = &lane.config;
    for (int i = 0; i < kMaxPlantConstants; ++i) {
      su.truth[i][l] = lane.truth[i];
      su.model[i][l] = lane.model[i];
      su.mismatch = su.mismatch || lane.truth[i] != lane.model[i];
    }
    for (int i = 0; i < 2 * N; ++i) su.x0[i][l] = lane.scenario->initial_state[i];
    for (int j = 0; trimmed && j < M; ++j) {  // M ≤ kMaxActuators then (PlantAdapter)
      su.u0[j][l] = lane.u0[j];
      su.lo[j][l] = lane.lo[j];
      su.hi[j][l] = lane.hi[j];
    }
    su.saturation[l] = lane.scenario->saturation.value_or(std::numeric_limits<double>::infinity());
    // What saturation_fraction measures the command against (the host's accumulators read them
    // too), and the settling threshold.
    for (int j = 0; j < M; ++j) {
      constexpr double inf = std::numeric_limits<double>::infinity();
      const CommandLimits c = trimmed ? command_limits(su.saturation[l], lane.lo[j], lane.hi[j])
                                      : command_limits(su.saturation[l], -inf, inf);
      su.limit_lo[j][l] = c.lo;
      su.limit_hi[j][l] = c.hi;
    }
    if (const std::optional<ActuatorModel>& a = lane.scenario->actuator) {
      su.actuator = true;
      const ActuatorSteps st = actuator_steps(*a, 0.5 * (su.Ts / su.substeps));
      su.act_gain[l] = st.gain;
      su.act_step[l] = st.max_step;
    }
    const double threshold = lane.options->metrics.settling_threshold;
    su.threshold_sq[l] = threshold * threshold;
    su.any_settling = su.any_settling || !std::isnan(threshold);
    su.first_onset[l] = std::numeric_limits<double>::infinity();  // metrics_accumulator.hpp's
    for (const Fault& f : lane.scenario->faults)
      su.first_onset[l] = f.onset < su.first_onset[l] ? f.onset : su.first_onset[l];
  }
  // The metrics in the kernel, unless a lane has more windows or faults than it keeps.
  su.kernel_metrics = true;
  su.want_samples = false;
  for (const LaneTask* l : lanes) {
    su.windows = std::max(su.windows, 1 + static_cast<int>(l->options->extra_windows.size()));
    su.onsets = std::max(su.onsets, static_cast<int>(l->scenario->faults.size()));
    su.want_samples = su.want_samples || l->options->record_every > 0;
  }
  if (su.windows > kMaxWindows || su.onsets > kMaxOnsets) {
    su.kernel_metrics = false;
    su.want_samples = true;
  } else {
    constexpr double inf = std::numeric_limits<double>::infinity();
    for (int l = 0; l < width; ++l) {
      const LaneTask& lane = *lanes[l < su.lanes ? l : 0];
      const SimulationOptions& o = *lane.options;
      for (int w = 0; w < su.windows; ++w) {
        const std::size_t e = static_cast<std::size_t>(w);
        const Window win = w == 0                        ? o.window
                           : e <= o.extra_windows.size() ? o.extra_windows[e - 1]
                                                         : Window{inf, inf};
        su.window[w][0][l] = win.t0;
        su.window[w][1][l] = win.t1;
        const double tail = o.metrics.steady_state_tail;
        su.tail_start[w][l] = tail_start(win, lane.scenario->duration, tail);
        su.any_tail = su.any_tail || !std::isnan(tail);
      }
      for (int f = 0; f < su.onsets; ++f) {
        const std::size_t e = static_cast<std::size_t>(f);
        su.onset[f][l] = e < lane.scenario->faults.size() ? lane.scenario->faults[e].onset : inf;
      }
    }
  }
  su.shared_inputs = true;
  for (const LaneTask* l : lanes)
    su.shared_inputs = su.shared_inputs && l->scenario == lanes[0]->scenario;
  Host<N, M> host(lanes, width, su);
  host.trimmed_ = trimmed;
  PackFinal<N, M> fin{};
  kernel_for<P, N, M>(isa)(su, host, fin);
  host.finish(fin);
}

// The narrowest instruction set up to `widest` that holds n lanes: a wide register costs more
// per instruction than a narrow one (AVX-512 on 2 lanes is slower than SSE2), and every
// instruction set gives the same bits.
inline Isa narrowest(Isa widest, std::size_t n) {
  static const std::vector<Isa> supported = supported_isas();
  for (Isa isa : supported) {
    if (isa == widest) break;
    if (static_cast<std::size_t>(lane_width(isa)) >= n) return isa;
  }
  return widest;
}

}  // namespace lane_host

// Runs the lanes of plant class P in packs of the instruction set's width (lanes that cannot
// share a pack run in different ones), writing each result. G and G_pinv: the plant's when
// constant, else null.
template <class P>
void run_lanes(std::span<LaneTask> lanes, const Mat<P::kAxes, P::kActuators>* G,
               const Mat<P::kActuators, P::kAxes>* G_pinv, bool trimmed, Isa isa) {
  // Lanes can share a pack when their loops have the same shape: sample time, substeps,
  // samples, control law (and network size), and an actuator model or none. Packs are formed in
  // task order.
  using Key = std::tuple<double, int, std::int64_t, ControllerType, double, bool>;
  const auto key = [](const LaneTask& l) {
    const bool adaptive = controller_info(l.config.type).adaptive;
    return Key{l.scenario->sample_time, l.scenario->substeps, l.scenario->samples(), l.config.type,
               adaptive ? l.config.nodes : 0.0, l.scenario->actuator.has_value()};
  };
  const std::size_t width = static_cast<std::size_t>(lane_width(isa));
  std::vector<bool> taken(lanes.size(), false);
  std::vector<LaneTask*> pack;
  for (std::size_t i = 0; i < lanes.size(); ++i) {
    if (taken[i]) continue;
    pack.clear();
    const Key k = key(lanes[i]);
    for (std::size_t j = i; j < lanes.size() && pack.size() < width; ++j)
      if (!taken[j] && key(lanes[j]) == k) {
        taken[j] = true;
        pack.push_back(&lanes[j]);
      }
    lane_host::run_pack<P, P::kAxes, P::kActuators>(pack, G, G_pinv, trimmed,
                                                    lane_host::narrowest(isa, pack.size()));
  }
}

}  // namespace ftc::sim::detail
