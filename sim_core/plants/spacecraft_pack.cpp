#include "plants/spacecraft_pack.hpp"

#include <algorithm>
#include <deque>
#include <limits>
#include <memory>
#include <tuple>
#include <vector>

#include "ftc/sim/disturbance.hpp"
#include "ftc/sim/faults.hpp"
#include "ftc/sim/metrics.hpp"
#include "lanes/pack.hpp"
#include "simulation_loop.hpp"

namespace ftc::sim::detail {
namespace {

PackKernel kernel_for(Isa isa) {
  switch (isa) {
#if defined(FTC_X86_KERNELS)
    case Isa::sse2:
      return pack_kernel_sse2;
    case Isa::avx2:
      return pack_kernel_avx2;
    case Isa::avx512:
      return pack_kernel_avx512;
#endif
    default:
      return pack_kernel_scalar;
  }
}

// The host of one pack: per distinct scenario one ExogenousInputs (lanes of one scenario share
// it), per lane its metrics and trajectory.
class Host final : public PackHost {
 public:
  Host(std::span<SpacecraftLane* const> lanes, int width, const PackSetup& setup)
      : lanes_(lanes.begin(), lanes.end()), width_(width), setup_(setup) {
    for (std::size_t l = 0; l < lanes_.size(); ++l) {
      const Scenario& s = *lanes_[l]->scenario;
      std::size_t g = 0;
      while (g < groups_.size() && groups_[g].scenario != &s) ++g;
      if (g == groups_.size()) groups_.emplace_back(s);
      group_of_.push_back(g);
      std::vector<double> onsets;
      for (const Fault& f : s.faults) onsets.push_back(f.onset);
      const SimulationOptions& o = *lanes_[l]->options;
      metrics_.emplace_back(s.sample_time, o.window, o.extra_windows, std::move(onsets));
      SimulationResult& r = *lanes_[l]->result;
      r = SimulationResult{};
      r.trajectory.axes = 3;
      r.trajectory.actuators = 4;
      if (o.record_every > 0)
        r.trajectory.values.reserve((setup.samples / o.record_every + 1) * r.trajectory.width());
    }
    for (std::size_t l = 0; l < lanes_.size(); ++l)
      groups_[group_of_[l]].lanes.push_back(static_cast<int>(l));
    // Unused lanes repeat lane 0.
    for (int l = static_cast<int>(lanes_.size()); l < width; ++l) groups_[0].lanes.push_back(l);
    done_.assign(lanes_.size(), false);
    buffer_.resize(static_cast<std::size_t>(setup.block) * setup.substeps * 3 * ExoRows::kCount *
                   ExoRows::stride(setup.shared_inputs, width));
  }

  const double* inputs(std::int64_t k0, int n) override {
    const int S = setup_.substeps;
    // With one scenario one value per row (PackSetup::shared_inputs), else one per lane.
    const bool shared = setup_.shared_inputs;
    const int stride = ExoRows::stride(shared, width_);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < S; ++j) {
        double* out =
            &buffer_[(static_cast<std::size_t>(i) * S + j) * 3 * ExoRows::kCount * stride];
        for (Group& g : groups_) {
          const auto* e = g.exo.step(k0 + i, j);
          for (int q = 0; q < 3; ++q) {
            double* rows = out + q * ExoRows::kCount * stride;
            for (const int l : g.lanes) {
              if (shared && l > 0) break;
              for (int r = 0; r < 3; ++r)
                rows[(ExoRows::kDist + r) * stride + l] = e[q].disturbance[r];
              for (int r = 0; r < 4; ++r) {
                rows[(ExoRows::kGain + r) * stride + l] = e[q].fault.gain[r];
                rows[(ExoRows::kOffset + r) * stride + l] = e[q].fault.offset[r];
              }
            }
          }
        }
      }
    return buffer_.data();
  }

  void samples(std::int64_t k0, int n, const SampleLanes* out) override {
    const bool metrics = !setup_.kernel_metrics;
    const int S = setup_.substeps;
    for (std::size_t l = 0; l < lanes_.size(); ++l) {
      if (done_[l]) continue;
      const double Ts = setup_.Ts;
      const std::int64_t every = lanes_[l]->options->record_every;
      for (int i = 0; i < n; ++i) {
        const std::int64_t k = k0 + i;
        const double t = static_cast<double>(k) * Ts;
        State x;
        Vec4 u;
        for (int r = 0; r < 6; ++r) x[r] = out[i].x[r][l];
        for (int r = 0; r < 4; ++r) u[r] = out[i].u[r][l];
        if (metrics) metrics_[l].sample(t, x, u);
        if (every > 0 && k % every == 0) {
          const std::size_t stride = ExoRows::stride(setup_.shared_inputs, width_);
          const double* e =
              &buffer_[static_cast<std::size_t>(i) * S * 3 * ExoRows::kCount * stride];
          const std::size_t from = setup_.shared_inputs ? 0 : l;
          FaultEffect<4> effect;
          for (int r = 0; r < 4; ++r) {
            effect.gain[r] = e[(ExoRows::kGain + r) * stride + from];
            effect.offset[r] = e[(ExoRows::kOffset + r) * stride + from];
          }
          append_row<3, 4>(lanes_[l]->result->trajectory, t, x, u,
                           groups_[group_of_[l]].faults.apply(effect, u));
        }
        if (out[i].diverged[l]) {
          if (metrics) metrics_[l].mark_diverged(t + Ts);
          done_[l] = true;
          break;
        }
      }
    }
  }

  void finish(const PackFinal& fin) {
    for (std::size_t l = 0; l < lanes_.size(); ++l) {
      SimulationResult& r = *lanes_[l]->result;
      r.samples = fin.samples[l];
      r.final_state.resize(6);
      for (int i = 0; i < 6; ++i) r.final_state[i] = fin.x[i][l];
      if (!setup_.kernel_metrics) {
        r.metrics = metrics_[l].result();
        continue;
      }
      // The kernel's sums, arranged as MetricsAccumulator arranges its own.
      Metrics m = metrics_[l].result();
      m.errors = {fin.ise[0][l], fin.iae[0][l], fin.itae[0][l]};
      for (std::size_t w = 0; w < m.extra.size(); ++w)
        m.extra[w] = {fin.ise[w + 1][l], fin.iae[w + 1][l], fin.itae[w + 1][l]};
      m.max_abs_u = fin.max_abs_u[l];
      m.control_tv = fin.control_tv[l];
      for (std::size_t f = 0; f < m.peak_error_after_fault.size(); ++f)
        m.peak_error_after_fault[f] = fin.peak[f][l];
      if (fin.diverged[l]) m.mark_diverged(fin.diverged_at[l]);
      r.metrics = std::move(m);
    }
  }

 private:
  struct Group {
    explicit Group(const Scenario& s)
        : scenario(&s),
          disturbance(s.disturbance),
          faults(s.faults, s.saturation),
          exo(disturbance, faults, s.sample_time, s.substeps) {}
    const Scenario* scenario;
    std::vector<int> lanes;  // in increasing order
    Disturbance disturbance;
    FaultSet faults;
    ExogenousInputs<3, 4> exo;  // refers to the two above: groups never move (deque)
  };

  std::vector<SpacecraftLane*> lanes_;
  int width_;
  const PackSetup& setup_;
  std::deque<Group> groups_;
  std::vector<std::size_t> group_of_;
  std::vector<MetricsAccumulator<3, 4>> metrics_;
  std::vector<bool> done_;
  std::vector<double> buffer_;  // the inputs of a block (PackHost::inputs)
};

void run_pack(std::span<SpacecraftLane* const> lanes, const Mat34& G, const Mat43& G_pinv,
              Isa isa) {
  const int width = lane_width(isa);
  PackSetup su;
  su.lanes = static_cast<int>(lanes.size());
  const Scenario& s0 = *lanes[0]->scenario;
  su.Ts = s0.sample_time;
  su.substeps = s0.substeps;
  su.samples = s0.samples();
  su.block = std::max(1, 16 / su.substeps);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) {
      su.G[i * 4 + j] = G(i, j);
      su.G_pinv[j * 3 + i] = G_pinv(j, i);
    }
  for (int l = 0; l < width; ++l) {
    const SpacecraftLane& lane = *lanes[l < su.lanes ? l : 0];
    su.configs[l] = &lane.config;
    for (int i = 0; i < 4; ++i) {
      su.truth[i][l] = lane.truth[i];
      su.model[i][l] = lane.model[i];
      su.mismatch = su.mismatch || lane.truth[i] != lane.model[i];
    }
    for (int i = 0; i < 6; ++i) su.x0[i][l] = lane.scenario->initial_state[i];
    su.saturation[l] = lane.scenario->saturation.value_or(std::numeric_limits<double>::infinity());
  }
  // The metrics in the kernel, unless a lane has more windows or faults than it keeps.
  su.kernel_metrics = true;
  su.want_samples = false;
  for (const SpacecraftLane* l : lanes) {
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
      const SpacecraftLane& lane = *lanes[l < su.lanes ? l : 0];
      const SimulationOptions& o = *lane.options;
      for (int w = 0; w < su.windows; ++w) {
        const std::size_t e = static_cast<std::size_t>(w);
        const Window win = w == 0                        ? o.window
                           : e <= o.extra_windows.size() ? o.extra_windows[e - 1]
                                                         : Window{inf, inf};
        su.window[w][0][l] = win.t0;
        su.window[w][1][l] = win.t1;
      }
      for (int f = 0; f < su.onsets; ++f) {
        const std::size_t e = static_cast<std::size_t>(f);
        su.onset[f][l] = e < lane.scenario->faults.size() ? lane.scenario->faults[e].onset : inf;
      }
    }
  }
  su.shared_inputs = true;
  for (const SpacecraftLane* l : lanes)
    su.shared_inputs = su.shared_inputs && l->scenario == lanes[0]->scenario;
  Host host(lanes, width, su);
  PackFinal fin{};
  kernel_for(isa)(su, host, fin);
  host.finish(fin);
}

// The narrowest instruction set up to `widest` that holds n lanes: a wide register costs more
// per instruction than a narrow one (AVX-512 on 2 lanes is slower than SSE2), and every
// instruction set gives the same bits.
Isa narrowest(Isa widest, std::size_t n) {
  static const std::vector<Isa> supported = supported_isas();
  for (Isa isa : supported) {
    if (isa == widest) break;
    if (static_cast<std::size_t>(lane_width(isa)) >= n) return isa;
  }
  return widest;
}

}  // namespace

void run_spacecraft_lanes(std::span<SpacecraftLane> lanes, const Mat34& G, const Mat43& G_pinv,
                          Isa isa) {
  // Lanes can share a pack when their loops have the same shape: sample time, substeps,
  // samples, control law (and network size). Packs are formed in task order.
  using Key = std::tuple<double, int, std::int64_t, ControllerType, double>;
  const auto key = [](const SpacecraftLane& l) {
    const bool adaptive = l.config.type == ControllerType::adaptive_neural_pi_fosmc;
    return Key{l.scenario->sample_time, l.scenario->substeps, l.scenario->samples(), l.config.type,
               adaptive ? l.config.nodes : 0.0};
  };
  const std::size_t width = static_cast<std::size_t>(lane_width(isa));
  std::vector<bool> taken(lanes.size(), false);
  std::vector<SpacecraftLane*> pack;
  for (std::size_t i = 0; i < lanes.size(); ++i) {
    if (taken[i]) continue;
    pack.clear();
    const Key k = key(lanes[i]);
    for (std::size_t j = i; j < lanes.size() && pack.size() < width; ++j)
      if (!taken[j] && key(lanes[j]) == k) {
        taken[j] = true;
        pack.push_back(&lanes[j]);
      }
    run_pack(pack, G, G_pinv, narrowest(isa, pack.size()));
  }
}

}  // namespace ftc::sim::detail
