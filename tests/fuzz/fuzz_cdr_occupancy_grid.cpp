// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: nav_msgs/OccupancyGrid as raymap echo decodes it.
#include <cstddef>
#include <cstdint>
#include <span>

#include "src/msgs/occupancy_grid_decode.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)raymap::msgs::decodeOccupancyGrid(
      std::span<const std::byte>(reinterpret_cast<const std::byte*>(data), size));
  return 0;
}
