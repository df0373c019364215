#pragma once
// The simulator's interface between the host (plants/lane_host.hpp: scenarios, disturbances,
// faults, the metrics' setup and read-back, trajectories, in plain C++ compiled once) and the
// kernels (lanes/closed_loop.hpp: the one closed loop, of W simulations of one plant in W SIMD
// lanes, compiled once per plant and instruction set). Only plain arrays and plain functions
// cross it, so that nothing compiled for one instruction set is shared with code compiled for
// another. Every array is sized by the plant's shape: n axes, m actuators (template parameters
// N, M).
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
inline constexpr int kMaxPlantConstants = 64;
// Actuators of a plant with an operating point (PackSetup::trimmed).
inline constexpr int kMaxActuators = 8;

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

// What a pack's metrics are measured against (SPEC §6, §16; ftc/sim/metrics.hpp), per lane:
// lanes/metric_lanes.hpp's MetricLanes reads it, for any number of windows and fault onsets.
// Arrays are lane-minor, kMaxLanes doubles a row; the host owns the storage of the per-window
// and per-onset rows (plants/lane_host.hpp).
template <int M>
struct MetricSetup {
  int windows = 0;                     // the objective window, then the extra ones
  const double* window = nullptr;      // [windows][2][kMaxLanes]: [t0, t1); [inf, inf) unused
  const double* tail_start = nullptr;  // [windows][kMaxLanes]: the steady-state tail, NaN: none
  int onsets = 0;
  const double* onset = nullptr;  // [onsets][kMaxLanes]: each fault's onset, inf: unused
  // The command's limits per actuator [limit_lo, limit_hi] (the plant's own range, within ± the
  // scenario's saturation): the loop holds the command and the faulted output within them and
  // saturation_fraction counts the samples at them. Then the earliest fault onset (+inf: none) and
  // the settling threshold squared (NaN: no settling time), per lane; whether any lane has a
  // threshold or a tail.
  double limit_lo[M][kMaxLanes] = {};
  double limit_hi[M][kMaxLanes] = {};
  double first_onset[kMaxLanes] = {};
  double threshold_sq[kMaxLanes] = {};
  bool any_settling = false;
  bool any_tail = false;
};

// The metrics of a pack's lanes at its end, each field of the metrics record
// (ftc/sim/metrics_record.hpp) at its slot among the fields of its scope (metric_slot("ise"),
// ...): per window, per run, per fault onset. The host owns the per-window and per-onset storage
// and reads every field back by the same table.
struct MetricsOut {
  static constexpr std::size_t kWindowFields = metric_count(MetricScope::window);
  static constexpr std::size_t kRunFields = metric_count(MetricScope::run);
  static constexpr std::size_t kFaultFields = metric_count(MetricScope::fault);
  double* window = nullptr;  // [windows][kWindowFields][kMaxLanes]
  double run[kRunFields][kMaxLanes] = {};
  double* fault = nullptr;  // [onsets][kFaultFields][kMaxLanes]
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
  // The lanes' actuator model (ftc/sim/scenario.hpp's ActuatorModel; every lane of a pack has
  // one or none): the half step's gain and largest step per lane (ActuatorSteps). The command is
  // clamped to [limit_lo, limit_hi] (MetricSetup) before the model follows it.
  bool actuator = false;
  double act_gain[kMaxLanes] = {};
  double act_step[kMaxLanes] = {};
  // For a plant whose actuators work about an operating point (PlantLanes' kTrimmed: a rotor's
  // hover thrust), per actuator and lane: u is a deviation from u0, and the faults act on the
  // physical output u0 + u (a loss of effectiveness scales it, a stuck actuator holds it). The
  // deviation's range (the rotor's 0 .. max thrust, less u0) is in MetricSetup's limits.
  double u0[M][kMaxLanes] = {};
  double Ts = 0.0;
  int substeps = 1;
  std::int64_t samples = 0;
  int block = 16;  // samples per exchange with the host

  // Sensors (ftc/sim/sensors.hpp, SPEC §18): every lane of a pack has them or none, with one
  // delay and one acceleration source. The noise comes from the host (PackHost::noise); per lane
  // the quantisation steps (0: none) and the low-pass's gain Ts / (τ + Ts); `ring`, host-owned
  // storage for the delayed measurements, (delay + 1) · 3N · kMaxLanes doubles.
  bool sensors = false;
  int delay = 0;
  bool differentiated = false;
  double angle_step[kMaxLanes] = {};
  double rate_step[kMaxLanes] = {};
  double lowpass_gain[kMaxLanes] = {};
  double* ring = nullptr;

  bool want_samples = false;  // call PackHost::samples (a lane records its trajectory)
  MetricSetup<M> metrics;
};

// The host side, called twice per block of samples (never per sample).
template <int N, int M>
class PackHost {
 public:
  // The inputs of samples k0 .. k0 + n - 1: for sample k0 + i, substep j, instant q (0 start,
  // 1 midpoint, 2 end), the ExoRows of instant ((i · substeps) + j) · 3 + q, one after another.
  virtual const double* inputs(std::int64_t k0, int n) = 0;
  // With sensors (PackSetup::sensors), the measurement noise of samples k0 .. k0 + n - 1 (called
  // after inputs() for the same samples): for sample k0 + i, 3N rows (the angles' σ_a z, the
  // rates' bias b_k, their σ_r z) of `stride` doubles each (ExoRows::stride), one after another.
  virtual const double* noise(std::int64_t k0, int n) = 0;
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
  bool model_invalid[kMaxLanes] = {};  // the plant's lane code says X left its model's validity
  MetricsOut metrics;
};

template <int N, int M>
using PackKernel = void (*)(const PackSetup<N, M>&, PackHost<N, M>&, PackFinal<N, M>&);

// A runtime Controller object (ftc/sim/controller.hpp) as the loop's control law, one lane: the
// host's two functions over it (plants/lane_host.hpp), so that the kernel needs no Eigen.
struct ObjectController {
  void* self = nullptr;
  void (*reset)(void* self) = nullptr;
  // u_d (m values) from the sample's time, X1, X2, the measured acceleration a (n values each)
  // and f(X) of the simulated plant, which a model-based controller of that plant reuses.
  void (*step)(void* self, double t, const double* X1, const double* X2, const double* a,
               const double* f, double* u) = nullptr;
};

// A plant known only through the Plant<n, m> interface (not a registered class, so without lane
// code), one lane: f(X) and G(X) (n × m, row-major) through the host.
struct ObjectPlant {
  const void* self = nullptr;
  void (*f)(const void* self, const double* x, double* f) = nullptr;
  void (*G)(const void* self, const double* x, double* G) = nullptr;
};

// The kernel of plant class P (its lane code: PlantLanes<P>, lanes/closed_loop.hpp), one per
// instruction set, each in the namespace of its instruction set (lanes/lane.hpp says why).
// Defined by the plant's lanes file compiled once per instruction set (FTC_PLANT_KERNEL and
// ftc_plant_kernels() in sim_core/CMakeLists.txt).
#ifndef FTC_ISA_NS
#define FTC_ISA_NS isa_scalar
#endif
inline namespace FTC_ISA_NS {}  // namespace FTC_ISA_NS
#define FTC_DECLARE_PACK_KERNEL(ns)                                            \
  namespace ns {                                                               \
  template <class P, int N, int M>                                             \
  void pack_kernel(const PackSetup<N, M>&, PackHost<N, M>&, PackFinal<N, M>&); \
  }
FTC_DECLARE_PACK_KERNEL(isa_scalar)
FTC_DECLARE_PACK_KERNEL(isa_sse2)
FTC_DECLARE_PACK_KERNEL(isa_avx2)
FTC_DECLARE_PACK_KERNEL(isa_avx512)
#undef FTC_DECLARE_PACK_KERNEL

// The loop of plant class P with a runtime Controller for its law (sim::simulate), in one lane of
// the scalar kernel: P's scalar lanes file defines it (FTC_PLANT_KERNEL).
namespace isa_scalar {
template <class P, int N, int M>
void controller_kernel(const PackSetup<N, M>&, PackHost<N, M>&, PackFinal<N, M>&,
                       const ObjectController&);
// The same for a plant known only through the Plant<n, m> interface: plants/registry.cpp
// defines it for the registered shapes.
template <int N, int M>
void object_plant_kernel(const PackSetup<N, M>&, PackHost<N, M>&, PackFinal<N, M>&,
                         const ObjectController&, const ObjectPlant&);
}  // namespace isa_scalar

}  // namespace ftc::sim::detail
