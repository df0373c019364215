// The batch simulator's kernel for scalar (sim_core/CMakeLists.txt compiles this file alone with
// its instruction set and FTC_ISA_NS=isa_scalar: see lanes/lane.hpp).
#include "lanes/spacecraft_kernel.hpp"

namespace ftc::sim::detail {

void pack_kernel_scalar(const PackSetup& setup, PackHost& host, PackFinal& final_state) {
  run_pack<double>(setup, host, final_state);
}

}  // namespace ftc::sim::detail
