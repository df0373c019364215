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


}  // namespace ftc::tune::job_detail
