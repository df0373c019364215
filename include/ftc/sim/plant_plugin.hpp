#pragma once
// Plant plugins: a plant built outside the tree (docs/plugins.md) as a shared library,
// ftctune_plant_<NAME>.so, that a job names as "plugin:<NAME>". The library is compiled with
// CMake's ftctune_add_plant() from the installed package, from the same lane code a shipped plant
// has, once per instruction set; it brings its PlantKind (n, m, parameters, uncertain parameters,
// trim) and its kernels, and takes everything else (the scenario's checks, the metrics' read-back,
// the elementary functions) from the process that loads it, so a plugin plant runs the very loop a
// compiled-in one runs, to the last bit.
//
// The library and ftctune share C++ types (PlantKind, AnyPlant, Scenario, ...), so a plugin is
// only loaded by an ftctune built from the same headers with the same compiler: its entry point
// gives an ABI version and an ID (kPlantAbiVersion, plant_abi_id()) that must both match.
//
// Where plugins come from: a job's "plugin:NAME" is looked up on the plant search path (the
// directories of --plant-path, then those of the environment variable FTCTUNE_PLANT_PATH, ':'
// between them) the first time it is named. A process that must not load what a job names (the
// HTTP service) loads its plugins at start with load_plant_plugin() and then calls
// lock_plant_plugins(): from then on a job naming any other plugin is refused.
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "ftc/sim/plants.hpp"

namespace ftc::sim {

// Bumped whenever what crosses the boundary changes in a way the header hash cannot see.
inline constexpr std::uint32_t kPlantAbiVersion = 1;
// The prefix of a plugin plant's model name in a job: "plugin:" NAME.
inline constexpr std::string_view kPluginPrefix = "plugin:";

// What a plugin's entry point (extern "C" ftctune_plant_plugin, defined by FTCTUNE_PLANT_PLUGIN in
// plants/plugin_entry.hpp) returns. The two leading fields are plain C, read before anything else.
struct PlantPluginApi {
  std::uint32_t abi_version;  // kPlantAbiVersion of the SDK it was built with
  const char* abi_id;         // plant_abi_id() of the SDK it was built with
  // The plugin's description; its model is "plugin:" + its name.
  PlantKind (*kind)();
  // For `ftctune plant check`: the plant built from `values` (validated), evaluated at the state
  // x (2n values): f(X) (n), G(X) (n×m, row-major), its G⁺(X) (m×n, row-major). False when the
  // plant refuses the values (`error` then says why).
  bool (*evaluate)(const std::vector<double>& values, const double* x, double* f, double* G,
                   double* G_pinv, std::string* error);
  // Its actuators' operating point u0 and the range of their deviation [lo, hi] (m each); false
  // for a plant without one.
  bool (*trim)(const std::vector<double>& values, double* u0, double* lo, double* hi);
};

inline constexpr const char* kPlantPluginEntry = "ftctune_plant_plugin";

// The ID of this build's plant ABI: ftctune's version, the compiler and a hash of the headers a
// plugin is compiled against.
const char* plant_abi_id();

// A loaded plugin.
struct PlantPlugin {
  std::string name;            // NAME of "plugin:NAME"
  std::filesystem::path file;  // the library, canonical (empty for a registered kind)
  std::string digest;          // of the library's bytes when loaded (MPI ranks compare it)
  const PlantKind* kind = nullptr;
  const PlantPluginApi* api = nullptr;
};

// The file name of plugin NAME: ftctune_plant_NAME.so.
std::string plant_plugin_file_name(std::string_view name);

// Loads the library at `file` (once; a second call returns the first load). Throws InputError
// (source "plugin") naming the file for a library that cannot be opened, has no entry point, was
// built for another ABI, names itself differently from its file, or whose kind() throws or is
// inconsistent. Never unloads: the plants it makes live as long as the process.
const PlantPlugin& load_plant_plugin(const std::filesystem::path& file);

// The plugin a job's model names ("plugin:NAME"): loaded already, or found on the search path and
// loaded when loading by name is allowed. Throws InputError (source "plant", path "/model") saying
// where it looked, or that this process only runs the plugins it was started with.
const PlantPlugin& find_plant_plugin(std::string_view model);

// Loads every ftctune_plant_*.so in the search path's directories (in name order; the first of a
// name wins), for what lists the plants a job can name (`ftctune schema job`). Throws as
// load_plant_plugin does.
std::vector<const PlantPlugin*> load_plant_plugins_on_search_path();

// The directories --plant-path gave (searched before FTCTUNE_PLANT_PATH's).
void set_plant_search_path(std::vector<std::filesystem::path> dirs);
// --plant-path's then FTCTUNE_PLANT_PATH's directories, in search order.
std::vector<std::filesystem::path> plant_search_path();

// From now on no library is loaded by name: a job may only name plugins loaded already. (The
// program itself may still call load_plant_plugin: what it loads is its operator's choice, never a
// job's.)
void lock_plant_plugins();
bool plant_plugins_locked();

// The plugins loaded so far, in load order.
std::vector<const PlantPlugin*> loaded_plant_plugins();

// Adds a kind compiled into the program under a plugin's name (tests compare a plugin with the
// same plant compiled in); a job naming it then needs no library. Throws std::logic_error for a
// name already taken.
void register_plant_kind(PlantKind kind);

// Counts the kinds added since start (plugins and registered kinds): a cache of something built
// from plant kinds (the job schema) rebuilds when it changes.
std::uint64_t plant_kinds_generation();

// Every kind a job can name now: the shipped ones, then the registered and loaded ones.
std::vector<const PlantKind*> all_plant_kinds();

}  // namespace ftc::sim
