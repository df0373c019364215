// make_controller for each shape of the registered plants (sim_core/plants/registry.cpp). The
// controllers are compiled here and nowhere else, so that no translation unit holding the loop
// sees their classes (see plants/plant_adapter.hpp for why that matters).
#include "controllers/factory.hpp"

namespace ftc::sim {

template std::unique_ptr<Controller<3, 4>> make_controller<3, 4>(const ControllerConfig&,
                                                                 const Plant<3, 4>&, double);
template std::unique_ptr<Controller<2, 3>> make_controller<2, 3>(const ControllerConfig&,
                                                                 const Plant<2, 3>&, double);
template std::unique_ptr<Controller<3, 6>> make_controller<3, 6>(const ControllerConfig&,
                                                                 const Plant<3, 6>&, double);
template std::unique_ptr<Controller<3, 8>> make_controller<3, 8>(const ControllerConfig&,
                                                                 const Plant<3, 8>&, double);

}  // namespace ftc::sim
