#pragma once
// Scenario ensembles (SPEC §12): many scenarios drawn from distributions, reproducibly, so that
// gains are tuned for a family of faults and plants and checked on members they were not tuned
// on. The random numbers are normative: member k has its own SplitMix64 stream seeded from the
// ensemble's seed and k, and its draws are taken in a fixed order whether used or not, so any
// implementation expands the same members, in any order and on any number of threads.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ftc/sim/random_stream.hpp"
#include "ftc/sim/scenario.hpp"
#include "ftc/tune/job/job.hpp"

namespace ftc::tune {

// SplitMix64 (SPEC §12): ftc/sim/random_stream.hpp.
using sim::SplitMix64;

// A random variable: a constant, U(a, b), or log-uniform on [a, b] (0 < a).
struct Distribution {
  enum class Kind { constant, uniform, log_uniform };
  Kind kind = Kind::constant;
  double a = 0.0, b = 0.0;  // the constant is a

  static Distribution constant(double v) { return {Kind::constant, v, v}; }
  double draw(double u) const;
};

// A weighted choice among names in a canonical order: the first name whose cumulative weight
// exceeds u·W. Absent names weigh 0.
struct Choice {
  std::vector<double> weights;  // per canonical name
  std::size_t pick(double u) const;
};

inline constexpr std::array<sim::FaultType, 3> kFaultTypeOrder = {
    sim::FaultType::bias, sim::FaultType::loss_of_effectiveness, sim::FaultType::stuck};
inline constexpr std::array<sim::FaultProfileType, 2> kProfileOrder = {
    sim::FaultProfileType::abrupt, sim::FaultProfileType::incipient};

struct FaultDistribution {
  int count_lo = 0, count_hi = 0;     // a member gets lo + floor(u (hi - lo + 1)) faults
  std::vector<int> actuators;         // in listed order; empty: every actuator of the plant
  Choice type;                        // over kFaultTypeOrder
  std::optional<Distribution> onset;  // absent: half the duration
  Choice profile{{1.0, 0.0}};         // over kProfileOrder; default abrupt only
  Distribution rate = Distribution::constant(1.0);
  Distribution offset = Distribution::constant(0.0);
  Distribution amplitude = Distribution::constant(0.0);
  Distribution frequency = Distribution::constant(0.0);
  Distribution phase = Distribution::constant(0.0);
  Distribution fraction = Distribution::constant(0.5);
  Distribution value = Distribution::constant(0.0);
};

enum class Unrecoverable { exclude, include };

// A scale on a parameter the plant declares uncertain (sim::PlantKind::uncertain), under the
// ensemble key `<parameter>_scale` ("inertia_scale").
struct ParameterScale {
  std::string parameter;
  Distribution distribution;
};

// The sensors of a member (SPEC §18), drawn after SPEC §17's draws when the ensemble has the
// key, in this order, each draw consumed whether or not its entry is given: angle_noise,
// rate_noise, rate_bias (n draws, one per axis), bias_walk, delay. An absent entry keeps the
// base's value (the base's sensors block, or exact sensors without one).
struct SensorDistribution {
  std::optional<Distribution> angle_noise, rate_noise, rate_bias, bias_walk;
  // The delay in samples: lo + floor(u (hi - lo + 1)); absent: the base's.
  std::optional<std::pair<int, int>> delay;
};

struct EnsembleConfig {
  std::int64_t count = 1;
  std::uint64_t seed = 0;
  std::string base;  // the scenario members copy; "" = the first
  // Absent: factor 1 (the draws are consumed all the same). At most one scale per parameter.
  std::vector<ParameterScale> parameter_scales;
  std::optional<Distribution> initial_state_scale, disturbance_scale;
  // SPEC §17's actuator uncertainty (plants that declare it: rigid_body both, multirotor the
  // scale), drawn once per actuator after SPEC §12's draws, m scales then m misalignments: a
  // member's actuator_scale is the base's (else 1) times its draw, its actuator_misalignment the
  // base's (else 0) plus its draw, in rad. Absent: the base's (the draws are consumed all the
  // same).
  std::optional<Distribution> actuator_scale, actuator_misalignment;
  // The scale of one parameter; null when there is none.
  const Distribution* parameter_scale(std::string_view parameter) const;
  std::optional<FaultDistribution> faults;  // absent: members keep the base's faults
  std::optional<SensorDistribution> sensors;  // absent: members keep the base's sensors
  Unrecoverable unrecoverable = Unrecoverable::exclude;
};

inline constexpr std::int64_t kMaxEnsembleCount = 1000000;

// The factors on the uncertain parameters a member scales, by parameter: value i of the
// parameter takes factor i by its rule (sim::Scaling). SPEC §12 draws 3 (the first 3 draws of a
// member's stream), which every scaled parameter maps through its own distribution.
inline constexpr std::size_t kParameterFactors = 3;
using ParameterFactors = std::vector<std::pair<std::string, std::array<double, kParameterFactors>>>;

// The ensemble's base scenario with factors applied as the scales apply them: the true values of
// every uncertain parameter of the plant (the base's, else the plant's), each scaled by its
// factors when it has any; one factor per initial-state component, one on every disturbance
// amplitude. A member is this with its drawn factors, then its drawn faults.
sim::Scenario scaled_base(const Job& job, const ParameterFactors& parameter_factors,
                          const std::vector<double>& state_factor, double disturbance_factor);

// `s` with the actuator draws applied (EnsembleConfig::actuator_scale, actuator_misalignment):
// the m values of each of the plant's per-actuator uncertain parameters, scale_draws[j] and
// misalignment_draws[j] being actuator j's drawn values.
void apply_actuator_draws(const Job& job, sim::Scenario& s, const std::vector<double>& scale_draws,
                          const std::vector<double>& misalignment_draws);

// Member k (0-based) of the job's ensemble with the given seed, named `<base>-<k>`. The job must
// be valid (parse_job checked the ensemble against its plant and scenarios).
sim::Scenario ensemble_member(const Job& job, std::uint64_t seed, std::int64_t k);
// Members 0 .. count-1; seed and count default to the job's ensemble's.
std::vector<sim::Scenario> expand_ensemble(const Job& job,
                                           std::optional<std::uint64_t> seed = std::nullopt,
                                           std::optional<std::int64_t> count = std::nullopt);

// What is wrong with the names of an ensemble of `count` members (member k is `<base>-<k>`), as
// errors at their paths: listed scenarios whose names a member would take again, and member
// names longer than a scenario name may be.
std::vector<FieldError> member_name_errors(const Job& job, std::int64_t count);

// The member count a command asked for (`--count`), or the ensemble's own: throws InputError
// (source "--count") when it is outside 1..kMaxEnsembleCount or would give a member the name of
// a listed scenario or a name too long. The job must have an ensemble.
std::int64_t ensemble_count(const Job& job, std::optional<std::int64_t> count);

// The base scenario of the job's ensemble.
const sim::Scenario& ensemble_base(const Job& job);
// The same, or null when the job names no such scenario (for checks that report, not throw).
const sim::Scenario* find_ensemble_base(const Job& job);

}  // namespace ftc::tune
