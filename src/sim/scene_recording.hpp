// SPDX-License-Identifier: BSD-3-Clause
// A scene file's sensors recorded over time as one stream of world-frame rays: the lidar's scans
// and the depth cameras' frames interleaved by time, what `raymap simulate --rays` writes.
#pragma once

#include <cstdint>
#include <vector>

#include "raymap/error.hpp"

#include "src/map/ray.hpp"
#include "src/sim/scene_file.hpp"

namespace raymap::sim {

/// @brief Which of a scene file's sensors run. Plain value type.
struct RecordedSensors {
  bool lidar = false;
  bool depth = false;
};

/// @brief The rays of every sensor that runs, sweep by sweep in time order (a lidar revolution
/// or a camera frame; the lidar first on a tie, then the cameras in file order), each sweep its
/// own scan index from 0, appended to `rays`. Depth frames go through the wire format and
/// raymapd's decoders (appendDepthFrameRays); `depth_frames` counts them.
/// @param duration_s seconds from the path's start (SceneFile::duration_s)
/// @return an error only when a camera cannot be made (a file the loader did not validate).
/// Allocates; deterministic for a file (its seed).
Expected<void, Error> recordScene(const SceneFile& file, const RecordedSensors& sensors,
                                  double duration_s, std::vector<Ray>& rays,
                                  std::uint64_t& depth_frames);

}  // namespace raymap::sim
