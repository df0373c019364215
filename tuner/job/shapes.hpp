#pragma once
// Shapes of the job file shared between the files of tuner/job. Private to tuner/.
#include <memory>

#include <string>
#include <vector>

#include "ftc/runtime/schema.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/tune/job/ensemble.hpp"

namespace ftc::tune::job_detail {

std::shared_ptr<const schema::Shape<EnsembleConfig>> ensemble_shape();

// The uncertain parameters of the registered plants (sim::PlantKind::uncertain), each once in
// registry order: the scenario keys of model mismatch's true values and, with "_scale", the
// ensemble's keys. A job may use only its own plant's (checked against the plant).
struct UncertainKey {
  std::string parameter;
  std::string models;                      // the plants that declare it: "spacecraft, hexarotor"
  std::string meaning;                     // the first declaring plant's words
  const sim::PlantParameter* declared{};  // the first declaring plant's parameter (unit, range)
};
const std::vector<UncertainKey>& uncertain_keys();

}  // namespace ftc::tune::job_detail
