// SPDX-License-Identifier: BSD-3-Clause
// Scene files: a scene, a lidar and its trajectory described in YAML (docs/scenes.md).
#pragma once

#include <string>

#include "raymap/error.hpp"

#include "src/sim/lidar.hpp"
#include "src/sim/scene.hpp"

namespace raymap::sim {

/// @brief Everything a scene file describes: the solids, and the recording to simulate in them.
struct SceneFile {
  Scene scene;
  SimulationConfig simulation;  ///< per-column poses (a deskewed recording)
};

/// @brief Reads and validates a scene file (docs/scenes.md).
/// @return the scene, or an error "PATH: line N: KEY.PATH: reason", e.g.
/// "stairs.yaml: line 12: objects[3].rise: must be > 0 (got -0.17)". Never throws.
Result<SceneFile> loadSceneFile(const std::string& path);

/// @brief The same from YAML text; `name` stands for the file in errors and is the scene's name
/// when the text has none.
Result<SceneFile> parseSceneFile(const std::string& text, const std::string& name);

}  // namespace raymap::sim
