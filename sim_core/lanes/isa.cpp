#include "ftc/sim/isa.hpp"

#include <cstdlib>
#include <string>

#include "ftc/sim/input_error.hpp"

namespace ftc::sim {

const char* to_string(Isa isa) {
  switch (isa) {
    case Isa::scalar:
      return "scalar";
    case Isa::sse2:
      return "sse2";
    case Isa::avx2:
      return "avx2";
    case Isa::avx512:
      return "avx512";
  }
  return "?";
}

int lane_width(Isa isa) {
  switch (isa) {
    case Isa::scalar:
      return 1;
    case Isa::sse2:
      return 2;
    case Isa::avx2:
      return 4;
    case Isa::avx512:
      return 8;
  }
  return 1;
}

std::vector<Isa> supported_isas() {
  std::vector<Isa> v{Isa::scalar};
  // The vector kernels this build has (FTC_VECTOR_KERNELS) that the CPU can run. SSE2 is part of
  // x86-64. __builtin_cpu_supports also asks the OS whether it saves the AVX and AVX-512
  // registers (XGETBV).
#if defined(FTC_KERNEL_SSE2)
  v.push_back(Isa::sse2);
#endif
#if defined(FTC_KERNEL_AVX2) || defined(FTC_KERNEL_AVX512)
  __builtin_cpu_init();
#endif
#if defined(FTC_KERNEL_AVX2)
  if (__builtin_cpu_supports("avx2")) v.push_back(Isa::avx2);
#endif
#if defined(FTC_KERNEL_AVX512)
  if (__builtin_cpu_supports("avx512f")) v.push_back(Isa::avx512);
#endif
  return v;
}

namespace {

Isa choose() {
  const std::vector<Isa> supported = supported_isas();
  const char* env = std::getenv("FTCTUNE_ISA");
  if (env == nullptr || *env == '\0') return supported.back();
  const std::string name(env);
  std::string names;
  for (Isa isa : supported) {
    if (name == to_string(isa)) return isa;
    names += names.empty() ? "" : ", ";
    names += to_string(isa);
  }
  for (Isa isa : {Isa::scalar, Isa::sse2, Isa::avx2, Isa::avx512})
    if (name == to_string(isa))
      throw InputError(
          "FTCTUNE_ISA", "",
          "is \"" + name + "\", which this CPU or build cannot run (it can: " + names + ")");
  throw InputError(
      "FTCTUNE_ISA", "",
      "is \"" + name + "\"; expected one of scalar, sse2, avx2, avx512 (this CPU: " + names + ")");
}

}  // namespace

Isa active_isa() {
  static const Isa isa = choose();  // a throw leaves it unset, so every caller hears of it
  return isa;
}

}  // namespace ftc::sim
