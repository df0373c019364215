# Sourced by tools/test --sanitize and tools/fuzz: the one sanitizer build both use, so that the
# project is compiled with the sanitizers once, not twice, when both are run.
#
# build-asan/ is a clang build with AddressSanitizer, UndefinedBehaviorSanitizer (every report
# fatal) and libFuzzer's coverage instrumentation (FTC_FUZZ=ON), at -O1 with line tables only
# (-g1: enough for the reports' stack traces, and faster to compile than -g). It holds the whole
# test suite and the fuzz targets. Left out: the benchmarks, and the SSE2 and AVX-512 kernel
# copies (FTC_VECTOR_KERNELS in sim_core/CMakeLists.txt): AVX2 beside scalar covers the lane
# code, and the two others took a sixth of its compile time (680 of 4 360 CPU seconds). clang
# rather than GCC because it compiled this build in about 9 minutes on 2 cores where GCC took
# about 15 (when it was smaller), and libFuzzer needs clang anyway.
#
#   sanitizer_build ROOT [TARGET...]   configures build-asan/ when needed, then builds TARGETs
#                                      (all when none); prints the build log on failure

sanitizer_build() {
  local root=$1
  shift
  local build="$root/build-asan"
  local log="$build/build.log"
  "$root/tools/bootstrap" --sanitize
  mkdir -p "$build"
  if [ ! -f "$build/CMakeCache.txt" ]; then
    local launcher=()
    command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
    cmake -S "$root" -B "$build" -DCMAKE_CXX_COMPILER=clang++-14 -DFTC_FUZZ=ON \
      -DCMAKE_BUILD_TYPE=None -DCMAKE_CXX_FLAGS="-O1 -g1" -DFTC_BUILD_BENCHMARKS=OFF -DFTC_VECTOR_KERNELS=avx2 \
      "${launcher[@]}" >"$log" 2>&1 || { cat "$log" >&2; return 1; }
  fi
  local targets=()
  for t in "$@"; do targets+=(--target "$t"); done
  cmake --build "$build" -j "$(nproc)" "${targets[@]}" >"$log" 2>&1 || { cat "$log" >&2; return 1; }
}
