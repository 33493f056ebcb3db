// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: sensor_msgs/Image from a depth camera (16UC1, mono16, 32FC1; both byte orders),
// back-projected with and without down-sampling and invalid-as-free.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "src/core/pinhole_camera.hpp"
#include "src/msgs/depth_image.hpp"

namespace {

/// A distorted camera of the image's own size, so that the decoder gets past the size check to
/// the pixels (the pixel rays are rebuilt only when the size changes).
const raymap::PixelRayTable* raysFor(std::uint32_t width, std::uint32_t height) {
  static raymap::PixelRayTable table;
  raymap::CameraIntrinsics camera;
  camera.width = width;
  camera.height = height;
  camera.fx = 0.8 * width + 1.0;
  camera.fy = 0.8 * width + 1.0;
  camera.cx = 0.5 * width;
  camera.cy = 0.5 * height;
  camera.distortion = raymap::DistortionModel::kPlumbBob;
  camera.k1 = -0.05;
  camera.k2 = 0.01;
  if (!table.matches(camera) && !table.build(camera)) {
    return nullptr;
  }
  return &table;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::byte> cdr(reinterpret_cast<const std::byte*>(data), size);
  auto info = raymap::msgs::inspectDepthImage(cdr);
  if (!info || info->width == 0 || info->height == 0 ||
      std::uint64_t{info->width} * info->height > 16384) {
    return 0;
  }
  const raymap::PixelRayTable* rays = raysFor(info->width, info->height);
  if (rays == nullptr) {
    return 0;
  }
  static std::array<raymap::msgs::ScanPoint, 16384> points;
  raymap::msgs::DepthDecodeOptions options;
  options.min_range_m = 0.2f;
  options.max_range_m = 4.0f;
  for (std::uint32_t downsample : {1u, 3u}) {
    for (bool invalid_as_free : {false, true}) {
      options.downsample = downsample;
      options.invalid_as_free = invalid_as_free;
      auto header = raymap::msgs::decodeDepthImage(cdr, *rays, options, points);
      if (header && header->points >
                        raymap::msgs::depthPointCapacity(info->width, info->height, downsample)) {
        std::abort();  // never more points than blocks
      }
    }
  }
  return 0;
}
