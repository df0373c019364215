#pragma once
// Every simulation goes through the one closed loop (lanes/closed_loop.hpp) from here: grouping
// tasks into packs, the host side of a pack (exogenous inputs, the metrics' setup and read-back,
// trajectories), in plain C++ compiled once, for plant class P; and a runtime Controller object
// in one lane of the scalar kernel (run_controller, sim::simulate). Private to sim_core
// (plants/plant_adapter.hpp, plants/registry.cpp).
#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <tuple>
#include <type_traits>
#include <vector>

#include "exogenous_inputs.hpp"
#include "ftc/sim/controller.hpp"
#include "ftc/sim/disturbance.hpp"
#include "ftc/sim/faults.hpp"
#include "ftc/sim/isa.hpp"
#include "ftc/sim/metrics.hpp"
#include "ftc/sim/metrics_record.hpp"
#include "ftc/sim/plant.hpp"
#include "ftc/sim/scenario.hpp"
#include "ftc/sim/simulation.hpp"
#include "lanes/pack.hpp"
#include "noise_tables.hpp"

namespace ftc::sim::detail {

constexpr std::array<double, kMaxActuators> filled(double v) {
  std::array<double, kMaxActuators> a{};
  for (double& x : a) x = v;
  return a;
}

// One validated simulation: its controller (checked, α1 resolved), scenario and options, the
// constants of the simulated plant and of the controller's model (the plant's f_constants()).
struct LaneTask {
  ControllerConfig config;
  const Scenario* scenario = nullptr;
  const SimulationOptions* options = nullptr;
  std::array<double, kMaxPlantConstants> truth{}, model{};
  // The simulated plant's operating point (PackSetup::u0, for a plant that has one) and its own
  // range of each actuator's command (a rotor's 0 .. max thrust less u0; unbounded for a plant
  // without limits): the scenario's saturation narrows it (MetricSetup's limits).
  std::array<double, kMaxActuators> u0{};
  std::array<double, kMaxActuators> lo = filled(-std::numeric_limits<double>::infinity());
  std::array<double, kMaxActuators> hi = filled(std::numeric_limits<double>::infinity());
  // The plant's own m when it is fewer than the kernel's M (a rigid body's columns past m are
  // zero): results and trajectories carry m. 0: M.
  int actuators = 0;
  // The plant's lane code reports whether X left its model's validity (SimulationResult's
  // model_invalid).
  bool reports_validity = false;
  SimulationResult* result = nullptr;
};

// A command's limits: the plant's own range [lo, hi] within ±u_max, the scenario's saturation
// (the loop holds the command and the faulted output within them; saturation_fraction counts the
// samples at them).
struct CommandLimits {
  double lo, hi;
};
inline CommandLimits command_limits(double u_max, double lo, double hi) {
  return {lo > -u_max ? lo : -u_max, hi < u_max ? hi : u_max};
}

// The applied output: the command within its limits [lo, hi], the faults (on the physical output
// u0 + u for a plant with an operating point, `u0` non-null), the limits again. The operations of
// the loop's forcing (lanes/closed_loop.hpp), for the recorded rows.
template <int M>
Vec<M> applied_output(const FaultEffect<M>& e, const Vec<M>& u_d, const double* u0,
                      const double* lo, const double* hi) {
  Vec<M> u;
  for (int j = 0; j < M; ++j) {
    double c = u_d[j] < lo[j] ? lo[j] : u_d[j];
    c = c > hi[j] ? hi[j] : c;
    const double v =
        u0 ? (e.gain[j] * (u0[j] + c) + e.offset[j]) - u0[j] : e.gain[j] * c + e.offset[j];
    const double w = v < lo[j] ? lo[j] : v;
    u[j] = w > hi[j] ? hi[j] : w;
  }
  return u;
}

// One recorded sample; out of line, as it is rare and would bloat the loop.
template <int N, int M>
[[gnu::noinline]] void append_row(Trajectory& tr, double t, const StateOf<N>& x, const Vec<M>& u_d,
                                  const Vec<M>& u) {
  std::vector<double>& v = tr.values;
  const int m = tr.actuators;  // ≤ M
  v.push_back(t);
  v.insert(v.end(), x.data(), x.data() + 2 * N);
  v.insert(v.end(), u_d.data(), u_d.data() + m);
  v.insert(v.end(), u.data(), u.data() + m);
}

// The metrics' side of a pack on the host: what each lane measures against (MetricSetup: its
// windows, their steady-state tails, its fault onsets, the command limits, the first onset and
// the settling threshold), the storage of those rows and of the values the kernel writes
// (MetricsOut), and the read-back of a lane's values into its Metrics, every field of the record
// from its slot (ftc/sim/metrics_record.hpp). The kernel's MetricLanes (lanes/metric_lanes.hpp)
// accumulates in between.
template <int M>
class MetricRows {
 public:
  // The rows of `lanes` (lanes past them up to `width` repeat lane 0), as many windows and onsets
  // as the lane with the most has; a lane with fewer has [inf, inf) windows and onsets at inf,
  // which count no sample.
  void set(std::span<LaneTask* const> lanes, int width, MetricSetup<M>& ms) {
    static_assert(M <= kMaxActuators);
    constexpr double inf = std::numeric_limits<double>::infinity();
    std::size_t windows = 0, onsets = 0;
    for (const LaneTask* l : lanes) {
      windows = std::max(windows, 1 + l->options->extra_windows.size());
      onsets = std::max(onsets, l->scenario->faults.size());
    }
    window_.assign(windows * 2 * kMaxLanes, inf);
    tail_.assign(windows * kMaxLanes, std::numeric_limits<double>::quiet_NaN());
    onset_.assign(onsets * kMaxLanes, inf);
    for (int l = 0; l < width; ++l) {
      const LaneTask& lane = *lanes[l < static_cast<int>(lanes.size()) ? l : 0];
      const SimulationOptions& o = *lane.options;
      const Scenario& s = *lane.scenario;
      const std::size_t own = 1 + o.extra_windows.size();
      const double tail = o.metrics.steady_state_tail;
      for (std::size_t w = 0; w < windows; ++w) {
        const Window win = w == 0 ? o.window : w < own ? o.extra_windows[w - 1] : Window{inf, inf};
        window_[(2 * w) * kMaxLanes + l] = win.t0;
        window_[(2 * w + 1) * kMaxLanes + l] = win.t1;
        tail_[w * kMaxLanes + l] = tail_start(win, s.duration, tail);
      }
      ms.any_tail = ms.any_tail || !std::isnan(tail);
      ms.first_onset[l] = inf;  // without a fault
      for (std::size_t f = 0; f < s.faults.size(); ++f) {
        onset_[f * kMaxLanes + l] = s.faults[f].onset;
        ms.first_onset[l] =
            s.faults[f].onset < ms.first_onset[l] ? s.faults[f].onset : ms.first_onset[l];
      }
      // The command's limits: the plant's range within ± the scenario's saturation.
      for (int j = 0; j < M; ++j) {
        const CommandLimits c = command_limits(s.saturation.limit(j), lane.lo[j], lane.hi[j]);
        ms.limit_lo[j][l] = c.lo;
        ms.limit_hi[j][l] = c.hi;
      }
      const double threshold = o.metrics.settling_threshold;
      ms.threshold_sq[l] = threshold * threshold;
      ms.any_settling = ms.any_settling || !std::isnan(threshold);
    }
    ms.windows = static_cast<int>(windows);
    ms.window = window_.data();
    ms.tail_start = tail_.data();
    ms.onsets = static_cast<int>(onsets);
    ms.onset = onset_.data();
    window_out_.assign(windows * MetricsOut::kWindowFields * kMaxLanes, 0.0);
    fault_out_.assign(onsets * MetricsOut::kFaultFields * kMaxLanes, 0.0);
  }

  // Where the kernel writes the values.
  void outputs(MetricsOut& out) {
    out.window = window_out_.data();
    out.fault = fault_out_.data();
  }

  // Lane l's record: its windows and fault onsets (from `o` and `s`), each field's value from
  // `out`, then +inf in every window when it diverged at `diverged_at`.
  Metrics read(std::size_t l, const MetricsOut& out, const SimulationOptions& o, const Scenario& s,
               std::optional<double> diverged_at) const {
    constexpr std::size_t kWindowFields = MetricsOut::kWindowFields;
    constexpr std::size_t kFaultFields = MetricsOut::kFaultFields;
    Metrics m;
    m.window = o.window;
    m.extra_windows = o.extra_windows;
    m.extra.assign(o.extra_windows.size(), ErrorIntegrals{});
    for (const Fault& f : s.faults) m.fault_onsets.push_back(f.onset);
    std::size_t slot[3] = {0, 0, 0};
    for (const MetricField& f : kMetricFields) {
      const std::size_t k = slot[static_cast<std::size_t>(f.scope)]++;
      const auto in_window = [&](std::size_t w) {
        return out.window[(w * kWindowFields + k) * kMaxLanes + l];
      };
      switch (f.scope) {
        case MetricScope::window:
          m.errors.*f.in_window = in_window(0);
          for (std::size_t w = 0; w < m.extra.size(); ++w)
            m.extra[w].*f.in_window = in_window(w + 1);
          break;
        case MetricScope::run:
          m.*f.per_run = out.run[k][l];
          break;
        case MetricScope::fault:
          (m.*f.per_fault).resize(m.fault_onsets.size());
          for (std::size_t i = 0; i < m.fault_onsets.size(); ++i)
            (m.*f.per_fault)[i] = out.fault[(i * kFaultFields + k) * kMaxLanes + l];
          break;
      }
    }
    if (diverged_at) m.mark_diverged(*diverged_at);
    return m;
  }

 private:
  std::vector<double> window_, tail_, onset_, window_out_, fault_out_;
};

namespace lane_host {

// Plant P's kernel for an instruction set.
template <class P, int N, int M>
PackKernel<N, M> kernel_for(Isa isa) {
  switch (isa) {
#if defined(FTC_KERNEL_SSE2)
    case Isa::sse2:
      return &isa_sse2::pack_kernel<P, N, M>;
#endif
#if defined(FTC_KERNEL_AVX2)
    case Isa::avx2:
      return &isa_avx2::pack_kernel<P, N, M>;
#endif
#if defined(FTC_KERNEL_AVX512)
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
// as an ensemble's members do, the second), per lane its trajectory, and the storage of the
// metrics' per-window and per-onset rows (MetricSetup, MetricsOut). A scenario whose disturbance
// no other scenario of the pack has steps both in one table: a pack of one scenario (Table 1's
// job, a landscape) builds one table, not two.
template <int N, int M>
class Host final : public PackHost<N, M> {
  using Exo = ExoRows<N, M>;

 public:
  // Fills the setup's metrics (MetricRows) from the lanes' options and scenarios.
  Host(std::span<LaneTask* const> lanes, int width, bool trimmed, PackSetup<N, M>& setup)
      : lanes_(lanes.begin(), lanes.end()), width_(width), trimmed_(trimmed), setup_(setup) {
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
      const SimulationOptions& o = *lanes_[l]->options;
      SimulationResult& r = *lanes_[l]->result;
      r = SimulationResult{};
      r.trajectory.axes = N;
      r.trajectory.actuators = lanes_[l]->actuators > 0 ? lanes_[l]->actuators : M;
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
    if (setup.sensors) {
      for (Group& g : groups_) {
        const Scenario& s = *g.scenario;
        g.table = noise_table(*s.sensors, N, s.sample_time, setup.samples);
        if (!g.table) g.noise.emplace(*s.sensors, N, s.sample_time);
      }
      noise_.resize(static_cast<std::size_t>(setup.block) * 3 * N *
                    Exo::stride(setup.shared_inputs, width));
      ring_.assign(static_cast<std::size_t>(setup.delay + 1) * 3 * N * kMaxLanes, 0.0);
      setup.ring = ring_.data();
    }
    buffer_.resize(static_cast<std::size_t>(setup.block) * setup.substeps * 3 * Exo::kCount *
                   Exo::stride(setup.shared_inputs, width));
    metrics_.set(lanes, width, setup.metrics);
  }

  const double* inputs(std::int64_t k0, int n) override {
    const int S = setup_.substeps;
    // With one scenario one value per row (PackSetup::shared_inputs), else one per lane.
    if (setup_.shared_inputs) {
      // One scenario, so one group with its own disturbance, and one value per row: the rows
      // of an instant are its entry's values in order. The general path below writes the same
      // values through lane lists and strides: 314 instructions a sample, here 91 (callgrind,
      // the paper's scenario on AVX2); with one scenario per pack, as a batch on one scenario
      // has, the general path took 5 % of a pack's time on AVX-512 (tools/profile-kernel).
      assert(groups_.size() == 1 && dists_.empty());
      auto& exo = groups_.front().exo;
      double* out = buffer_.data();
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < S; ++j) {
          const auto* e = exo.step(k0 + i, j);
          for (int q = 0; q < 3; ++q, out += Exo::kCount) rows_of(e[q], out);
        }
      return buffer_.data();
    }
    const int stride = width_;  // one value per lane
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < S; ++j) {
        double* out = &buffer_[(static_cast<std::size_t>(i) * S + j) * 3 * Exo::kCount * stride];
        for (Dist& d : dists_) scatter(d.exo.step(k0 + i, j), d.lanes, out, true, false);
        for (Group& g : groups_)
          scatter(g.exo.step(k0 + i, j), g.lanes, out, g.dist == Group::kOwn, true);
      }
    return buffer_.data();
  }

  // Each scenario's measurement noise, from its table (noise_tables.hpp) or drawn sample by
  // sample from its stream, into its lanes' rows.
  const double* noise(std::int64_t k0, int n) override {
    const bool shared = setup_.shared_inputs;
    const int stride = Exo::stride(shared, width_);
    double drawn[3 * N];
    for (int i = 0; i < n; ++i) {
      double* rows = &noise_[static_cast<std::size_t>(i) * 3 * N * stride];
      for (Group& g : groups_) {
        const double* terms = drawn;
        if (g.table)
          terms = g.table->data() + static_cast<std::size_t>(k0 + i) * 3 * N;
        else
          g.noise->next(drawn, drawn + N, drawn + 2 * N);
        for (const int l : g.lanes) {
          if (shared && l > 0) break;
          for (int r = 0; r < 3 * N; ++r) rows[r * stride + l] = terms[r];
        }
      }
    }
    return noise_.data();
  }

  // The recorded rows: every record_every-th sample of a lane that records, with the command
  // after the faults, the saturation and the limits as the loop formed it.
  void samples(std::int64_t k0, int n, const SampleLanes<N, M>* out) override {
    const int S = setup_.substeps;
    for (std::size_t l = 0; l < lanes_.size(); ++l) {
      const std::int64_t every = lanes_[l]->options->record_every;
      if (done_[l] || every <= 0) continue;
      const double Ts = setup_.Ts;
      for (int i = 0; i < n; ++i) {
        const std::int64_t k = k0 + i;
        const double t = static_cast<double>(k) * Ts;
        if (k % every == 0) {
          StateOf<N> x;
          Vec<M> u;
          for (int r = 0; r < 2 * N; ++r) x[r] = out[i].x[r][l];
          for (int r = 0; r < M; ++r) u[r] = out[i].u[r][l];
          // The plant's input: the actuators' output with a model, else the command.
          Vec<M> drive = u;
          if (setup_.actuator)
            for (int r = 0; r < M; ++r) drive[r] = out[i].ua[r][l];
          const std::size_t stride = Exo::stride(setup_.shared_inputs, width_);
          const double* e = &buffer_[static_cast<std::size_t>(i) * S * 3 * Exo::kCount * stride];
          const std::size_t from = setup_.shared_inputs ? 0 : l;
          FaultEffect<M> effect;
          for (int r = 0; r < M; ++r) {
            effect.gain[r] = e[(Exo::kGain + r) * stride + from];
            effect.offset[r] = e[(Exo::kOffset + r) * stride + from];
          }
          append_row<N, M>(lanes_[l]->result->trajectory, t, x, u, applied(l, effect, drive));
        }
        if (out[i].diverged[l]) {
          done_[l] = true;
          break;
        }
      }
    }
  }

  // The command within its limits, after the faults and within the limits again, as the loop
  // forms it (lanes/closed_loop.hpp).
  Vec<M> applied(std::size_t l, const FaultEffect<M>& e, const Vec<M>& u_d) const {
    double lo[M], hi[M];
    for (int j = 0; j < M; ++j) {
      lo[j] = setup_.metrics.limit_lo[j][l];
      hi[j] = setup_.metrics.limit_hi[j][l];
    }
    return applied_output<M>(e, u_d, trimmed_ ? lanes_[l]->u0.data() : nullptr, lo, hi);
  }

  // Where the kernel writes the metrics.
  void outputs(PackFinal<N, M>& fin) { metrics_.outputs(fin.metrics); }

  // Each lane's result: its samples, final state and metrics.
  void finish(const PackFinal<N, M>& fin) {
    for (std::size_t l = 0; l < lanes_.size(); ++l) {
      SimulationResult& r = *lanes_[l]->result;
      r.samples = fin.samples[l];
      r.final_state.resize(2 * N);
      for (int i = 0; i < 2 * N; ++i) r.final_state[i] = fin.x[i][l];
      r.metrics =
          metrics_.read(l, fin.metrics, *lanes_[l]->options, *lanes_[l]->scenario,
                        fin.diverged[l] ? std::optional<double>(fin.diverged_at[l]) : std::nullopt);
      if (lanes_[l]->reports_validity) r.model_invalid = fin.model_invalid[l];
    }
  }

 private:
  // An instant's inputs as the kCount values of its rows, in ExoRows' order.
  static void rows_of(const typename ExogenousInputs<N, M>::Entry& e, double* v) {
    for (int r = 0; r < N; ++r) v[Exo::kDist + r] = e.disturbance[r];
    for (int r = 0; r < M; ++r) {
      v[Exo::kGain + r] = e.fault.gain[r];
      v[Exo::kOffset + r] = e.fault.offset[r];
    }
  }

  // Writes a table's three entries (a substep's start, midpoint and end) into the rows of its
  // lanes, in a pack whose lanes have inputs of their own (inputs() writes a shared pack's rows
  // itself): Δ's rows when `disturbance`, the faults' gain and offset rows when `faults`.
  void scatter(const typename ExogenousInputs<N, M>::Entry* e, const std::vector<int>& lanes,
               double* out, bool disturbance, bool faults) {
    const std::size_t stride = static_cast<std::size_t>(width_);
    for (int q = 0; q < 3; ++q) {
      // The instant's values in a local array, which no store to the rows can alias (a store
      // through `rows` could change the entry, so reading it in the loop reloads it), and the
      // row loops of fixed length. `ftctune evaluate jobs/robust-faults.json --count 8` (a pack
      // of eight scenarios, AVX2): 52.6 million instructions in inputs() before, 41.9 after
      // (callgrind); a row loop over a range chosen at run time took 74.2.
      double v[Exo::kCount];
      rows_of(e[q], v);
      double* rows = out + q * Exo::kCount * stride;
      for (const int l : lanes) {
        double* column = rows + l;
        if (disturbance)
          for (int r = Exo::kDist; r < Exo::kDist + N; ++r) column[r * stride] = v[r];
        if (faults)
          for (int r = Exo::kGain; r < Exo::kCount; ++r) column[r * stride] = v[r];
      }
    }
  }

  // The lanes of one scenario: its faults' effects, and its disturbance too when no other
  // scenario of the pack has it (else exo's disturbance is empty and dists_ steps it).
  struct Group {
    static constexpr std::size_t kOwn = static_cast<std::size_t>(-1);
    Group(const Scenario& s, std::size_t d)
        : scenario(&s),
          dist(d),
          disturbance(d == kOwn ? Disturbance(s.disturbance) : Disturbance()),
          faults(s.faults, s.saturation),
          exo(disturbance, faults, s.sample_time, s.substeps) {}
    const Scenario* scenario;
    std::size_t dist;        // its disturbance in dists_, or kOwn
    std::vector<int> lanes;  // in increasing order
    // With sensors (PackSetup::sensors): the scenario's noise table, else its stream.
    std::shared_ptr<const NoiseTable> table;
    std::optional<SensorNoise> noise;
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
  bool trimmed_;  // the plant's actuators work about an operating point
  const PackSetup<N, M>& setup_;
  std::deque<Group> groups_;
  std::deque<Dist> dists_;
  std::vector<std::size_t> group_of_;
  std::vector<bool> done_;
  std::vector<double> buffer_;  // the inputs of a block (PackHost::inputs)
  std::vector<double> noise_;   // the measurement noise of a block (PackHost::noise)
  std::vector<double> ring_;    // the delayed measurements (PackSetup::ring)
  MetricRows<M> metrics_;
};

// The setup of a pack of lanes of one loop shape, but for its metrics (Host fills them): G and G⁺
// when the plant's are constant (else null: its lane code forms them).
template <int N, int M>
PackSetup<N, M> pack_setup(std::span<LaneTask* const> lanes, const Mat<N, M>* G,
                           const Mat<M, N>* G_pinv, bool trimmed, int width) {
  PackSetup<N, M> su;
  su.lanes = static_cast<int>(lanes.size());
  const Scenario& s0 = *lanes[0]->scenario;
  su.Ts = s0.sample_time;
  su.substeps = s0.substeps;
  su.samples = s0.samples();
  su.block = std::max(1, 16 / su.substeps);
  // Sensors: the lanes share one delay and acceleration source (run_lanes' key).
  if (const SensorModel* sm = s0.active_sensors()) {
    su.sensors = true;
    su.delay = sm->delay;
    su.differentiated = sm->acceleration.source == AccelerationSource::differentiated;
  }
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
    for (int j = 0; trimmed && j < M; ++j) su.u0[j][l] = lane.u0[j];
    if (su.sensors) {
      const SensorModel& sm = *lane.scenario->sensors;
      su.angle_step[l] = sm.angle.quantization;
      su.rate_step[l] = sm.rate.quantization;
      su.lowpass_gain[l] = su.Ts / (sm.acceleration.time_constant + su.Ts);
    }
    if (const std::optional<ActuatorModel>& a = lane.scenario->actuator) {
      su.actuator = true;
      const ActuatorSteps st = actuator_steps(*a, 0.5 * (su.Ts / su.substeps));
      su.act_gain[l] = st.gain;
      su.act_step[l] = st.max_step;
    }
  }
  su.want_samples = false;
  for (const LaneTask* l : lanes) su.want_samples = su.want_samples || l->options->record_every > 0;
  su.shared_inputs = true;
  for (const LaneTask* l : lanes)
    su.shared_inputs = su.shared_inputs && l->scenario == lanes[0]->scenario;
  return su;
}

// Runs a pack through `kernel`: its setup, its host, the kernel, the results.
template <int N, int M, class Kernel>
void run_pack_with(std::span<LaneTask* const> lanes, const Mat<N, M>* G, const Mat<M, N>* G_pinv,
                   bool trimmed, int width, Kernel&& kernel) {
  PackSetup<N, M> su = pack_setup<N, M>(lanes, G, G_pinv, trimmed, width);
  Host<N, M> host(lanes, width, trimmed, su);
  PackFinal<N, M> fin{};
  host.outputs(fin);
  kernel(su, host, fin);
  host.finish(fin);
}

// G and G⁺ when the plant's are constant (else null: its lane code forms them).
template <class P, int N, int M>
void run_pack(std::span<LaneTask* const> lanes, const Mat<N, M>* G, const Mat<M, N>* G_pinv,
              bool trimmed, Isa isa) {
  run_pack_with<N, M>(lanes, G, G_pinv, trimmed, lane_width(isa), kernel_for<P, N, M>(isa));
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
  // samples, control law (and network size), an actuator model or none, and sensors or none. Packs are formed in
  // task order.
  // With sensors, one delay and acceleration source (−1: none).
  using Key = std::tuple<double, int, std::int64_t, ControllerType, double, bool, int>;
  const auto key = [](const LaneTask& l) {
    const bool adaptive = controller_info(l.config.type).adaptive;
    const SensorModel* sm = l.scenario->active_sensors();
    const int sensors =
        sm ? 2 * sm->delay + (sm->acceleration.source == AccelerationSource::differentiated) : -1;
    return Key{l.scenario->sample_time,         l.scenario->substeps,
               l.scenario->samples(),           l.config.type,
               adaptive ? l.config.nodes : 0.0, l.scenario->actuator.has_value(),
               sensors};
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

// A runtime Controller and the simulated plant it is in closed loop with, as the kernel's
// ObjectController calls them: the controller gets f(X) of that plant with the plant's address
// (Measurement::f_of), so that a model-based controller of the same plant object reuses it.
template <int N, int M>
struct ControllerBinding {
  Controller<N, M>* controller;
  const Plant<N, M>* plant;

  ObjectController functions() {
    ObjectController o;
    o.self = this;
    o.reset = [](void* self) { static_cast<ControllerBinding*>(self)->controller->reset(); };
    o.step = [](void* self, double t, const double* X1, const double* X2, const double* a,
                const double* f, double* u) {
      const ControllerBinding& b = *static_cast<ControllerBinding*>(self);
      const Vec<N> fx = Eigen::Map<const Vec<N>>(f);
      const Vec<M> out = b.controller->step(
          Measurement<N>{t, Eigen::Map<const Vec<N>>(X1), Eigen::Map<const Vec<N>>(X2),
                         Eigen::Map<const Vec<N>>(a), &fx, static_cast<const void*>(b.plant)});
      for (int j = 0; j < M; ++j) u[j] = out[j];
    };
    return o;
  }
};

// A plant known only through the Plant<N, M> interface, as the kernel's ObjectPlant calls it.
template <int N, int M>
ObjectPlant object_plant(const Plant<N, M>& plant) {
  ObjectPlant o;
  o.self = &plant;
  o.f = [](const void* self, const double* x, double* f) {
    const Vec<N> v = static_cast<const Plant<N, M>*>(self)->f(Eigen::Map<const StateOf<N>>(x));
    for (int i = 0; i < N; ++i) f[i] = v[i];
  };
  o.G = [](const void* self, const double* x, double* G) {
    const Mat<N, M> g = static_cast<const Plant<N, M>*>(self)->G(Eigen::Map<const StateOf<N>>(x));
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < M; ++j) G[i * M + j] = g(i, j);
  };
  return o;
}

// A plant's own actuator count (when it has fewer than its class's M) and whether it reports
// its model's validity, for a lane of it.
template <class P>
void plant_extent(const P& plant, LaneTask& lane) {
  if constexpr (requires { plant.actuator_count(); }) lane.actuators = plant.actuator_count();
  if constexpr (requires { plant.reports_validity(); })
    lane.reports_validity = plant.reports_validity();
}

// The runtime's sim::simulate: `controller` in closed loop with `plant`, in one lane of the
// scalar kernel's loop with the controller as its law, so that it replays a tuning run's lane to
// the last bit. P is a registered plant class (its lanes file's controller_kernel runs its lane
// code) or Plant<N, M> itself (a plant known only through the interface: ObjectPlantLanes calls
// its f and G, object_plant_kernel, plants/registry.cpp). The scenario is valid.
template <class P>
SimulationResult run_controller(const P& plant, Controller<P::kAxes, P::kActuators>& controller,
                                const Scenario& scenario, const SimulationOptions& options) {
  constexpr int N = P::kAxes, M = P::kActuators;
  constexpr bool kRegistered = !std::is_same_v<P, Plant<N, M>>;
  SimulationResult result;
  LaneTask lane;
  lane.config = controller.config();
  lane.scenario = &scenario;
  lane.options = &options;
  lane.result = &result;
  bool trimmed = false;
  if constexpr (kRegistered) {
    const auto k = plant.f_constants();
    std::copy(k.begin(), k.end(), lane.truth.begin());
    lane.model = lane.truth;
    plant_extent(plant, lane);
    if constexpr (requires { plant.actuator_trim(); }) {
      trimmed = true;
      const auto t = plant.actuator_trim();
      for (int j = 0; j < M; ++j) {
        lane.u0[j] = t.u0[j];
        lane.lo[j] = t.lo[j];
        lane.hi[j] = t.hi[j];
      }
    }
  }
  const StateOf<N> x0 = Eigen::Map<const StateOf<N>>(scenario.initial_state.data());
  const bool constant = kRegistered && plant.input_matrix_is_constant();
  const Mat<N, M> G = constant ? plant.G(x0) : Mat<N, M>::Zero();
  const Mat<M, N> G_pinv = constant ? plant.G_pinv(x0) : Mat<M, N>::Zero();
  ControllerBinding<N, M> binding{&controller, &plant};
  const ObjectController c = binding.functions();
  LaneTask* lanes[1] = {&lane};
  lane_host::run_pack_with<N, M>(
      lanes, constant ? &G : nullptr, constant ? &G_pinv : nullptr, trimmed, 1,
      [&](const PackSetup<N, M>& su, PackHost<N, M>& host, PackFinal<N, M>& fin) {
        if constexpr (kRegistered)
          isa_scalar::controller_kernel<P, N, M>(su, host, fin, c);
        else
          isa_scalar::object_plant_kernel<N, M>(su, host, fin, c, object_plant(plant));
      });
  return result;
}

}  // namespace ftc::sim::detail
