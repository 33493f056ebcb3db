// SPDX-License-Identifier: BSD-3-Clause
// The shared data sets and the ray loader.
#include "tests/support/shared_data.hpp"

#include <cstddef>

#include <gtest/gtest.h>

#include "src/io/ray_source.hpp"

namespace raymap::test {

std::span<const DataSet> sharedDataSets() {
  static constexpr DataSet kDataSets[] = {
      {"ouster", "ouster/ouster_os1_lb_n3_raycloud.ply.gz", nullptr},
      {"3dtk", "3dtk/3dtk_raycloud.ply.gz", nullptr},
      {"octomap", "octomap/octomap_scan_raycloud.ply.gz", nullptr},
      {"3dtk_points", "3dtk/3dtk_points.ply.gz", "3dtk/3dtk_trajectory.txt"},
  };
  return kDataSets;
}

std::vector<Ray> loadRays(const std::filesystem::path& file,
                          const std::filesystem::path& trajectory) {
  io::RaySourceOptions options;
  if (!trajectory.empty()) {
    options.trajectory_path = trajectory.string();
  }
  auto source = io::openRaySource(file.string(), options);
  if (!source) {
    ADD_FAILURE() << source.error().message;
    return {};
  }
  std::vector<Ray> rays;
  std::vector<Ray> chunk(std::size_t{1} << 16);
  for (;;) {
    auto n = (*source)->read(chunk);
    if (!n) {
      ADD_FAILURE() << n.error().message;
      return {};
    }
    if (*n == 0) {
      return rays;
    }
    rays.insert(rays.end(), chunk.begin(), chunk.begin() + static_cast<std::ptrdiff_t>(*n));
  }
}

}  // namespace raymap::test
