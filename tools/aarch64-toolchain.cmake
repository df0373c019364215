# Cross-compiles ftctune for 64-bit Arm (aarch64) with Debian's cross compiler and multiarch
# arm64 libraries, and runs the tests under qemu-user: `tools/test --aarch64` uses it (see
# docs/architecture.md, "Runtime dispatch"). The x86-64 SIMD kernels are not built for aarch64;
# the scalar path is the one that runs, and it must give the same bits as on x86-64.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)

# Multiarch arm64 packages live under /usr/lib/aarch64-linux-gnu; pagmo's -dev package cannot be
# installed beside the x86-64 one (it is not Multi-Arch: same), so tools/bootstrap --aarch64
# unpacks it into FTC_AARCH64_EXTRA instead.
set(FTC_AARCH64_EXTRA "" CACHE PATH "Where tools/bootstrap --aarch64 unpacked arm64 -dev packages")
set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu / ${FTC_AARCH64_EXTRA})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)
set(ENV{PKG_CONFIG_LIBDIR} /usr/lib/aarch64-linux-gnu/pkgconfig:/usr/share/pkgconfig)

# The host's mpicxx would hand over x86-64 libraries: this build is for one machine.
set(CMAKE_DISABLE_FIND_PACKAGE_MPI ON)

# CTest and gtest_discover_tests run every test binary through qemu (the arm64 loader and libc
# come from libc6:arm64).
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64)
