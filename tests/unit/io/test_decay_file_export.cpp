// SPDX-License-Identifier: BSD-3-Clause
// Decay-rate maps in files: the traversal layer round-trips and marks the loaded map as a
// decay-rate map; `export --mode decay` writes the voxels whose rate reaches the threshold, with
// their rate and metres; maps without the layer are refused with the reason.
#include <bit>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "kernels/common/decay.h"
#include "src/io/map_export.hpp"
#include "src/io/map_file.hpp"
#include "tests/support/file_bytes.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::io {
namespace {

using test::TempDir;

/// Rays along +x from the centre of voxel (0,0,0): five to x = 1.55, 1.65, 2.35, 1.03 and 1.07 m
/// (tests/unit/map/test_decay_map.cpp works the lengths out: voxel (10,0,0) has 0.4 m and 2
/// samples, rate 5).
VoxelMap decayMap(bool with_occupancy = true) {
  const MapConfig config = test::decayConfig();
  VoxelMap map = test::makeMap(with_occupancy ? config : config.forDecay());
  auto backend = test::cpuBackend(map, 1);
  std::vector<Ray> rays;
  for (const double end_x : {1.55, 1.65, 2.35, 1.03, 1.07}) {
    rays.push_back(test::makeRay({0.05, 0.05, 0.05}, {end_x, 0.05, 0.05}));
  }
  test::integrate(map, *backend, rays);
  return map;
}

float f32At(const test::Bytes& bytes, std::size_t at) {
  return std::bit_cast<float>(static_cast<std::uint32_t>(test::getLe(bytes, at, 4)));
}

TEST(DecayFile, TheTraversalLayerRoundTripsAndMakesADecayRateMap) {
  for (const bool with_occupancy : {true, false}) {
    TempDir dir;
    const VoxelMap map = decayMap(with_occupancy);
    const std::string path = dir.file("decay.rmap");
    ASSERT_TRUE(saveMap(map, path).has_value());
    auto loaded = loadMap(path);
    ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
    EXPECT_TRUE(loaded->config().decay_rate);
    EXPECT_EQ(loaded->config().occupancy_layer, with_occupancy);
    EXPECT_EQ(mapModeName(loaded->config()), with_occupancy ? "occupancy+decay" : "decay");
    ASSERT_GE(loaded->traversalLayer(), 0);
    for (int x = -1; x < 30; ++x) {
      EXPECT_EQ(loaded->traversal({x, 0, 0}), map.traversal({x, 0, 0})) << "x = " << x;
    }
    EXPECT_NEAR(rm_decay_rate(loaded->mean({10, 0, 0}).count, loaded->traversal({10, 0, 0})), 5.0f,
                1e-5f);
  }
}

/// Exports map (decayMap()) at thresholds 0 and 4.5 and checks the points and their records.
void exportAndCheck(const VoxelMap& map);

TEST(DecayFile, ExportWritesTheVoxelsAtOrAboveTheThresholdWithRateAndMetres) {
  for (const bool with_occupancy : {true, false}) {
    SCOPED_TRACE(with_occupancy ? "occupancy+decay" : "decay");
    exportAndCheck(decayMap(with_occupancy));
  }
}

TEST(DecayFile, AMapOfDecayRatesOnlyExportsMeansButNoOccupiedOrFreeVoxels) {
  TempDir dir;
  const VoxelMap map = decayMap(false);
  auto means = exportPly(map, ExportMode::kMean, dir.file("mean.ply"));
  ASSERT_TRUE(means.has_value()) << means.error().message;
  EXPECT_EQ(*means, 4u);  // the samples' voxels: 10 (two of them), 15, 16 and 23
  for (const ExportMode mode : {ExportMode::kOccupied, ExportMode::kFree}) {
    auto refused = exportPly(map, mode, dir.file("x.ply"));
    ASSERT_FALSE(refused.has_value());
    EXPECT_NE(refused.error().message.find("no occupancy layer"), std::string::npos)
        << refused.error().message;
  }
}

void exportAndCheck(const VoxelMap& map) {
  TempDir dir;
  const std::string all = dir.file("all.ply");
  const std::string high = dir.file("high.ply");
  auto n_all = exportPly(map, ExportMode::kDecay, all);
  ExportOptions options;
  options.decay_threshold = 4.5;
  auto n_high = exportPly(map, ExportMode::kDecay, high, options);
  ASSERT_TRUE(n_all.has_value()) << n_all.error().message;
  ASSERT_TRUE(n_high.has_value()) << n_high.error().message;
  // Every voxel the rays entered: x = 0 .. 23 along the row.
  EXPECT_EQ(*n_all, 24u);
  // Rates: voxel 10 has 5, voxel 15 4, 16 6.67 (0.15 m, 1 sample), 23: 1 / 0.05 = 20.
  EXPECT_EQ(*n_high, 3u);
  const test::Bytes bytes = test::readFileBytes(high);
  const std::string text(bytes.begin(), bytes.end());
  const std::size_t end = text.find("end_header\n");
  ASSERT_NE(end, std::string::npos);
  EXPECT_NE(text.find("property float decay_rate\nproperty float traversal\n"), std::string::npos);
  const test::Bytes data(bytes.begin() + static_cast<std::ptrdiff_t>(end + 11), bytes.end());
  ASSERT_EQ(data.size(), 3u * 28u);
  // The first point (regions and voxels in order): voxel 10 at its mean, rate 5 over 0.4 m.
  EXPECT_NEAR(f32At(data, 0), 1.05f, 0.021f);  // the mean of the samples at 1.03 and 1.07
  EXPECT_NEAR(f32At(data, 20), 5.0f, 1e-5f);
  EXPECT_NEAR(f32At(data, 24), 0.4f, 1e-6f);
}

TEST(DecayFile, ExportRefusesAMapWithoutTheTraversalLayerAndABadThreshold) {
  TempDir dir;
  VoxelMap plain = test::makeMap(test::smallConfig(Semantics::kPerRay, 16));
  auto refused = exportPly(plain, ExportMode::kDecay, dir.file("x.ply"));
  ASSERT_FALSE(refused.has_value());
  EXPECT_NE(refused.error().message.find("no traversal layer"), std::string::npos);
  ExportOptions negative;
  negative.decay_threshold = -1.0;
  const VoxelMap map = decayMap();
  auto bad = exportPly(map, ExportMode::kDecay, dir.file("y.ply"), negative);
  ASSERT_FALSE(bad.has_value());
  EXPECT_NE(bad.error().message.find("threshold"), std::string::npos);
}

}  // namespace
}  // namespace raymap::io
