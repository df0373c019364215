// Plant plugins: opening a library, checking it, and the kinds it adds (ftc/sim/plant_plugin.hpp).
#include <dlfcn.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <fstream>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <system_error>

#include "ftc/sim/input_error.hpp"
#include "ftc/sim/loadable.hpp"
#include "ftc/sim/plant_plugin.hpp"
#include "lanes/pack.hpp"
#include "plant_abi.hpp"

namespace ftc::sim {

namespace fs = std::filesystem;

namespace {

struct Registry {
  std::mutex mutex;
  // Stable addresses: jobs, schemas and plants keep pointers to the kinds.
  std::deque<std::unique_ptr<PlantPlugin>> plugins;
  std::deque<std::unique_ptr<PlantKind>> kinds;
  std::vector<fs::path> dirs;  // --plant-path
  bool locked = false;
  std::atomic<std::uint64_t> generation{0};
};

Registry& registry() {
  static Registry r;
  return r;
}

std::string name_of(std::string_view model) {
  return std::string(model.substr(kPluginPrefix.size()));
}

// The loaded plugin or registered kind named `name`; the caller holds the mutex.
const PlantPlugin* loaded(Registry& r, std::string_view name) {
  for (const auto& p : r.plugins)
    if (p->name == name) return p.get();
  return nullptr;
}

// A plugin name: letters, digits and '_' (it is part of a file name and of a model name).
bool valid_name(std::string_view name) {
  if (name.empty()) return false;
  for (const char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
  return true;
}

// Checks what a plugin's kind() returned against what the loop and the job files assume.
void check_kind(const PlantKind& k, const std::string& expected_model, const std::string& where) {
  const auto fail = [&](const std::string& what) {
    throw InputError("plugin", "", where + ": " + what);
  };
  if (k.model != expected_model)
    fail("its plant calls itself '" + k.model + "', but its file name makes it '" + expected_model +
         "' (a plugin NAME is built as ftctune_plant_NAME.so and names its "
         "model \"plugin:NAME\")");
  if (k.axes < 1 || k.actuators < k.axes || k.actuators > kMaxActuators)
    fail("declares n = " + std::to_string(k.axes) + " axes and m = " + std::to_string(k.actuators) +
         " actuators (a plant needs 1 ≤ n ≤ m ≤ " + std::to_string(kMaxActuators) + ")");
  if (!k.make) fail("its kind has no make() (FTCTUNE_PLANT_PLUGIN sets it)");
  if (k.default_initial_state.size() != static_cast<std::size_t>(2 * k.axes))
    fail("its default initial state has " + std::to_string(k.default_initial_state.size()) +
         " values; a plant of n = " + std::to_string(k.axes) + " needs " +
         std::to_string(2 * k.axes));
  if (!k.axis_names.empty() && k.axis_names.size() != static_cast<std::size_t>(k.axes))
    fail("names " + std::to_string(k.axis_names.size()) + " axes; it has " +
         std::to_string(k.axes));
  for (const PlantParameter& p : k.parameters) {
    if (p.name.empty() || p.defaults.empty()) fail("has a parameter without a name or a default");
    for (const double v : p.defaults)
      if (std::string msg = p.range.check(v); !msg.empty())
        fail("the default of its parameter " + p.name + " is out of its own range: " + msg);
  }
  for (const UncertainParameter& u : k.uncertain)
    if (k.offset(u.parameter) == std::string_view::npos)
      fail("declares '" + u.parameter + "' uncertain but has no parameter of that name");
}

}  // namespace

// FNV-1a, 64 bits, of the library's bytes as loaded: what MPI ranks compare (another build of
// the same name is another digest; nothing here is adversarial: the ranks are the operator's).
std::string digest_of(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError("plugin", "", file.string() + ": cannot be read");
  std::uint64_t h = 0xcbf29ce484222325ULL;
  char buf[65536];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    for (std::streamsize i = 0; i < in.gcount(); ++i) {
      h ^= static_cast<unsigned char>(buf[i]);
      h *= 0x100000001b3ULL;
    }
    if (!in) break;
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

std::string plant_plugin_file_name(std::string_view name) {
  return "ftctune_plant_" + std::string(name) + ".so";
}

const PlantPlugin& load_plant_plugin(const fs::path& file) {
  Registry& r = registry();
  // One load at a time; the registry's own mutex is not held while the library's code runs (its
  // static initialisers, entry point and kind() may look plants up).
  static std::mutex loading;
  std::lock_guard load_lock(loading);
  std::error_code ec;
  const fs::path canonical = fs::canonical(file, ec);
  if (ec) throw InputError("plugin", "", file.string() + ": no such file");
  const std::string where = canonical.string();
  const std::string stem = canonical.filename().string();
  const std::string prefix = "ftctune_plant_", suffix = ".so";
  const bool named = stem.size() > prefix.size() + suffix.size() && stem.rfind(prefix, 0) == 0 &&
                     stem.compare(stem.size() - suffix.size(), suffix.size(), suffix) == 0;
  const std::string name =
      named ? stem.substr(prefix.size(), stem.size() - prefix.size() - suffix.size()) : "";
  if (!named || !valid_name(name))
    throw InputError("plugin", "",
                     where +
                         ": a plant plugin's file is named ftctune_plant_NAME.so, NAME of "
                         "letters, digits and _ (ftctune_add_plant(NAME ...) builds it so)");
  {
    std::lock_guard lock(r.mutex);
    for (const auto& p : r.plugins)
      if (p->file == canonical) return *p;
    if (const PlantPlugin* other = loaded(r, name))
      throw InputError(
          "plugin", "",
          where + ": a plant named plugin:" + name + " is loaded already (from " +
              (other->file.empty() ? std::string("this program") : other->file.string()) + ")");
  }
  const std::string digest = digest_of(canonical);
  share_symbols_with_modules();
  // Never closed: the plants it makes live as long as the process.
  void* h = ::dlopen(canonical.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!h) {
    const char* why = ::dlerror();
    throw InputError("plugin", "",
                     where + ": cannot be loaded (" + (why ? why : "unknown reason") +
                         "); was it built with ftctune_add_plant against this ftctune?");
  }
  using Entry = const PlantPluginApi* (*)();
  const auto entry = reinterpret_cast<Entry>(::dlsym(h, kPlantPluginEntry));
  if (!entry)
    throw InputError("plugin", "",
                     where + ": has no entry point " + kPlantPluginEntry +
                         " (a plant plugin ends its plant's source with FTCTUNE_PLANT_PLUGIN)");
  const PlantPluginApi* api = nullptr;
  try {
    api = entry();
  } catch (const std::exception& e) {
    throw InputError("plugin", "", where + ": its entry point threw: " + e.what());
  } catch (...) {
    throw InputError("plugin", "", where + ": its entry point threw");
  }
  if (!api) throw InputError("plugin", "", where + ": its entry point returned nothing");
  if (api->abi_version != kPlantAbiVersion || !api->abi_id ||
      std::string(api->abi_id) != plant_abi_id())
    throw InputError(
        "plugin", "",
        where + ": was built for plant ABI " + std::to_string(api->abi_version) + " (" +
            (api->abi_id ? api->abi_id : "no ID") + "), but this ftctune has ABI " +
            std::to_string(kPlantAbiVersion) + " (" + plant_abi_id() +
            "); rebuild it with ftctune_add_plant against this ftctune's installed package");
  if (!api->kind || !api->evaluate || !api->trim)
    throw InputError("plugin", "", where + ": its entry point gives an incomplete interface");
  auto kind = std::make_unique<PlantKind>();
  try {
    *kind = api->kind();
  } catch (const std::exception& e) {
    throw InputError("plugin", "", where + ": its kind() threw: " + e.what());
  } catch (...) {
    throw InputError("plugin", "", where + ": its kind() threw");
  }
  check_kind(*kind, std::string(kPluginPrefix) + name, where);
  auto plugin = std::make_unique<PlantPlugin>();
  plugin->name = name;
  plugin->file = canonical;
  plugin->digest = digest;
  plugin->kind = kind.get();
  plugin->api = api;
  std::lock_guard lock(r.mutex);
  r.kinds.push_back(std::move(kind));
  r.plugins.push_back(std::move(plugin));
  ++r.generation;
  return *r.plugins.back();
}

const PlantPlugin& find_plant_plugin(std::string_view model) {
  const std::string name = name_of(model);
  if (!valid_name(name))
    throw InputError("plant", "/model",
                     "'" + std::string(model) +
                         "' is no plugin name (plugin:NAME, NAME of letters, digits and _)");
  fs::path found;
  std::string tried;
  {
    Registry& r = registry();
    std::lock_guard lock(r.mutex);
    if (const PlantPlugin* p = loaded(r, name)) return *p;
    if (r.locked) {
      std::string names;
      for (const auto& p : r.plugins)
        names += (names.empty() ? "" : ", ") + std::string(kPluginPrefix) + p->name;
      throw InputError(
          "plant", "/model",
          "plugin:" + name + " is not one of the plugins this server was started with (" +
              (names.empty() ? std::string("none") : names) +
              "); a job cannot make it load a library: start it with serve --plugin LIB");
    }
  }
  const std::string file = plant_plugin_file_name(name);
  for (const fs::path& d : plant_search_path()) {
    std::error_code ec;
    if (fs::is_regular_file(d / file, ec)) {
      found = d / file;
      break;
    }
    tried += (tried.empty() ? "" : ", ") + d.string();
  }
  if (found.empty())
    throw InputError("plant", "/model",
                     "plugin:" + name + ": " + file + " is not on the plant search path (" +
                         (tried.empty() ? std::string("empty") : "searched " + tried) +
                         "); give its directory with --plant-path DIR or FTCTUNE_PLANT_PATH");
  try {
    return load_plant_plugin(found);
  } catch (const InputError& e) {
    throw InputError("plant", "/model", e.errors().front().message);
  }
}

std::vector<const PlantPlugin*> load_plant_plugins_on_search_path() {
  std::vector<const PlantPlugin*> out;
  std::vector<std::string> names;
  for (const fs::path& d : plant_search_path()) {
    std::error_code ec;
    std::vector<fs::path> files;
    for (const fs::directory_entry& e : fs::directory_iterator(d, ec)) {
      const std::string f = e.path().filename().string();
      if (f.rfind("ftctune_plant_", 0) == 0 && f.size() > 3 && f.ends_with(".so"))
        files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    for (const fs::path& f : files) {
      const std::string name = f.filename().string();
      if (std::find(names.begin(), names.end(), name) != names.end()) continue;
      names.push_back(name);
      out.push_back(&load_plant_plugin(f));
    }
  }
  return out;
}

void set_plant_search_path(std::vector<fs::path> dirs) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  r.dirs = std::move(dirs);
}

std::vector<fs::path> plant_search_path() {
  std::vector<fs::path> dirs;
  {
    Registry& r = registry();
    std::lock_guard lock(r.mutex);
    dirs = r.dirs;
  }
  if (const char* env = std::getenv("FTCTUNE_PLANT_PATH"); env && *env) {
    std::string_view s(env);
    while (!s.empty()) {
      const std::size_t colon = s.find(':');
      const std::string_view d = s.substr(0, colon);
      if (!d.empty()) dirs.emplace_back(d);
      if (colon == std::string_view::npos) break;
      s.remove_prefix(colon + 1);
    }
  }
  return dirs;
}

void lock_plant_plugins() {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  r.locked = true;
}

bool plant_plugins_locked() {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  return r.locked;
}

std::vector<const PlantPlugin*> loaded_plant_plugins() {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  std::vector<const PlantPlugin*> out;
  for (const auto& p : r.plugins)
    if (!p->file.empty()) out.push_back(p.get());
  return out;
}

void register_plant_kind(PlantKind kind) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  if (kind.model.rfind(kPluginPrefix, 0) != 0)
    throw std::logic_error("register_plant_kind: " + kind.model + " is not a plugin:NAME");
  const std::string name = name_of(kind.model);
  if (loaded(r, name)) throw std::logic_error("register_plant_kind: " + kind.model + " is taken");
  auto k = std::make_unique<PlantKind>(std::move(kind));
  auto plugin = std::make_unique<PlantPlugin>();
  plugin->name = name;
  plugin->digest = "compiled in";
  plugin->kind = k.get();
  r.kinds.push_back(std::move(k));
  r.plugins.push_back(std::move(plugin));
  ++r.generation;
}

std::uint64_t plant_kinds_generation() { return registry().generation.load(); }

std::vector<const PlantKind*> all_plant_kinds() {
  std::vector<const PlantKind*> out;
  for (const PlantKind& k : plant_kinds()) out.push_back(&k);
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  for (const auto& p : r.plugins) out.push_back(p->kind);
  return out;
}

const char* plant_abi_id() { return FTC_PLANT_ABI_ID_OF_THIS_BUILD; }

// ---- loadable.hpp

fs::path this_image() {
  Dl_info info{};
  if (::dladdr(reinterpret_cast<const void*>(&this_image), &info) == 0 || !info.dli_fname)
    return {};
  std::error_code ec;
  fs::path p = fs::canonical(info.dli_fname, ec);
  if (ec) {
    // dladdr names the main program by argv[0], which may be relative to a changed directory.
    p = fs::read_symlink("/proc/self/exe", ec);
    if (ec) return {};
  }
  return p;
}

void share_symbols_with_modules() {
  static std::once_flag once;
  std::call_once(once, [] {
    const fs::path image = this_image();
    std::error_code ec;
    if (!image.empty() && image != fs::read_symlink("/proc/self/exe", ec))
      ::dlopen(image.c_str(), RTLD_NOW | RTLD_NOLOAD | RTLD_GLOBAL);
  });
}

}  // namespace ftc::sim
