// ftctune schema job|gains: the JSON Schema of a file format, generated from the description
// the loaders read with, for editors and CI checks of job files.
#include <cstdio>
#include <nlohmann/json.hpp>

#include "cli.hpp"
#include "ftc/runtime/gains.hpp"
#include "ftc/sim/plant_plugin.hpp"
#include "ftc/tune/job/job.hpp"

namespace ftc::cli {

void add_schema_command(CLI::App& app, const Globals&, Action& action) {
  auto which = std::make_shared<std::string>();
  CLI::App* sub = app.add_subcommand(
      "schema", "Print the JSON Schema (draft 2020-12) of the job or the gains file format");
  sub->add_option("format", *which, "job or gains")
      ->required()
      ->check(CLI::IsMember({"job", "gains"}));
  sub->footer(
      "Examples:\n  ftctune schema job > job.schema.json\n"
      "  python3 -m jsonschema -i jobs/table1.json job.schema.json   (python3-jsonschema)\n"
      "  ftctune schema job --plant-path build/tests/plugins   (with the plugins there)");
  sub->callback([&action, which] {
    action = [which] {
      // The plugins on the plant search path (--plant-path, FTCTUNE_PLANT_PATH) are plants too.
      if (*which == "job") sim::load_plant_plugins_on_search_path();
      const nlohmann::json s =
          *which == "job" ? tune::job_json_schema() : runtime::gains_json_schema();
      std::printf("%s\n", s.dump(2).c_str());
      return 0;
    };
  });
}

}  // namespace ftc::cli
