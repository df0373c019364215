// Opens the pagmo2 adapter module the first time something asks for a pagmo algorithm (see
// optimizers/pagmo_plugin.hpp for why it is a module), and stands in for it in the registry until
// then: parsing a job of another algorithm, `ftctune --version` or `validate` never load it.
#include <dlfcn.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "ftc/sim/input_error.hpp"
#include "ftc/sim/loadable.hpp"
#include "ftc/tune/optimizers/hypervolume.hpp"
#include "ftc/tune/optimizers/pagmo.hpp"
#include "optimizers/pagmo_plugin.hpp"

namespace ftc::tune {

namespace {

namespace fs = std::filesystem;

// Where the module may be: $FTCTUNE_PLUGIN_DIR, beside an installed binary
// (<prefix>/<bindir>/../<libdir>/ftctune) or an installed Python module
// (<prefix>/<python dir>/ftctune/../../ftctune), and, for a binary inside the build tree, that
// tree.
std::vector<fs::path> candidates(const fs::path& image) {
  std::vector<fs::path> dirs;
  if (const char* env = std::getenv("FTCTUNE_PLUGIN_DIR"); env && *env) dirs.emplace_back(env);
  if (!image.empty()) {
    dirs.push_back(image.parent_path() / FTC_PLUGIN_DIR_FROM_BIN);
    if (const std::string py = FTC_PLUGIN_DIR_FROM_PYTHON; !py.empty())
      dirs.push_back(image.parent_path() / py);
    // The build tree only for a binary that lives in it: an installed copy must not pick up a
    // module of whatever the build tree holds today.
    const std::string tree = FTC_BUILD_TREE;
    if (image.string().rfind(tree + "/", 0) == 0) dirs.emplace_back(FTC_PLUGIN_BUILD_DIR);
  }
  std::vector<fs::path> files;
  for (const fs::path& d : dirs) files.push_back(d / pagmo_plugin::kModuleName);
  return files;
}

const pagmo_plugin::Api& api() {
  static const pagmo_plugin::Api* loaded = nullptr;
  static std::string failure;
  static std::once_flag once;
  std::call_once(once, [] {
    std::string tried;
    const fs::path image = sim::this_image();
    // The module takes the tuner's symbols from the global scope (ftc/sim/loadable.hpp).
    sim::share_symbols_with_modules();
    for (const fs::path& f : candidates(image)) {
      std::error_code ec;
      if (!fs::exists(f, ec)) {
        tried += (tried.empty() ? "" : ", ") + f.string();
        continue;
      }
      // Never closed: the settings and optimisers it makes live as long as the process.
      void* h = ::dlopen(f.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (!h) {
        tried += (tried.empty() ? "" : ", ") + f.string() + " (" + ::dlerror() + ")";
        continue;
      }
      using Entry = const pagmo_plugin::Api* (*)();
      const auto entry = reinterpret_cast<Entry>(::dlsym(h, pagmo_plugin::kEntryPoint));
      const pagmo_plugin::Api* a = entry ? entry() : nullptr;
      if (!a || std::string(a->build_id) != FTC_BUILD_ID) {
        tried += (tried.empty() ? "" : ", ") + f.string() + " (from another build of ftctune)";
        continue;
      }
      loaded = a;
      return;
    }
    failure = "the pagmo2 adapter " + std::string(pagmo_plugin::kModuleName) +
              " of this build was not found (tried " + tried +
              "); it is built and installed with ftctune, or point FTCTUNE_PLUGIN_DIR at it";
  });
  if (!loaded) throw InputError("tuning.algorithm", "", "pagmo: " + failure);
  return *loaded;
}

}  // namespace

const std::vector<PagmoAlgorithmInfo>& pagmo_algorithms() { return api().algorithms(); }

const PagmoAlgorithmInfo* find_pagmo_algorithm(const std::string& name) {
  for (const PagmoAlgorithmInfo& a : pagmo_algorithms())
    if (a.name == name) return &a;
  return nullptr;
}

double hypervolume(const std::vector<std::vector<double>>& points,
                   const std::vector<double>& reference) {
  std::vector<std::vector<double>> inside;
  for (const std::vector<double>& p : points) {
    if (p.size() != reference.size())
      throw std::invalid_argument("a point of " + std::to_string(p.size()) +
                                  " objectives against a reference point of " +
                                  std::to_string(reference.size()));
    bool strictly = true;
    for (std::size_t k = 0; k < p.size(); ++k)
      strictly = strictly && std::isfinite(p[k]) && p[k] < reference[k];
    if (strictly) inside.push_back(p);
  }
  if (inside.empty()) return 0.0;
  return api().hypervolume(inside, reference);
}

AlgorithmInfo pagmo_algorithm_info() {
  // Parsing and the schema go to the module; the entry itself costs nothing to register.
  AlgorithmInfo info;
  info.type = "pagmo";
  info.description =
      "a single-objective algorithm of pagmo2, chosen by `name` (see docs/optimizers.md)";
  info.parse = [](const nlohmann::json& j, const std::string& path,
                  std::vector<FieldError>& errors) { return api().info().parse(j, path, errors); };
  info.schema = [] { return api().info().schema(); };
  return info;
}

}  // namespace ftc::tune
