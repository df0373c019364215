// The registered plants. Adding a plant takes its own files (its class, its PlantKind, its
// dynamics and lane code: docs/architecture.md, "Plant seam") plus the lines marked below: the
// list of kinds, the list of classes for the runtime's simulate() with a Controller object,
// and, for a new shape (n, m), the three instantiations.
#include <cmath>
#include <stdexcept>
#include <tuple>

#include "ftc/sim/hexarotor.hpp"
#include "ftc/sim/manipulator.hpp"
#include "ftc/sim/plant_plugin.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/sim/rigid_body.hpp"
#include "ftc/sim/spacecraft.hpp"
#include "lanes/closed_loop.hpp"
#include "plants/kinds.hpp"
#include "plants/lane_host.hpp"

namespace ftc::sim {

const std::vector<PlantKind>& plant_kinds() {
  static const std::vector<PlantKind> kinds = {
      detail::spacecraft_kind(), detail::manipulator_kind(), detail::hexarotor_kind(),
      detail::rigid_body_kind(), detail::multirotor_kind()};  // <- add here
  return kinds;
}

namespace {

using RegisteredPlants = std::tuple<Spacecraft, Manipulator, Hexarotor, RigidBody>;  // <- and here

// The one loop with the controller for its law: with the lane code of the registered class the
// plant is (found by dynamic_cast), or through the Plant<N, M> interface when it is none of them.
template <int N, int M, std::size_t I = 0>
SimulationResult run_registered(const Plant<N, M>& plant, Controller<N, M>& controller,
                                const Scenario& scenario, const SimulationOptions& options) {
  if constexpr (I < std::tuple_size_v<RegisteredPlants>) {
    using P = std::tuple_element_t<I, RegisteredPlants>;
    if constexpr (P::kAxes == N && P::kActuators == M)
      if (const auto* p = dynamic_cast<const P*>(&plant))
        return detail::run_controller(*p, controller, scenario, options);
    return run_registered<N, M, I + 1>(plant, controller, scenario, options);
  } else {
    return detail::run_controller(plant, controller, scenario, options);
  }
}

}  // namespace

template <int N, int M>
SimulationResult simulate(const Plant<N, M>& plant, Controller<N, M>& controller,
                          const Scenario& scenario, const SimulationOptions& options) {
  throw_if_errors("scenario " + scenario.name, scenario.validate("", N, M));
  return run_registered(plant, controller, scenario, options);
}

namespace detail::isa_scalar {
template <int N, int M>
void object_plant_kernel(const PackSetup<N, M>& su, PackHost<N, M>& host, PackFinal<N, M>& fin,
                         const ObjectController& c, const ObjectPlant& p) {
  run_closed_loop<double, true>(
      su, [&] { return ObjectPlantLanes<N, M>(p); }, [&] { return ObjectLaw<N, M>(c); }, host, fin);
}
}  // namespace detail::isa_scalar

// One per plant shape (n, m), with make_controller in controllers/factory.cpp.  <- and here
#define FTC_SHAPE(N, M)                                                                            \
  template SimulationResult simulate<N, M>(const Plant<N, M>&, Controller<N, M>&, const Scenario&, \
                                           const SimulationOptions&);                              \
  template void detail::isa_scalar::object_plant_kernel<N, M>(                                     \
      const detail::PackSetup<N, M>&, detail::PackHost<N, M>&, detail::PackFinal<N, M>&,           \
      const detail::ObjectController&, const detail::ObjectPlant&);
FTC_SHAPE(3, 4)
FTC_SHAPE(2, 3)
FTC_SHAPE(3, 6)
FTC_SHAPE(3, 8)
#undef FTC_SHAPE

const PlantKind* find_plant_kind(std::string_view model) {
  for (const PlantKind& k : plant_kinds())
    if (k.model == model) return &k;
  if (model.rfind(kPluginPrefix, 0) == 0) try {
      return find_plant_plugin(model).kind;
    } catch (const InputError&) {
      return nullptr;  // make_plant and the job's reader say why
    }
  return nullptr;
}

void AnyPlant::simulate_pack(std::span<const PackTask> tasks, std::span<SimulationResult> results,
                             std::span<std::string> errors) const {
  simulate_pack(tasks, results, errors, active_isa());
}

void AnyPlant::simulate_pack(std::span<const PackTask> tasks, std::span<SimulationResult> results,
                             std::span<std::string> errors, Isa /*isa*/) const {
  for (std::size_t i = 0; i < tasks.size(); ++i) {
    errors[i].clear();
    try {
      results[i] = simulate(*tasks[i].controller, *tasks[i].scenario, *tasks[i].options);
    } catch (const InputError& e) {
      errors[i] = e.what();
    }
  }
}

std::string plant_model_names() {
  std::string s;
  for (const PlantKind* k : all_plant_kinds()) s += (s.empty() ? "" : ", ") + k->model;
  return s + ", or plugin:NAME for a plant plugin";
}

std::unique_ptr<AnyPlant> make_plant(const PlantSpec& spec) {
  const PlantKind* kind = spec.model.rfind(kPluginPrefix, 0) == 0
                              ? find_plant_plugin(spec.model).kind
                              : find_plant_kind(spec.model);
  if (!kind)
    throw InputError(
        "plant", "/model",
        "unknown plant model '" + spec.model + "' (known: " + plant_model_names() + ")");
  const std::vector<double> values = spec.values.empty() ? kind->defaults() : spec.values;
  throw_if_errors("plant", kind->validate(values, ""));
  return kind->make(values);
}

std::vector<double> PlantKind::defaults() const {
  std::vector<double> v;
  for (const PlantParameter& p : parameters)
    v.insert(v.end(), p.defaults.begin(), p.defaults.end());
  return v;
}

int PlantKind::actuators_of(const std::vector<double>& values) const {
  if (!count_actuators) return actuators;
  return count_actuators(values.empty() ? defaults() : values);
}

std::size_t PlantKind::value_count() const {
  std::size_t n = 0;
  for (const PlantParameter& p : parameters) n += p.size();
  return n;
}

std::size_t PlantKind::offset(std::string_view parameter) const {
  std::size_t n = 0;
  for (const PlantParameter& p : parameters) {
    if (p.name == parameter) return n;
    n += p.size();
  }
  return std::string_view::npos;
}

const UncertainParameter* PlantKind::find_uncertain(std::string_view parameter) const {
  for (const UncertainParameter& u : uncertain)
    if (u.parameter == parameter) return &u;
  return nullptr;
}

std::string PlantKind::uncertain_names() const {
  std::string s;
  for (const UncertainParameter& u : uncertain) s += (s.empty() ? "" : ", ") + u.parameter;
  return s.empty() ? "none" : s;
}

std::vector<double> PlantKind::parameter_values(const std::vector<double>& values,
                                                std::string_view parameter) const {
  const std::size_t at = offset(parameter);
  for (const PlantParameter& p : parameters)
    if (p.name == parameter)
      return {values.begin() + static_cast<long>(at),
              values.begin() + static_cast<long>(at + p.size())};
  throw std::logic_error("no plant parameter " + std::string(parameter));
}

std::vector<double> PlantKind::with_true_values(std::vector<double> values,
                                                const std::vector<TrueValue>& truth,
                                                const std::string& path) const {
  for (const TrueValue& t : truth) {
    const std::string where = path + "/" + t.parameter;
    if (!find_uncertain(t.parameter))
      throw InputError("plant", where,
                       "the " + model + " plant does not declare " + t.parameter +
                           " uncertain (its uncertain parameters: " + uncertain_names() + ")");
    const std::size_t at = offset(t.parameter);
    const UncertainParameter& u = *find_uncertain(t.parameter);
    for (const PlantParameter& p : parameters)
      if (p.name == t.parameter) {
        if (u.per_actuator) {
          // The plant's m values; the slots past m keep theirs (no actuator reads them).
          const auto m = static_cast<std::size_t>(actuators_of(values));
          if (t.values.size() != m)
            throw InputError("plant", where,
                             "expected one value per actuator of the " + model + " (" +
                                 std::to_string(m) + "), got " + std::to_string(t.values.size()));
          std::copy(t.values.begin(), t.values.end(), values.begin() + static_cast<long>(at));
          continue;
        }
        if (u.scaling == Scaling::congruence && p.size() == 9 && t.values.size() == 3) {
          // A tensor given by its principal moments: the diagonal one.
          const std::vector<double>& d = t.values;
          const double J[9] = {d[0], 0.0, 0.0, 0.0, d[1], 0.0, 0.0, 0.0, d[2]};
          std::copy(J, J + 9, values.begin() + static_cast<long>(at));
          continue;
        }
        if (t.values.size() != p.size())
          throw InputError("plant", where,
                           u.scaling == Scaling::congruence
                               ? "expected 3 principal moments or a 3×3 tensor (the " + model +
                                     "'s " + p.name + "), got " + std::to_string(t.values.size()) +
                                     " numbers"
                               : "expected " + std::to_string(p.size()) + " numbers (the " + model +
                                     "'s " + p.name + "), got " + std::to_string(t.values.size()));
        std::copy(t.values.begin(), t.values.end(), values.begin() + static_cast<long>(at));
      }
  }
  return values;
}

std::vector<FieldError> PlantKind::check_true_values(const std::vector<double>& values,
                                                     const std::vector<TrueValue>& truth,
                                                     const std::string& path) const {
  std::vector<FieldError> errs;
  try {
    // Only the given values' own errors: the job's plant values have theirs.
    for (FieldError& e : validate(with_true_values(values, truth, path), path))
      for (const TrueValue& t : truth) {
        const std::string p = path + "/" + t.parameter;
        if (e.path == p || e.path.rfind(p + "/", 0) == 0) {
          errs.push_back(std::move(e));
          break;
        }
      }
  } catch (const InputError& e) {
    errs = e.errors();
  }
  return errs;
}

void PlantKind::scale(const UncertainParameter& u, std::vector<double>& values,
                      std::span<const double> factors) {
  switch (u.scaling) {
    case Scaling::elementwise:
      for (std::size_t i = 0; i < values.size() && i < factors.size(); ++i) values[i] *= factors[i];
      return;
    case Scaling::congruence:
      // (S J S)_ik = √(s_i s_k) J_ik; on the diagonal s_i J_ii, as elementwise scales a diagonal.
      if (values.size() != 9 || factors.size() < 3) return;
      for (std::size_t i = 0; i < 3; ++i)
        for (std::size_t k = 0; k < 3; ++k)
          values[3 * i + k] *= i == k ? factors[i] : std::sqrt(factors[i] * factors[k]);
      return;
  }
}

std::vector<FieldError> PlantKind::validate(const std::vector<double>& values,
                                            const std::string& path) const {
  std::vector<FieldError> errs;
  if (values.size() != value_count()) {
    errs.push_back({path, "expected " + std::to_string(value_count()) + " parameter values for " +
                              model + ", got " + std::to_string(values.size())});
    return errs;
  }
  if (check_values) return check_values(values, path);
  std::size_t i = 0;
  for (const PlantParameter& p : parameters)
    for (std::size_t j = 0; j < p.size(); ++j, ++i) {
      std::string where = path + "/" + p.name;
      if (p.size() > 1) where.append("/").append(std::to_string(j));
      if (std::string msg = p.range.check(values[i]); !msg.empty())
        errs.push_back({where, std::move(msg)});
    }
  return errs;
}

}  // namespace ftc::sim
