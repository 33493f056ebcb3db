// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: sensor_msgs/CameraInfo (size, K, D, binning, region of interest), and the pixel rays
// of what it accepts.
#include <cstddef>
#include <cstdint>
#include <span>

#include "src/core/pinhole_camera.hpp"
#include "src/msgs/camera_info.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto info = raymap::msgs::decodeCameraInfo(
      std::span<const std::byte>(reinterpret_cast<const std::byte*>(data), size));
  if (!info) {
    return 0;
  }
  const auto& camera = info->camera;
  (void)camera.validate();
  // The pixel rays of a small accepted camera (raymapd builds them for every CameraInfo it
  // accepts; the size bound here is the fuzzer's, raymapd's is the sensor's max_points).
  if (camera.usable() && std::uint64_t{camera.width} * camera.height <= 16384) {
    raymap::PixelRayTable table;
    (void)table.build(camera);
  }
  return 0;
}
