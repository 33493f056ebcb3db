// SPDX-License-Identifier: BSD-3-Clause
// The height-map generators under test: the CPU one always, OpenCL and CUDA where this build and
// machine have them. Tests are parametrised by name and skip a generator that is unavailable.
#pragma once
#include <string>
#include <vector>

#include "src/heightmap/heightmap_generator.hpp"

namespace raymap::test {

/// "cpu", plus "opencl" / "cuda" when built in.
std::vector<std::string> heightmapGeneratorNames();

/// @brief The generator called `name` (created once per process), or nullptr with `why` set when
/// this machine has no such device.
heightmap::HeightmapGenerator* heightmapGenerator(const std::string& name, std::string* why);

}  // namespace raymap::test

/// Skips the current test when the parametrised generator is unavailable.
#define REQUIRE_HEIGHTMAP_GENERATOR(name, var)                                                     \
  std::string var##_why;                                                                           \
  raymap::heightmap::HeightmapGenerator* var = raymap::test::heightmapGenerator(name, &var##_why); \
  if (var == nullptr) {                                                                            \
    GTEST_SKIP() << name << " height-map generator unavailable: " << var##_why;                    \
  }
