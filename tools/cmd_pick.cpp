// ftctune pick RUN --rule knee|min:METRIC|limit:METRIC<=X|index:N [--out FILE]: another gains
// file from the Pareto front of a run with two or more soft goals, without re-running
// (run/front.hpp's pick_gains).
#include <cstdio>
#include <nlohmann/json.hpp>

#include "cli.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/run/front.hpp"

namespace ftc::cli {

void add_pick_command(CLI::App& app, const Globals& g, Action& action) {
  struct Options {
    std::string run, rule = "knee", out;
  };
  auto o = std::make_shared<Options>();
  CLI::App* sub = app.add_subcommand(
      "pick", "Write the gains file of another point of a run's Pareto front (front.json)");
  sub->add_option("run", o->run,
                  "the run directory (out/<job>/...), or the output of evaluate --front")
      ->required()
      ->check(CLI::ExistingDirectory);
  sub->add_option("--rule", o->rule,
                  "knee | min:METRIC | limit:METRIC<=X (the least first other soft goal among "
                  "the points within the limit) | index:N")
      ->capture_default_str();
  sub->add_option("--out", o->out, "the gains file to write (default: standard output)")
      ->check(output_file());
  sub->footer("Example:\n  ftctune pick out/post-fault-pareto/latest --rule limit:control_tv<=500 "
              "--out tv500.json");
  sub->callback([&action, &g, o] {
    action = [o, &g] {
      const nlohmann::json gains = tune::pick_gains(o->run, o->rule);
      // On a held-out front: each soft goal on which the point does not hold out of sample.
      const nlohmann::json* held = nullptr;
      if (gains["goals"]["front"].contains("held_out")) held = &gains["goals"]["front"]["held_out"];
      if (held && !g.quiet)
        for (const nlohmann::json& w : (*held)["warnings"])
          std::fprintf(stderr, "[warning] %s\n", w.get<std::string>().c_str());
      // A point a compared controller (the job's own gains, a compare entry) dominates.
      if (gains["goals"]["front"].contains("dominated_by") && !g.quiet)
        for (const nlohmann::json& w : gains["warnings"])
          if (tune::is_dominated_warning(w.get<std::string>()))
            std::fprintf(stderr, "[warning] %s\n", w.get<std::string>().c_str());
      const std::string text = gains.dump(2) + "\n";
      if (o->out.empty()) {
        std::fputs(text.c_str(), stdout);
      } else {
        tune::write_file_atomic(o->out, text);
        if (!g.quiet)
          std::fprintf(stderr, "wrote %s (point %s of the front)\n", o->out.c_str(),
                       gains["goals"]["front"]["index"].dump().c_str());
      }
      return 0;
    };
  });
}

}  // namespace ftc::cli
