// SPDX-License-Identifier: BSD-3-Clause
// Where raymap-load finds its scene when none is named: the installed scenes beside the program
// (<prefix>/share/raymap/scenes), else the source tree's config/scenes it was built from, so it
// works from any working directory, installed or not.
#pragma once

#include <string>

#include "raymap/error.hpp"

namespace raymap::driver {

/// @brief The path of scene file `name` (e.g. "yard.yaml"): `<directory of the running
/// program>/../share/raymap/scenes/<name>` when it exists, else `<source_scenes_dir>/<name>`
/// when that exists. @return the path, or an error naming both places and --scene.
Result<std::string> findDefaultScene(const std::string& name, const std::string& source_scenes_dir);

}  // namespace raymap::driver
