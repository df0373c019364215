// Plant plugins that fail in the ways the loader must report cleanly (tests/test_plant_plugin.cpp):
// one per FTC_BROKEN_* definition, each built as ftctune_plant_<name>.so by tests/CMakeLists.txt.
#include <stdexcept>
#include <string>
#include <vector>

#include "ftc/sim/plant_plugin.hpp"

namespace {

using ftc::sim::PlantKind;

[[maybe_unused]] PlantKind kind() {
#if defined(FTC_BROKEN_THROWS)
  throw std::runtime_error("this plant's parameters file is missing");
#else
  PlantKind k;
  k.model = "plugin:someone_else";  // FTC_BROKEN_MISNAMED: not its file's name
  k.axes = 1;
  k.actuators = 2;
  k.default_initial_state = {0.0, 0.0};
  return k;
#endif
}

[[maybe_unused]] bool evaluate(const std::vector<double>&, const double*, double*, double*, double*,
                               std::string*) {
  return false;
}
[[maybe_unused]] bool trim(const std::vector<double>&, double*, double*, double*) { return false; }

}  // namespace

#if !defined(FTC_BROKEN_NO_ENTRY)
extern "C" __attribute__((visibility("default"))) const ftc::sim::PlantPluginApi*
ftctune_plant_plugin() {
#if defined(FTC_BROKEN_WRONG_ABI)
  // As a plugin built against another ftctune would say.
  static const ftc::sim::PlantPluginApi api = {ftc::sim::kPlantAbiVersion + 1,
                                               "0.0.9-0123456789abcdef", &kind, &evaluate, &trim};
#else
  static const ftc::sim::PlantPluginApi api = {ftc::sim::kPlantAbiVersion, FTC_PLANT_ABI_ID, &kind,
                                               &evaluate, &trim};
#endif
  return &api;
}
#else
extern "C" __attribute__((visibility("default"))) int ftctune_plant_plugin_v0() { return 0; }
#endif
