#pragma once
// The controllers in one table: each controller's name in files, its name in tables and figures,
// a one-line description and its traits. Everything that names or tells controllers apart reads
// it: the file formats and their JSON Schema, the command line, the display names, the figures'
// line styles, the batch simulator's pack shapes. Their gains (names, units, valid ranges,
// which controller has which) are the field table of controller_config.hpp, controller_fields(),
// and their defaults, the paper's Table 1, are ControllerConfig's initialisers.
//
// The compile-time side is visit_controller_type(): the one place a run-time type becomes a
// type, for the laws of the batch simulator (lanes/closed_loop.hpp) and the controller classes
// (controllers/factory.hpp), each of which maps it with a specialisation next to its own code.
// The dispatch happens once per pack or per controller object, never per sample.
//
// To add a controller: its enumerator, its line here, its fields' bits in controller_fields(),
// its law in controllers/laws.hpp with its law::LawOf specialisation, and its class with its
// ControllerClass specialisation (controllers/plant_model.hpp).
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

namespace ftc::sim {

enum class ControllerType : std::uint8_t { nftsmc, fosmc, pi_fosmc, adaptive_neural_pi_fosmc };

struct ControllerInfo {
  ControllerType type;
  const char* name;          // in job, gains and result files, and on the command line
  const char* display_name;  // in tables, figures and messages
  const char* description;   // one line, for the JSON Schema
  bool model_based;  // the law uses the controller's plant model f(X) (else it learns it)
  bool integral;     // the law has an integral state (the PI surface, Kp and Ki)
  bool adaptive;     // adaptive switching gain and an RBF network: the network's size (nodes)
                     // shapes the simulated loop, and its centres are a range (centre_range)
  int plot_style;    // base line style in figures (tuner/report/gnuplot.hpp); the tuned one is 1
};

inline constexpr ControllerInfo kControllers[] = {
    {ControllerType::nftsmc, "nftsmc", "NFTSMC",
     "nonsingular fast terminal sliding-mode controller (paper's Appendix C)", true, false, false,
     4},
    {ControllerType::fosmc, "fosmc", "FOSMC",
     "full-order sliding-mode controller (paper's Appendix D)", true, false, false, 3},
    {ControllerType::pi_fosmc, "pi_fosmc", "PI-FOSMC",
     "PI full-order sliding-mode controller (paper's eqs. 7, 11-13)", true, true, false, 2},
    {ControllerType::adaptive_neural_pi_fosmc, "adaptive_neural_pi_fosmc",
     "adaptive neural PI-FOSMC",
     "model-free PI-FOSMC with an RBF network and an adaptive switching gain (paper's eqs. 20, "
     "22, 26-30)",
     false, true, true, 5},
};

// Every type, in table order.
inline constexpr auto kAllControllerTypes = [] {
  std::array<ControllerType, std::size(kControllers)> types{};
  for (std::size_t i = 0; i < types.size(); ++i) types[i] = kControllers[i].type;
  return types;
}();

// The table lists the enumerators in order, so a type indexes its line.
static_assert([] {
  for (std::size_t i = 0; i < std::size(kControllers); ++i)
    if (static_cast<std::size_t>(kControllers[i].type) != i) return false;
  return true;
}());

constexpr const ControllerInfo& controller_info(ControllerType t) {
  return kControllers[static_cast<std::size_t>(t)];
}
constexpr const char* to_string(ControllerType t) { return controller_info(t).name; }

constexpr const ControllerInfo* find_controller(std::string_view name) {
  for (const ControllerInfo& c : kControllers)
    if (name == c.name) return &c;
  return nullptr;
}
constexpr std::optional<ControllerType> controller_type_from_string(std::string_view name) {
  if (const ControllerInfo* c = find_controller(name)) return c->type;
  return std::nullopt;
}

// The names of all types, comma-separated ("nftsmc, fosmc, ..."), for messages and help.
inline std::string_view controller_type_list() {
  static const std::string list = [] {
    std::string s;
    for (const ControllerInfo& c : kControllers) s += (s.empty() ? "" : ", ") + std::string(c.name);
    return s;
  }();
  return list;
}

// Calls f(std::integral_constant<ControllerType, t>{}) and returns its result: a run-time type
// as a compile-time one.
template <std::size_t I = 0, class F>
decltype(auto) visit_controller_type(ControllerType t, F&& f) {
  constexpr ControllerType k = kAllControllerTypes[I];
  if constexpr (I + 1 == kAllControllerTypes.size()) {
    return std::forward<F>(f)(std::integral_constant<ControllerType, k>{});
  } else {
    if (t == k) return std::forward<F>(f)(std::integral_constant<ControllerType, k>{});
    return visit_controller_type<I + 1>(t, std::forward<F>(f));
  }
}

}  // namespace ftc::sim
