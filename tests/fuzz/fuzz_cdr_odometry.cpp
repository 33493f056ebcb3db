// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: nav_msgs/Odometry (the body pose raymapd takes from an odometry topic).
#include <cstddef>
#include <cstdint>
#include <span>

#include "src/msgs/pose.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)raymap::msgs::decodeOdometry(
      std::span<const std::byte>(reinterpret_cast<const std::byte*>(data), size));
  return 0;
}
