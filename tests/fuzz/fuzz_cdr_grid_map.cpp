// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: grid_map_msgs/GridMap as raymap echo and the tests decode raymapd's output.
#include <cstddef>
#include <cstdint>
#include <span>

#include "src/msgs/grid_map_decode.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto map = raymap::msgs::decodeGridMap(
      std::span<const std::byte>(reinterpret_cast<const std::byte*>(data), size));
  if (map) {
    for (const auto& layer : map->data) {
      (void)raymap::msgs::layerStats(layer.data);
    }
  }
  return 0;
}
