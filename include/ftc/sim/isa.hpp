#pragma once
// The instruction set the batch simulator runs its SIMD lanes on. One binary serves any x86-64
// CPU: the kernels are compiled for SSE2 (2 lanes of doubles), AVX2 (4) and AVX-512 (8) beside
// the scalar one (1), and the widest the CPU has is chosen at start-up, unless the environment
// variable FTCTUNE_ISA names another (scalar, sse2, avx2, avx512). That is the widest used:
// packs of fewer lanes run on the narrowest instruction set that holds them, which is cheaper.
// On other CPUs (aarch64) only the scalar kernel exists. Every choice gives the same results to
// the last bit: the lanes run the scalar code's operations (docs/architecture.md).
#include <string>
#include <vector>

namespace ftc::sim {

enum class Isa { scalar, sse2, avx2, avx512 };

const char* to_string(Isa isa);
// Doubles per SIMD register: 1, 2, 4, 8.
int lane_width(Isa isa);
// The instruction sets this build has kernels for and this CPU can run, narrowest first.
std::vector<Isa> supported_isas();
// The one in use: FTCTUNE_ISA when set, otherwise the last of supported_isas(). Throws
// InputError (source "FTCTUNE_ISA") for an unknown name or one this CPU cannot run; read once.
Isa active_isa();

}  // namespace ftc::sim
