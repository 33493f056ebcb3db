// SPDX-License-Identifier: BSD-3-Clause
// Where raymap-load finds its scene when none is named: $RAYMAP_SCENE_DIR, the installed scenes
// beside the program (<prefix>/share/raymap/scenes), the source tree it was built from, or the
// working folder's config/scenes, so it works from any working directory, installed or not.
#pragma once

#include <string>

#include "raymap/error.hpp"

namespace raymap::driver {

/// @brief The path of scene file `name` (e.g. "yard.yaml"): the first that exists of
/// $RAYMAP_SCENE_DIR/<name>, <directory of the running program>/../share/raymap/scenes/<name>,
/// <source_scenes_dir>/<name> and config/scenes/<name>. @return the path, or an error naming
/// every place looked at, --scene and RAYMAP_SCENE_DIR.
Result<std::string> findDefaultScene(const std::string& name, const std::string& source_scenes_dir);

}  // namespace raymap::driver
