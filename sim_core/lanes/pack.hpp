#pragma once
// The batch simulator's interface between the host (plants/lane_host.hpp: scenarios,
// disturbances, faults, metrics, trajectories, in plain C++ compiled once) and the kernels
// (lanes/closed_loop.hpp: the closed loop of W simulations of one plant in W SIMD lanes,
// compiled once per plant and instruction set). Only plain arrays cross it, so that nothing
// compiled for one instruction set is shared with code compiled for another. Every array is
// sized by the plant's shape: n axes, m actuators (template parameters N, M).
//
// A pack is up to W simulations in lockstep that share the sample time, the substeps, the
// number of samples, the controller type (and the network size of the adaptive one) and, when
// the plant's G is constant, the input matrix; each lane has its own gains, initial state, true
// and model plant constants, saturation, disturbance and faults. Lanes beyond `lanes` repeat
// lane 0 and are ignored.
#include <cstdint>

#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/metrics_record.hpp"

namespace ftc::sim::detail {

inline constexpr int kMaxLanes = 8;  // AVX-512: 8 doubles
// The constants a plant's f and G are built from, per lane (Spacecraft::f_constants()).
inline constexpr int kMaxPlantConstants = 8;
// Actuators of a plant with an operating point (PackSetup::trimmed).
inline constexpr int kMaxActuators = 8;
// Metrics the kernel accumulates itself (SPEC §6; the host's MetricsAccumulator otherwise):
// the objective window and the extra ones, and the peak error after each fault onset.
inline constexpr int kMaxWindows = 8;
inline constexpr int kMaxOnsets = 8;

// The exogenous inputs at one instant (a stage time of RK4): the disturbance Δ(t) and the fault
// effect u = gain ⊙ u_d + offset, as kCount rows of `stride` doubles each. The stride is 1 when
// every lane has the same inputs (PackSetup::shared_inputs: the kernel broadcasts the value) and
// the pack's width otherwise (one value per lane, lane-minor, so that a kernel loads W at a
// time). Packed tight: with one double per row a block of instants takes 4 kB, where rows of 8
// took 34 kB, more than the level-1 cache, for the same 4 kB of values.
template <int N, int M>
struct ExoRows {
  static constexpr int kDist = 0;        // Δ(t), N rows
  static constexpr int kGain = N;        // the faults' gains, M rows
  static constexpr int kOffset = N + M;  // the faults' offsets, M rows
  static constexpr int kCount = N + 2 * M;
  static constexpr int stride(bool shared, int width) { return shared ? 1 : width; }
};

// What the kernel reports for one sample k of every lane: X(t_k), the command u_d(t_k), and
// whether the step from t_k left the bounds (|X_i| > 1e6, inf or NaN): that lane diverged.
template <int N, int M>
struct SampleLanes {
  double x[2 * N][kMaxLanes];
  double u[M][kMaxLanes];
  double ua[M][kMaxLanes];  // with an actuator model (PackSetup::actuator): its output u_a(t_k)
  bool diverged[kMaxLanes];
};

template <int N, int M>
struct PackSetup {
  int lanes = 1;  // in use, 1 .. W
  const ControllerConfig* configs[kMaxLanes] = {};
  // The constants of the simulated plant (truth) and of the controller's model, per lane.
  double truth[kMaxPlantConstants][kMaxLanes] = {};
  double model[kMaxPlantConstants][kMaxLanes] = {};
  bool mismatch = false;  // some lane's truth differs from its model
  // Every lane has the same exogenous inputs (one scenario): the host writes one value per
  // row (ExoRows), and the kernel broadcasts it.
  bool shared_inputs = false;
  // For a plant whose G is constant (the same for every lane): G and its right inverse,
  // row-major. Unused otherwise (the plant's lane code forms G(X) and G⁺(X)).
  double G[N * M] = {};
  double G_pinv[M * N] = {};
  double x0[2 * N][kMaxLanes] = {};
  double saturation[kMaxLanes] = {};  // u_max; +inf for none
  // The lanes' actuator model (ftc/sim/scenario.hpp's ActuatorModel; every lane of a pack has
  // one or none): the half step's gain and largest step per lane (ActuatorSteps). The command is
  // clamped to [limit_lo, limit_hi] (below) before the model follows it.
  bool actuator = false;
  double act_gain[kMaxLanes] = {};
  double act_step[kMaxLanes] = {};
  // For a plant whose actuators work about an operating point (PlantLanes' kTrimmed: a rotor's
  // hover thrust), per actuator and lane: u is a deviation from u0, the faults act on the
  // physical output u0 + u (a loss of effectiveness scales it, a stuck actuator holds it), and
  // the deviation is held within [lo, hi] (the rotor's 0 .. max thrust, less u0) after them.
  double u0[M][kMaxLanes] = {};
  double lo[M][kMaxLanes] = {};
  double hi[M][kMaxLanes] = {};
  double Ts = 0.0;
  int substeps = 1;
  std::int64_t samples = 0;
  int block = 16;  // samples per exchange with the host

  // The kernel accumulates the metrics (else the host does, from PackHost::samples).
  bool kernel_metrics = false;
  bool want_samples = true;  // call PackHost::samples (recording, or the host's metrics)
  int windows = 0;           // [t0, t1) per lane: 0 the objective window, then the extra ones
  double window[kMaxWindows][2][kMaxLanes] = {};  // unused: [inf, inf)
  int onsets = 0;
  double onset[kMaxOnsets][kMaxLanes] = {};  // unused: inf
  // The window metrics' setup (ftc/sim/metrics.hpp, sim_core/metrics_accumulator.hpp): the
  // command limits of saturation_fraction per actuator and lane, the earliest fault onset
  // (+inf: none), the settling threshold squared (NaN: no settling time) and each window's
  // steady-state tail start (NaN: no tail), per lane; whether any lane has a threshold or a tail.
  double limit_lo[M][kMaxLanes] = {};
  double limit_hi[M][kMaxLanes] = {};
  double first_onset[kMaxLanes] = {};
  double threshold_sq[kMaxLanes] = {};
  double tail_start[kMaxWindows][kMaxLanes] = {};
  bool any_settling = false;
  bool any_tail = false;
};

// The host side, called twice per block of samples (never per sample).
template <int N, int M>
class PackHost {
 public:
  // The inputs of samples k0 .. k0 + n - 1: for sample k0 + i, substep j, instant q (0 start,
  // 1 midpoint, 2 end), the ExoRows of instant ((i · substeps) + j) · 3 + q, one after another.
  virtual const double* inputs(std::int64_t k0, int n) = 0;
  // Samples k0 .. k0 + n - 1 as simulated (lanes that had diverged before are to be ignored).
  virtual void samples(std::int64_t k0, int n, const SampleLanes<N, M>* out) = 0;

 protected:
  ~PackHost() = default;
};

template <int N, int M>
struct PackFinal {
  double x[2 * N][kMaxLanes];       // X at the end of each lane's run
  std::int64_t samples[kMaxLanes];  // samples simulated per lane
  bool diverged[kMaxLanes];
  double diverged_at[kMaxLanes];  // s
  // With kernel_metrics: the record's fields (ftc/sim/metrics_record.hpp) by scope, each at its
  // slot (metric_slot("ise") and so on): per window (the objective window first), per lane, or
  // per fault onset. The host reads them back by the same table.
  static constexpr std::size_t kWindowFields = metric_count(MetricScope::window);
  static constexpr std::size_t kRunFields = metric_count(MetricScope::run);
  static constexpr std::size_t kFaultFields = metric_count(MetricScope::fault);
  double window_field[kWindowFields][kMaxWindows][kMaxLanes];
  double run_field[kRunFields][kMaxLanes];
  double fault_field[kFaultFields][kMaxOnsets][kMaxLanes];
};

template <int N, int M>
using PackKernel = void (*)(const PackSetup<N, M>&, PackHost<N, M>&, PackFinal<N, M>&);

// The kernel of plant class P (its lane code: PlantLanes<P>, lanes/closed_loop.hpp), one per
// instruction set, each in the namespace of its instruction set (lanes/lane.hpp says why).
// Defined by the plant's lanes file compiled once per instruction set (FTC_PLANT_KERNEL and
// ftc_plant_kernels() in sim_core/CMakeLists.txt).
#ifndef FTC_ISA_NS
#define FTC_ISA_NS isa_scalar
#endif
inline namespace FTC_ISA_NS {}  // inline from its first declaration on (the others are not)
#define FTC_DECLARE_PACK_KERNEL(ns)                                                          \
  namespace ns {                                                                             \
  template <class P, int N, int M>                                                           \
  void pack_kernel(const PackSetup<N, M>&, PackHost<N, M>&, PackFinal<N, M>&);              \
  }
FTC_DECLARE_PACK_KERNEL(isa_scalar)
FTC_DECLARE_PACK_KERNEL(isa_sse2)
FTC_DECLARE_PACK_KERNEL(isa_avx2)
FTC_DECLARE_PACK_KERNEL(isa_avx512)
#undef FTC_DECLARE_PACK_KERNEL

}  // namespace ftc::sim::detail
