// ftctune plant check LIB [--against model.py]: what a plant plugin must satisfy before anyone
// tunes with it (api/plant_check.hpp), one line per check; exit 2 when one fails.
#include <cstdio>
#include <nlohmann/json.hpp>

#include "cli.hpp"
#include "ftc/tune/api/plant_check.hpp"

namespace ftc::cli {

void add_plant_command(CLI::App& app, const Globals&, Action& action) {
  struct Options {
    std::string library;
    tune::PlantCheckOptions check;
    bool json = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* plant = app.add_subcommand("plant", "Work with plant plugins (docs/plugins.md)");
  plant->require_subcommand(1);
  CLI::App* sub = plant->add_subcommand(
      "check",
      "Check a plant plugin before tuning with it: G G⁺ = I, finite and deterministic "
      "f and G, lanes equal to one lane on every instruction set, the trim, and "
      "optionally f and G against a Python model");
  sub->add_option("library", o->library, "the plugin (ftctune_plant_NAME.so)")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--against", o->check.against,
                  "a Python file defining f(x, p) and G(x, p) (x: the 2n state values, p: the "
                  "parameters by name) to compare with at the random states")
      ->check(CLI::ExistingFile);
  sub->add_option("--tolerance", o->check.tolerance,
                  "largest relative difference from the Python model")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  sub->add_option("--python", o->check.python, "the interpreter for --against")
      ->capture_default_str();
  sub->add_option("--states", o->check.states, "random states to check at")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  sub->add_option("--seed", o->check.seed, "seed of the random states")->capture_default_str();
  sub->add_flag("--json", o->json, "print the report as JSON");
  sub->callback([&action, o] {
    action = [o] {
      const tune::PlantCheckReport r = tune::check_plant_plugin(o->library, o->check);
      int failed = 0;
      for (const tune::PlantCheckItem& i : r.items) failed += i.passed ? 0 : 1;
      if (o->json) {
        nlohmann::json items = nlohmann::json::array();
        for (const tune::PlantCheckItem& i : r.items)
          items.push_back({{"check", i.name}, {"passed", i.passed}, {"detail", i.detail}});
        const nlohmann::json j = {{"model", r.model},     {"file", r.file},
                                  {"axes", r.axes},       {"actuators", r.actuators},
                                  {"passed", r.passed()}, {"checks", items}};
        std::printf("%s\n", j.dump(2).c_str());
      } else {
        std::printf("%s (n = %d, m = %d) from %s\n", r.model.c_str(), r.axes, r.actuators,
                    r.file.c_str());
        for (const tune::PlantCheckItem& i : r.items)
          std::printf("  %-4s %s: %s\n", i.passed ? "ok" : "FAIL", i.name.c_str(),
                      i.detail.c_str());
      }
      if (failed == 0) return 0;
      std::fflush(stdout);
      std::fprintf(stderr, "ftctune: error: %s fails %d of %zu checks\n", r.model.c_str(), failed,
                   r.items.size());
      return 2;
    };
  });
}

}  // namespace ftc::cli
