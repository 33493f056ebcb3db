// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: a simulator scene file (YAML: shapes, lidar, depth cameras, trajectory).
#include <cstddef>
#include <cstdint>
#include <string>

#include "src/sim/scene_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  (void)raymap::sim::parseSceneFile(text, "fuzz.yaml");
  return 0;
}
