# SPDX-License-Identifier: BSD-3-Clause
# Cross build for arm64 (a Jetson Orin's CPU) from an x86-64 Debian 12: Debian's cross compiler
# (crossbuild-essential-arm64) with an arm64 Debian 12 root holding the project's dependencies
# (tools/arm64-root.sh makes one) as the system root. idlc and the other build tools are the build
# host's own (cyclonedds-tools); the programs built run under qemu-user-static with the root as
# their library prefix (ctest does that through CMAKE_CROSSCOMPILING_EMULATOR).
#
#   RAYMAP_ARM64_ROOT=/path/to/root cmake --preset arm64
#
# CUDA: Debian 12's and NVIDIA's x86-64 nvcc here has no aarch64 target, so the arm64 build has no
# CUDA backend; a Jetson builds it natively (docs/arm64.md).
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)

if(NOT RAYMAP_ARM64_ROOT)
  set(RAYMAP_ARM64_ROOT "$ENV{RAYMAP_ARM64_ROOT}")
endif()
# Kept in the cache, so that a later reconfigure (cmake ., a changed CMakeLists.txt) finds it.
set(RAYMAP_ARM64_ROOT "${RAYMAP_ARM64_ROOT}" CACHE PATH "arm64 Debian 12 root (tools/arm64-root.sh)")
if(NOT RAYMAP_ARM64_ROOT OR NOT EXISTS "${RAYMAP_ARM64_ROOT}/usr/lib/aarch64-linux-gnu")
  message(FATAL_ERROR "arm64 cross build: RAYMAP_ARM64_ROOT ('${RAYMAP_ARM64_ROOT}') is not an "
    "arm64 Debian 12 root; make one with tools/arm64-root.sh DIR and set RAYMAP_ARM64_ROOT=DIR")
endif()
# Passed on to try_compile's projects, which read this file again.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES RAYMAP_ARM64_ROOT)

set(CMAKE_SYSROOT "${RAYMAP_ARM64_ROOT}")
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)

# Libraries, headers and CMake packages from the root only; programs (idlc, node) from the host.
set(CMAKE_FIND_ROOT_PATH "${RAYMAP_ARM64_ROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${RAYMAP_ARM64_ROOT}")
set(ENV{PKG_CONFIG_LIBDIR}
  "${RAYMAP_ARM64_ROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${RAYMAP_ARM64_ROOT}/usr/share/pkgconfig")

# Test programs (gtest's discovery at build time, ctest) run emulated, finding the dynamic loader
# and the libraries in the root.
find_program(RAYMAP_QEMU_AARCH64 qemu-aarch64-static REQUIRED)
set(CMAKE_CROSSCOMPILING_EMULATOR "${RAYMAP_QEMU_AARCH64};-L;${RAYMAP_ARM64_ROOT}")
