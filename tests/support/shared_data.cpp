// SPDX-License-Identifier: BSD-3-Clause
// The shared data sets and the ray loader.
#include "tests/support/shared_data.hpp"

#include <cctype>
#include <cstddef>

#include <gtest/gtest.h>

#include "src/io/ray_source.hpp"
#include "tests/support/temp_dir.hpp"

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

void PrintTo(const DataCase& c, std::ostream* os) {
  *os << c.data.name << "/" << toString(c.semantics);
}

std::vector<DataCase> dataCases() {
  std::vector<DataCase> cases;
  for (const DataSet& data : sharedDataSets()) {
    for (const Semantics semantics : {Semantics::kPerRay, Semantics::kPerScan}) {
      cases.push_back({data, semantics});
    }
  }
  return cases;
}

std::string dataCaseName(const DataCase& c) {
  std::string name = std::string(c.data.name) + "_" + toString(c.semantics);
  for (char& ch : name) {
    ch = (std::isalnum(static_cast<unsigned char>(ch)) != 0) ? ch : '_';
  }
  return name;
}

DataFiles dataFiles(const DataSet& data) {
  namespace fs = std::filesystem;
  DataFiles files;
  const fs::path dir = sharedDataDir();
  if (dir.empty()) {
    files.missing = "no shared data (../shared/data or $RAYMAP_SHARED_DATA)";
    return files;
  }
  files.file = dir / data.file;
  if (data.trajectory != nullptr) {
    files.trajectory = dir / data.trajectory;
  }
  if (!fs::exists(files.file) || (!files.trajectory.empty() && !fs::exists(files.trajectory))) {
    files.missing = "missing " + files.file.string();
  }
  return files;
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
