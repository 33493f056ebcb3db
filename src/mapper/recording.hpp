// SPDX-License-Identifier: BSD-3-Clause
// Opening a recording (a PLY file or a rosbag2 bag) as the one ray source that raymap::
// RecordingReader and `raymap populate` both read: one choice of reader, one conversion of the
// options.
#pragma once

#include <memory>
#include <string>

#include "raymap/error.hpp"
#include "raymap/recording.hpp"

#include "src/bag/bag_ray_source.hpp"
#include "src/io/ray_source.hpp"

namespace raymap::mapper {

/// @brief A file's reading options as the PLY readers take them.
io::RaySourceOptions toRaySourceOptions(const RecordingOptions& options);
/// @brief A bag's reading options as the bag reader takes them.
bag::BagRaysOptions toBagRaysOptions(const RecordingOptions& options);

/// An open recording: its rays, and for a bag its report (owned by `source`).
struct OpenedRecording {
  std::unique_ptr<io::RaySource> source;
  bag::BagRaySource* bag = nullptr;  ///< non-null for a bag
};

/// @brief Opens `path`: a bag (bag::isBag), else a PLY. A raymap record log is refused naming
/// what reads it. Errors name the file and the reason.
Result<OpenedRecording> openRecording(const std::string& path, const RecordingOptions& options);

}  // namespace raymap::mapper
