// SPDX-License-Identifier: BSD-3-Clause
// findDefaultScene: $RAYMAP_SCENE_DIR, the installed scenes, the source tree's, the working
// folder's config/scenes, in that order.
#include "tools/dds_driver/default_scene.hpp"

#include <cstdlib>
#include <filesystem>
#include <system_error>
#include <vector>

namespace raymap::driver {

Result<std::string> findDefaultScene(const std::string& name,
                                     const std::string& source_scenes_dir) {
  namespace fs = std::filesystem;
  std::vector<fs::path> places;
  if (const char* dir = std::getenv("RAYMAP_SCENE_DIR"); dir != nullptr && dir[0] != '\0') {
    places.push_back(fs::path(dir) / name);  // the device kit carries its scenes there
  }
  std::error_code error;
  const fs::path program = fs::read_symlink("/proc/self/exe", error);
  if (!error) {
    places.push_back(program.parent_path().parent_path() / "share/raymap/scenes" / name);
  }
  places.push_back(fs::path(source_scenes_dir) / name);
  places.push_back(fs::path("config/scenes") / name);  // a checkout or kit as working folder
  std::string tried;
  for (const fs::path& place : places) {
    if (fs::is_regular_file(place, error)) {
      return place.string();
    }
    tried += (tried.empty() ? "" : ", ") + place.string();
  }
  return fail(ErrorCode::kIo, "no scene " + name + " found (looked at " + tried +
                                  "); name one with --scene or set RAYMAP_SCENE_DIR");
}

}  // namespace raymap::driver
