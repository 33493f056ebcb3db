// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: sensor_msgs/PointCloud2 as raymapd decodes it (CDR either byte order, any fields).
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "src/msgs/point_cloud.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::byte> cdr(reinterpret_cast<const std::byte*>(data), size);
  static std::array<raymap::msgs::ScanPoint, 4096> points;
  // raymapd's defaults, and a configuration naming its fields (time in a named field, no
  // intensity, zero points kept), so both option paths see every input.
  raymap::msgs::CloudDecodeOptions named;
  named.time_field = "timestamp";
  named.intensity_field = nullptr;
  named.origin_is_no_return = false;
  for (const auto& options : {raymap::msgs::CloudDecodeOptions{}, named}) {
    auto header = raymap::msgs::decodePointCloud2(cdr, points, options);
    if (header && header->points > points.size()) {
      std::abort();  // never more points than room
    }
  }
  return 0;
}
