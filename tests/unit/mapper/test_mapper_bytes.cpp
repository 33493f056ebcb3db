// SPDX-License-Identifier: BSD-3-Clause
// The same rays give the same map file, byte for byte, on every architecture (issue 57): maps of a
// fixed ray set, per ray, per scan and NDT-OM, saved by raymap::Mapper, have the SHA-256 sums
// recorded in tests/golden/library_maps.sha256. The x86-64 build recorded them; the arm64 build
// runs this test under qemu (tools/check-arm64.sh), where floating-point contraction left on
// would move voxel crossings and update roundings (docs/arm64.md).
//
// The rays are made here with +, -, *, / and sqrt only (IEEE 754 rounds each exactly, so every
// architecture makes the same rays; sin, cos and the like may differ in the last bit from one
// libm to another).
//
// A deliberate change of the maths or the file format: run the test with
// RAYMAP_GOLDEN_UPDATE=FILE, which writes the sums to FILE instead of comparing, copy FILE over
// the manifest, and say in the commit why the bytes changed.
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "raymap/mapper.hpp"
#include <gtest/gtest.h>

#include "tests/support/golden_manifest.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::test {
namespace {

/// A walk through a 10 x 8 x 3 m room with a pillar: 40 scans, each a sweep of 48 x 16 rays from
/// the sensor 1.2 m up to the first wall, floor, ceiling or pillar face they meet (rays past
/// 6 m are cut there and clear free space only).
std::vector<std::vector<WorldRay>> roomScansForBytes() {
  std::vector<std::vector<WorldRay>> scans;
  for (int k = 0; k < 40; ++k) {
    const Eigen::Vector3d origin(-3.7 + 0.17 * k, -1.1 + 0.045 * k, 1.2);
    std::vector<WorldRay> scan;
    for (int i = 0; i < 48; ++i) {
      for (int j = 0; j < 16; ++j) {
        // A direction on the cube's surface, normalised: sqrt is exact in IEEE 754.
        Eigen::Vector3d d(1.0 - (i % 12) / 5.5, (i / 12) * 0.7 - 1.05 + 0.013 * k, j / 7.5 - 1.0);
        d /= std::sqrt(d.squaredNorm());
        double t = 6.0;
        const auto hit = [&](double along, double from, double plane) {
          if (along != 0.0) {
            const double s = (plane - from) / along;
            if (s > 0.0 && s < t) {
              t = s;
            }
          }
        };
        hit(d.x(), origin.x(), d.x() > 0.0 ? 5.0 : -5.0);
        hit(d.y(), origin.y(), d.y() > 0.0 ? 4.0 : -4.0);
        hit(d.z(), origin.z(), d.z() > 0.0 ? 3.0 : 0.0);
        // The pillar: x = 1.5, facing -x, between y = -0.5 and 0.5.
        if (d.x() > 0.0 && origin.x() < 1.5) {
          const double s = (1.5 - origin.x()) / d.x();
          const double y = origin.y() + s * d.y();
          if (s < t && y > -0.5 && y < 0.5) {
            t = s;
          }
        }
        WorldRay ray;
        ray.origin = origin;
        ray.end = origin + t * d;
        ray.intensity = static_cast<float>(i + j);
        ray.no_return = t == 6.0;
        scan.push_back(ray);
      }
    }
    scans.push_back(std::move(scan));
  }
  return scans;
}

TEST(MapperBytes, TheSameRaysGiveTheSameMapFileOnEveryArchitecture) {
  TempDir dir;
  const std::vector<std::vector<WorldRay>> scans = roomScansForBytes();
  struct Case {
    const char* name;
    Semantics semantics;
    MapMode mode;
  };
  const Case cases[] = {{"room_ray.rmap", Semantics::kPerRay, MapMode::kOccupancy},
                        {"room_scan.rmap", Semantics::kPerScan, MapMode::kOccupancy},
                        {"room_ndt_om.rmap", Semantics::kPerRay, MapMode::kNdtOm}};
  const char* update = std::getenv("RAYMAP_GOLDEN_UPDATE");
  // $RAYMAP_GOLDEN_DIR when set (the device kit carries the manifest beside its test programs),
  // else the source tree's.
  const char* golden_dir = std::getenv("RAYMAP_GOLDEN_DIR");
  const std::string manifest_path = (golden_dir != nullptr && *golden_dir != '\0'
                                         ? std::string(golden_dir)
                                         : std::string(RAYMAP_SOURCE_DIR) + "/tests/golden") +
                                    "/library_maps.sha256";
  const std::map<std::string, std::string> manifest = readSha256Manifest(manifest_path);
  std::ostringstream sums;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    MapperConfig config;
    config.map.semantics = c.semantics;
    config.map.mode = c.mode;
    config.map.max_memory_bytes = std::uint64_t{256} << 20;
    auto mapper = Mapper::create(config);
    ASSERT_TRUE(mapper) << mapper.error().message;
    for (const std::vector<WorldRay>& scan : scans) {
      ASSERT_TRUE(mapper->integrate(scan));
    }
    const std::string path = dir.file(c.name);
    auto saved = mapper->save(path);
    ASSERT_TRUE(saved) << saved.error().message;
    EXPECT_GT(mapper->counts().voxels_occupied, 1000u);
    const std::string sha = sha256OfFile(path);
    ASSERT_EQ(sha.size(), 64u) << "sha256sum failed on " << path;
    sums << sha << "  " << c.name << "\n";
    if (update == nullptr) {
      ASSERT_EQ(manifest.count(c.name), 1u) << manifest_path << " lacks " << c.name;
      EXPECT_EQ(sha, manifest.at(c.name)) << c.name << " is not the recorded map";
    }
  }
  if (update != nullptr) {
    std::ofstream(update) << sums.str();
  }
}

}  // namespace
}  // namespace raymap::test
