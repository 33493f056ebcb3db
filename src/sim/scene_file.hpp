// SPDX-License-Identifier: BSD-3-Clause
// Scene files: a scene, its sensors (a lidar, depth cameras) and their trajectory described in
// YAML (docs/scenes.md).
#pragma once

#include <string>
#include <vector>

#include "raymap/error.hpp"

#include "src/sim/depth_camera.hpp"
#include "src/sim/lidar.hpp"
#include "src/sim/scene.hpp"

namespace raymap::sim {

/// @brief Everything a scene file describes: the solids, and the recording to simulate in them.
/// The trajectory (simulation.path) is the lidar's pose and the robot body's: depth cameras sit
/// on the body at their mounts.
struct SceneFile {
  Scene scene;
  SimulationConfig simulation;  ///< per-column poses (a deskewed recording); scans 0 without lidar
  /// Whether the lidar runs: the file has `lidar:`, or no `depth_cameras:` (a file without
  /// either gets the default lidar, as every file did before depth cameras).
  bool has_lidar = true;
  std::vector<DepthCameraModel> depth_cameras;  ///< validated: DepthCamera::create() succeeds
  /// Seconds recorded from the path's start: `duration`, else scans / rate with a lidar, else
  /// the trajectory's length. Each camera takes frameCount(duration_s, rate_hz) frames.
  double duration_s = 0.0;
};

/// @brief Reads and validates a scene file (docs/scenes.md).
/// @return the scene, or an error "PATH: line N: KEY.PATH: reason", e.g.
/// "stairs.yaml: line 12: objects[3].rise: must be > 0 (got -0.17)". Never throws.
Result<SceneFile> loadSceneFile(const std::string& path);

/// @brief The same from YAML text; `name` stands for the file in errors and is the scene's name
/// when the text has none.
Result<SceneFile> parseSceneFile(const std::string& text, const std::string& name);

}  // namespace raymap::sim
