#!/usr/bin/env bash
# The SIMD kernels (<build>/sim_core/kernels/ftc_sim_kernels/<plant>_lanes_<isa>.cpp, and a plant
# plugin's <build>/.../kernels/<target>/<lanes>_<isa>.cpp) are compiled for their own instruction
# set. Any inline function they instantiate outside their own namespace would be a weak symbol that
# the linker may pick for the whole program, and an AVX-512 copy of it would crash the scalar code
# on a CPU without AVX-512. So every weak (or unique) symbol a kernel object defines must lie in its
# namespace isa_<isa> (lanes/lane.hpp). Arguments: object files (the others are ignored).
set -euo pipefail
checked=0
status=0
for obj in "$@"; do
  base=$(basename "$obj")
  case "$base" in
    *_sse2.cpp.o | *_avx2.cpp.o | *_avx512.cpp.o) ;;
    *) continue ;;
  esac
  isa=${base%.cpp.o}
  isa=${isa##*_}
  checked=$((checked + 1))
  # Weak (W, V, w, v) and unique global (u) definitions, less the exception-handling reference
  # every C++ object has.
  stray=$(nm -C --defined-only "$obj" | awk '$2 ~ /^[WVwvu]$/' |
    grep -v "DW.ref.__gxx_personality_v0" | grep -v "isa_${isa}::" || true)
  if [ -n "$stray" ]; then
    echo "$base defines weak symbols outside namespace isa_${isa}:" >&2
    echo "$stray" | head -20 >&2
    status=1
  fi
done
if [ "$checked" -eq 0 ]; then
  echo "no kernel objects among the arguments" >&2
  exit 1
fi
echo "checked $checked kernel objects"
exit $status
