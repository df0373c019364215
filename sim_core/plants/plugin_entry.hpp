#pragma once
// The end of a plant plugin's source (docs/plugins.md):
//
//   FTCTUNE_PLANT_PLUGIN(Pendulum, pendulum_kind, build_pendulum)
//
// gives the library its entry point (ftc/sim/plant_plugin.hpp). `Pendulum` is the plant class (a
// final class derived from Plant<n, m>, with f_constants() for its lane code, as a shipped plant
// has); `pendulum_kind()` returns its PlantKind without `make`; `build_pendulum(values)` makes a
// Pendulum from the flattened parameter values (throwing InputError for values it refuses). The
// macro fills `make` with the plant's adapter (plants/plant_adapter.hpp): the same batch kernels,
// lane host and checks a shipped plant runs in. The lanes file (PlantLanes<Pendulum>, ending with
// FTC_PLANT_KERNEL(Pendulum)) is compiled once per instruction set by ftctune_add_plant.
//
// A plant compiled into a program rather than loaded (tests compare the two) uses
// plugin::kind_of<P>(kind, build) and register_plant_kind() instead.
#include <exception>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "ftc/sim/plant_plugin.hpp"
#include "plants/plant_adapter.hpp"

#ifndef FTC_PLANT_ABI_ID
#error "FTC_PLANT_ABI_ID is not defined: build plant plugins with ftctune_add_plant()"
#endif

namespace ftc::sim::plugin {

// The kind with `make` set: a PlantAdapter<P> of the values, built by `build`.
// Throws std::invalid_argument when the kind's n and m are not P's, or when a plant P builds calls
// itself by another model name than the kind's (the loader reports it as the plugin's error).
template <class P, class Build>
PlantKind kind_of(PlantKind kind, Build build) {
  if (kind.axes != P::kAxes || kind.actuators != P::kActuators)
    throw std::invalid_argument("the kind declares n = " + std::to_string(kind.axes) +
                                ", m = " + std::to_string(kind.actuators) +
                                " but the class is a Plant<" + std::to_string(P::kAxes) + ", " +
                                std::to_string(P::kActuators) + ">");
  if (const std::string m = build(kind.defaults()).model(); m != kind.model)
    throw std::invalid_argument("the kind's model is '" + kind.model +
                                "' but its plant's model() is '" + m + "'");
  kind.make = [build](const std::vector<double>& values) -> std::unique_ptr<AnyPlant> {
    return std::make_unique<detail::PlantAdapter<P>>(
        values, [build](const std::vector<double>& v) { return P(build(v)); });
  };
  return kind;
}

template <class P, class Build>
bool evaluate(Build build, const std::vector<double>& values, const double* x, double* f, double* G,
              double* G_pinv, std::string* error) {
  constexpr int N = P::kAxes, M = P::kActuators;
  try {
    const P p = build(values);
    const typename P::State s = Eigen::Map<const typename P::State>(x);
    const auto fx = p.f(s);
    const auto Gx = p.G(s);
    const auto Gp = p.G_pinv(s);
    for (int i = 0; i < N; ++i) f[i] = fx[i];
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < M; ++j) G[i * M + j] = Gx(i, j);
    for (int j = 0; j < M; ++j)
      for (int i = 0; i < N; ++i) G_pinv[j * N + i] = Gp(j, i);
    return true;
  } catch (const std::exception& e) {
    if (error) *error = e.what();
    return false;
  }
}

template <class P, class Build>
bool trim(Build build, const std::vector<double>& values, double* u0, double* lo, double* hi) {
  if constexpr (requires(const P& p) { p.actuator_trim(); }) {
    const auto t = build(values).actuator_trim();
    for (int j = 0; j < P::kActuators; ++j) {
      u0[j] = t.u0[j];
      lo[j] = t.lo[j];
      hi[j] = t.hi[j];
    }
    return true;
  } else {
    (void)build, (void)values, (void)u0, (void)lo, (void)hi;
    return false;
  }
}

}  // namespace ftc::sim::plugin

#define FTCTUNE_PLANT_PLUGIN(P, KIND, BUILD)                                                      \
  extern "C" __attribute__((visibility("default"))) const ::ftc::sim::PlantPluginApi*             \
  ftctune_plant_plugin() {                                                                        \
    static const ::ftc::sim::PlantPluginApi api = {                                               \
        ::ftc::sim::kPlantAbiVersion, FTC_PLANT_ABI_ID,                                           \
        [] { return ::ftc::sim::plugin::kind_of<P>(KIND(), BUILD); },                             \
        [](const std::vector<double>& v, const double* x, double* f, double* G, double* Gp,       \
           std::string* e) { return ::ftc::sim::plugin::evaluate<P>(BUILD, v, x, f, G, Gp, e); }, \
        [](const std::vector<double>& v, double* u0, double* lo, double* hi) {                    \
          return ::ftc::sim::plugin::trim<P>(BUILD, v, u0, lo, hi);                               \
        }};                                                                                       \
    return &api;                                                                                  \
  }
