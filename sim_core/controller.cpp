#include "ftc/sim/controller.hpp"

#include "checks.hpp"
#include "ftc/sim/adaptive_neural_pi_fosmc.hpp"
#include "ftc/sim/fosmc.hpp"
#include "ftc/sim/nftsmc.hpp"
#include "ftc/sim/pi_fosmc.hpp"

namespace ftc::sim {
namespace detail {

// Shared by every controller constructor: validated copy with α1 resolved.
ControllerConfig checked_config(const ControllerConfig& config, double sample_time) {
  std::vector<FieldError> errs = config.validate("");
  for (FieldError& e : errs) e.path = e.path.substr(1);  // field names, not JSON paths
  if (!(sample_time > 0.0) || !std::isfinite(sample_time))
    errs.push_back({"sample_time", "must be > 0 (got " + fmt_num(sample_time) + ")"});
  throw_if_errors(std::string("controller ") + to_string(config.type), std::move(errs));
  ControllerConfig c = config;
  c.alpha1 = config.resolved_alpha1();
  return c;
}

}  // namespace detail

std::unique_ptr<Controller> make_controller(const ControllerConfig& config, const Plant& plant,
                                            double sample_time) {
  switch (config.type) {
    case ControllerType::nftsmc:
      return std::make_unique<Nftsmc>(config, plant, sample_time);
    case ControllerType::fosmc:
      return std::make_unique<Fosmc>(config, plant, sample_time);
    case ControllerType::pi_fosmc:
      return std::make_unique<PiFosmc>(config, plant, sample_time);
    case ControllerType::adaptive_neural_pi_fosmc:
      return std::make_unique<AdaptiveNeuralPiFosmc>(config, plant, sample_time);
  }
  throw InputError("controller", "type", "unknown controller type");
}

}  // namespace ftc::sim
