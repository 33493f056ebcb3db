// SPDX-License-Identifier: BSD-3-Clause
// findDefaultScene: the installed scenes first, then the source tree's.
#include "tools/dds_driver/default_scene.hpp"

#include <filesystem>
#include <system_error>

namespace raymap::driver {

Result<std::string> findDefaultScene(const std::string& name,
                                     const std::string& source_scenes_dir) {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::path program = fs::read_symlink("/proc/self/exe", error);
  const fs::path installed =
      error ? fs::path() : program.parent_path().parent_path() / "share/raymap/scenes" / name;
  if (!installed.empty() && fs::is_regular_file(installed, error)) {
    return installed.string();
  }
  const fs::path source = fs::path(source_scenes_dir) / name;
  if (fs::is_regular_file(source, error)) {
    return source.string();
  }
  return fail(ErrorCode::kIo, "no scene " + name + " installed (" +
                                  (installed.empty() ? std::string("?") : installed.string()) +
                                  ") nor in the source tree (" + source.string() +
                                  "); name one with --scene");
}

}  // namespace raymap::driver
