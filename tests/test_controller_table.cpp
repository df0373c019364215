// The controller table (include/ftc/sim/controllers.hpp) and everything that reads it.
#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "ftc/runtime/controller_json.hpp"
#include "ftc/sim/controller_config.hpp"
#include "ftc/sim/controllers.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "report/gnuplot.hpp"

using namespace ftc;
using sim::ControllerInfo;
using sim::ControllerType;

TEST(ControllerTable, EveryControllerRoundTripsNameAndType) {
  std::set<std::string> names, displays;
  std::set<int> styles;
  ASSERT_EQ(std::size(sim::kControllers), sim::kAllControllerTypes.size());
  for (std::size_t i = 0; i < std::size(sim::kControllers); ++i) {
    const ControllerInfo& c = sim::kControllers[i];
    SCOPED_TRACE(c.name);
    EXPECT_EQ(sim::kAllControllerTypes[i], c.type);
    EXPECT_EQ(&sim::controller_info(c.type), &c);
    EXPECT_STREQ(sim::to_string(c.type), c.name);
    EXPECT_EQ(sim::controller_type_from_string(c.name), c.type);
    EXPECT_EQ(sim::find_controller(c.name), &c);
    EXPECT_EQ(tune::display_name(c.type), c.display_name);
    EXPECT_EQ(tune::plot::controller_style(c.name, false), c.plot_style);
    // A controller read from its name writes that name back.
    std::vector<FieldError> errs;
    const sim::ControllerConfig cfg =
        runtime::parse_controller(nlohmann::json{{"type", c.name}}, "/controller", errs);
    EXPECT_TRUE(errs.empty());
    EXPECT_EQ(cfg.type, c.type);
    EXPECT_EQ(runtime::to_json(cfg)["type"], c.name);
    EXPECT_TRUE(names.insert(c.name).second) << "name used twice";
    EXPECT_TRUE(displays.insert(c.display_name).second) << "display name used twice";
    EXPECT_TRUE(styles.insert(c.plot_style).second) << "line style used twice";
    EXPECT_NE(c.plot_style, 1) << "style 1 is the tuned controller's";
  }
  EXPECT_FALSE(sim::controller_type_from_string("PI-FOSMC"));
  EXPECT_FALSE(sim::controller_type_from_string(""));
  EXPECT_EQ(sim::find_controller("pid"), nullptr);
}

TEST(ControllerTable, TraitsMatchTheFieldsAndTheLaws) {
  for (const ControllerInfo& c : sim::kControllers) {
    SCOPED_TRACE(c.name);
    const std::vector<std::string> f = sim::controller_field_names(c.type);
    const auto has = [&](const char* n) { return std::find(f.begin(), f.end(), n) != f.end(); };
    EXPECT_EQ(has("Ki"), c.integral);
    EXPECT_EQ(has("Kp"), c.integral);
    EXPECT_EQ(has("centre_range"), c.adaptive);
    EXPECT_EQ(has("nodes"), c.adaptive);
    // A model-free law has nothing to learn f(X) with but its network.
    EXPECT_EQ(!c.model_based, c.adaptive);
  }
  // The batch simulator's lane packs and the runtime's classes reach a law through the table's
  // types; a type becomes a compile-time constant once.
  for (const ControllerType t : sim::kAllControllerTypes)
    EXPECT_EQ(sim::visit_controller_type(t, [](auto k) { return decltype(k)::value; }), t);
}

// The job file's JSON Schema (ftctune schema job) lists the table: one case per controller, in
// order, each described by its line.
TEST(ControllerTable, JobSchemaListsTheTable) {
  const nlohmann::json schema = tune::job_json_schema();
  const nlohmann::json& controller = schema.at("properties").at("controller");
  ASSERT_TRUE(controller.contains("oneOf")) << controller.dump(1).substr(0, 400);
  const nlohmann::json& cases = controller["oneOf"];
  ASSERT_EQ(cases.size(), std::size(sim::kControllers));
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const ControllerInfo& c = sim::kControllers[i];
    EXPECT_EQ(cases[i]["properties"]["type"]["const"], c.name);
    const std::string d = cases[i].value("description", "");
    EXPECT_NE(d.find(c.display_name), std::string::npos) << d;
    EXPECT_NE(d.find(c.description), std::string::npos) << d;
    EXPECT_EQ(d.find("integral state") != std::string::npos, c.integral) << d;
  }
  // An unknown type's message names every controller of the table.
  std::vector<FieldError> errs;
  runtime::parse_controller(nlohmann::json{{"type", "pi_fosmcc"}}, "/controller", errs);
  ASSERT_EQ(errs.size(), 1u);
  EXPECT_EQ(errs[0].path, "/controller/type");
  for (const ControllerInfo& c : sim::kControllers)
    EXPECT_NE(errs[0].message.find(c.name), std::string::npos) << errs[0].message;
  EXPECT_NE(errs[0].message.find("did you mean \"pi_fosmc\""), std::string::npos)
      << errs[0].message;
}
