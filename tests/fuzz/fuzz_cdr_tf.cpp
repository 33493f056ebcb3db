// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: tf2_msgs/TFMessage (rt/tf and rt/tf_static), with room for fewer transforms than
// sent.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "src/msgs/pose.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::byte> cdr(reinterpret_cast<const std::byte*>(data), size);
  static std::array<raymap::msgs::StampedTransform, 4> transforms;
  auto written = raymap::msgs::decodeTfMessage(cdr, transforms);
  if (written && *written > transforms.size()) {
    std::abort();
  }
  return 0;
}
