// The batch simulator's kernel for avx2 (sim_core/CMakeLists.txt compiles this file alone with
// its instruction set and FTC_ISA_NS=isa_avx2: see lanes/lane.hpp).
#include "lanes/spacecraft_kernel.hpp"

namespace ftc::sim::detail {

void pack_kernel_avx2(const PackSetup& setup, PackHost& host, PackFinal& final_state) {
  run_pack<xsimd::batch<double, xsimd::avx2>>(setup, host, final_state);
}

}  // namespace ftc::sim::detail
