// SPDX-License-Identifier: BSD-3-Clause
// Map files of NDT-OM / NDT-TM maps: the mode, every NDT parameter and the NDT layers round-trip;
// version-1 files load as occupancy maps; damaged NDT sections fail with the file named.
#include <bit>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "src/io/map_file.hpp"
#include "tests/support/file_bytes.hpp"
#include "tests/support/map_file_layout.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::io {
namespace {

using test::crc32;
using test::getLe;
using test::putLe;
using test::readFileBytes;
using test::TempDir;
using test::writeFileBytes;

// ---- file bytes (docs/map-format.md) ----

// The version-2 tail of the header body: mode, reserved, block size, then the NDT block; version 3
// appends the TSDF block (size, reserved, 3 f64) after it.
constexpr std::size_t kModeAndNdtBytes = 4 + 52;
constexpr std::size_t kTsdfBytes = 4 + 24;
// Offsets inside that tail.
constexpr std::size_t kTailMode = 0;
constexpr std::size_t kTailBlockBytes = 2;
constexpr std::size_t kTailSensorNoise = 4;
constexpr std::size_t kTailFlags = 4 + 52 - 4;
constexpr std::size_t kTailTsdfTruncation = kModeAndNdtBytes + 4;

std::size_t bodyBytes(const std::vector<std::uint8_t>& bytes) {
  return static_cast<std::size_t>(getLe(bytes, 12, 4));
}

/// File offset of the version-2 tail of the header body.
std::size_t tailOffset(const std::vector<std::uint8_t>& bytes) {
  return test::kMapPrefixBytes + bodyBytes(bytes) - kModeAndNdtBytes - kTsdfBytes;
}

void resealVersionedHeader(std::vector<std::uint8_t>& bytes) {
  const std::size_t covered = test::kMapPrefixBytes + bodyBytes(bytes);
  putLe(bytes, covered, crc32(bytes.data(), covered), 4);
}

/// Rewrites a version-3 file as an older version wrote it: version 2 without the TSDF block,
/// version 1 without the mode and NDT block too. The block offsets in the index and footer move
/// with the header.
std::vector<std::uint8_t> asVersion(const std::vector<std::uint8_t>& v3, std::uint32_t version) {
  std::vector<std::uint8_t> old = v3;
  const std::size_t removed = version == 1 ? kModeAndNdtBytes + kTsdfBytes : kTsdfBytes;
  const std::size_t cut = test::kMapPrefixBytes + bodyBytes(v3) - removed;
  old.erase(old.begin() + static_cast<std::ptrdiff_t>(cut),
            old.begin() + static_cast<std::ptrdiff_t>(cut + removed));
  putLe(old, 8, version, 4);
  putLe(old, 12, bodyBytes(v3) - removed, 4);
  resealVersionedHeader(old);
  // Footer: region count at +4, index offset at +12; index entries: coord (12) + offset (8).
  const std::size_t footer = old.size() - 24;
  const std::size_t count = static_cast<std::size_t>(getLe(old, footer + 4, 8));
  const std::size_t index = static_cast<std::size_t>(getLe(old, footer + 12, 8)) - removed;
  putLe(old, footer + 12, index, 8);
  putLe(old, footer + 20, crc32(old.data() + footer, 20), 4);
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t at = index + 4 + i * 20 + 12;
    putLe(old, at, getLe(old, at, 8) - removed, 8);
  }
  const std::size_t index_bytes = 4 + count * 20;
  putLe(old, index + index_bytes, crc32(old.data() + index, index_bytes), 4);
  return old;
}

// ---- maps ----

MapConfig ndtConfig(MapMode mode) {
  MapConfig config;
  config.geometry.resolution = 0.2;
  config.geometry.region_voxels = 8;
  config.mode = mode;
  config.ndt.sensor_noise = 0.031;
  config.ndt.regulariser = 0.25;
  config.ndt.sample_threshold = 6;
  config.ndt.reinit_probability = 0.15;
  config.ndt.reinit_count = 77;
  config.ndt.adaptation_rate = 0.35;
  config.ndt.initial_intensity_variance = 2.5;
  config.memory_budget_bytes = std::uint64_t{16} << 20;
  return config;
}

VoxelMap integratedMap(const MapConfig& config) {
  VoxelMap map = test::makeMap(config);
  auto backend = test::cpuBackend(map, 1);
  std::vector<Ray> rays = test::cubeRoomRays(config.geometry.resolution, 12);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    rays[i].intensity = static_cast<float>(i % 97);
  }
  test::integrate(map, *backend, rays);
  return map;
}

/// Every saved layer of every region is bit-identical.
void expectSameSavedLayers(const VoxelMap& expected, const VoxelMap& actual) {
  ASSERT_EQ(actual.store().size(), expected.store().size());
  const LayerSchema& schema = expected.store().schema();
  expected.store().forEachRegion([&](std::uint32_t slot, Vec3i coord) {
    const std::uint32_t other = actual.store().find(coord);
    ASSERT_NE(other, RegionStore::kNoSlot);
    for (int l = 0; l < schema.size(); ++l) {
      const int other_layer = actual.store().schema().indexOf(schema.at(l).kind);
      ASSERT_GE(other_layer, 0) << schema.at(l).name;
      EXPECT_EQ(
          std::memcmp(actual.store().layerBytes(other, other_layer),
                      expected.store().layerBytes(slot, l), expected.store().layerRegionBytes(l)),
          0)
          << "layer " << schema.at(l).name;
    }
  });
}

class NdtMapFile : public ::testing::TestWithParam<MapMode> {};

TEST_P(NdtMapFile, RoundTripsModeParametersAndNdtLayers) {
  // Arrange
  const MapConfig config = ndtConfig(GetParam());
  const VoxelMap map = integratedMap(config);
  TempDir dir;
  const std::string path = dir.file("ndt.rmap");

  // Act
  ASSERT_TRUE(saveMap(map, path).has_value());
  auto header = readMapHeader(path);
  auto loaded = loadMap(path);

  // Assert
  ASSERT_TRUE(header.has_value()) << header.error().message;
  EXPECT_EQ(header->config.mode, GetParam());
  EXPECT_EQ(header->config.ndt, config.ndt);
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  EXPECT_EQ(loaded->mode(), GetParam());
  EXPECT_EQ(loaded->config().ndt, config.ndt);
  EXPECT_TRUE(loaded->store().schema() == config.schema());
  EXPECT_GE(loaded->ndtLayer(), 0);
  EXPECT_EQ(loaded->hitMissLayer() >= 0, GetParam() == MapMode::kNdtTm);
  EXPECT_EQ(loaded->intensityLayer() >= 0, GetParam() == MapMode::kNdtTm);
  expectSameSavedLayers(map, *loaded);
  EXPECT_GT(loaded->summarise().voxels_occupied, 0u);
}

INSTANTIATE_TEST_SUITE_P(BothNdtModes, NdtMapFile,
                         ::testing::Values(MapMode::kNdtOm, MapMode::kNdtTm));

TEST(NdtMapFileParams, AnUnsetAdaptationRateStaysUnset) {
  // Arrange: derived from the miss probability, which must stay so after a reload.
  MapConfig config = ndtConfig(MapMode::kNdtOm);
  config.ndt.adaptation_rate.reset();
  const VoxelMap map = test::makeMap(config);
  TempDir dir;
  const std::string path = dir.file("derived.rmap");

  // Act
  ASSERT_TRUE(saveMap(map, path).has_value());
  auto header = readMapHeader(path);

  // Assert
  ASSERT_TRUE(header.has_value()) << header.error().message;
  EXPECT_FALSE(header->config.ndt.adaptation_rate.has_value());
  EXPECT_EQ(header->config.ndt, config.ndt);
}

TEST(NdtMapFileParams, AVersion1FileLoadsAsAnOccupancyMap) {
  // Arrange
  MapConfig config = ndtConfig(MapMode::kOccupancy);
  config.ndt = NdtParams{};
  const VoxelMap map = integratedMap(config);
  TempDir dir;
  const std::string path = dir.file("v1.rmap");
  ASSERT_TRUE(saveMap(map, path).has_value());
  writeFileBytes(path, asVersion(readFileBytes(path), 1));

  // Act
  auto loaded = loadMap(path);

  // Assert
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  EXPECT_EQ(loaded->mode(), MapMode::kOccupancy);
  EXPECT_EQ(loaded->config().ndt, NdtParams{});
  expectSameSavedLayers(map, *loaded);
}

TEST(NdtMapFileParams, AVersion2FileLoadsWithTheDefaultTsdfParameters) {
  // Arrange
  const MapConfig config = ndtConfig(MapMode::kNdtOm);
  const VoxelMap map = integratedMap(config);
  TempDir dir;
  const std::string path = dir.file("v2.rmap");
  ASSERT_TRUE(saveMap(map, path).has_value());
  writeFileBytes(path, asVersion(readFileBytes(path), 2));

  // Act
  auto loaded = loadMap(path);

  // Assert
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  EXPECT_EQ(loaded->mode(), MapMode::kNdtOm);
  EXPECT_EQ(loaded->config().ndt, config.ndt);
  EXPECT_EQ(loaded->config().tsdf, TsdfParams{});
  expectSameSavedLayers(map, *loaded);
}

TEST(TsdfMapFile, ATsdfMapRoundTripsWithItsParametersAndField) {
  // Arrange
  MapConfig config = ndtConfig(MapMode::kOccupancy).forTsdf();
  config.tsdf.truncation_m = 0.7;
  config.tsdf.max_weight = 77.0;
  config.tsdf.dropoff_m = 0.0;
  const VoxelMap map = integratedMap(config);
  TempDir dir;
  const std::string path = dir.file("tsdf.rmap");

  // Act
  ASSERT_TRUE(saveMap(map, path).has_value());
  auto loaded = loadMap(path);

  // Assert
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  EXPECT_EQ(loaded->mode(), MapMode::kTsdf);
  EXPECT_EQ(loaded->config().tsdf.truncationMetres(0.2), 0.7);
  EXPECT_EQ(loaded->config().tsdf.max_weight, 77.0);
  EXPECT_EQ(loaded->config().tsdf.dropoffMetres(0.2), 0.0);
  EXPECT_EQ(loaded->occupancyLayer(), -1);
  std::uint64_t updated = 0;
  map.store().forEachRegion([&](std::uint32_t slot, Vec3i region) {
    const auto* a = map.store().layerData<rm_tsdf_voxel>(slot, map.tsdfLayer());
    for (std::uint32_t i = 0; i < map.store().voxelsPerRegion(); ++i) {
      const rm_tsdf_voxel b = loaded->tsdf(map.voxelAt(region, i));
      ASSERT_EQ(a[i].distance, b.distance);
      ASSERT_EQ(a[i].weight, b.weight);
      updated += a[i].weight > 0.0f ? 1u : 0u;
    }
  });
  EXPECT_GT(updated, 100u);
}

// ---- damaged NDT sections ----

class DamagedNdtFile : public ::testing::Test {
 protected:
  void SetUp() override {
    const VoxelMap map = integratedMap(ndtConfig(MapMode::kNdtTm));
    ASSERT_TRUE(saveMap(map, good_path_).has_value());
    good_ = readFileBytes(good_path_);
    tail_ = tailOffset(good_);
    ASSERT_EQ(good_.at(tail_ + kTailMode), 2u);
  }

  /// Loads `bad` (after resealing its header) and returns the error.
  Error loadFails(std::vector<std::uint8_t> bad) {
    resealVersionedHeader(bad);
    writeFileBytes(bad_path_, bad);
    auto loaded = loadMap(bad_path_);
    EXPECT_FALSE(loaded.has_value());
    if (loaded.has_value()) {
      return Error{};
    }
    EXPECT_EQ(loaded.error().message.rfind(bad_path_ + ": ", 0), 0u) << loaded.error().message;
    return loaded.error();
  }

  TempDir dir_;
  const std::string good_path_ = dir_.file("good.rmap");
  const std::string bad_path_ = dir_.file("bad.rmap");
  std::vector<std::uint8_t> good_;
  std::size_t tail_ = 0;
};

TEST_F(DamagedNdtFile, AnUnknownModeIsNamed) {
  std::vector<std::uint8_t> bad = good_;
  bad[tail_ + kTailMode] = 9;
  const Error error = loadFails(bad);
  EXPECT_EQ(error.code, ErrorCode::kCorrupt);
  EXPECT_NE(error.message.find("unknown map mode 9"), std::string::npos) << error.message;
}

TEST_F(DamagedNdtFile, AModeThatDisagreesWithTheLayersIsRejected) {
  // ndt-om declares fewer layers than the ndt-tm file holds.
  std::vector<std::uint8_t> bad = good_;
  bad[tail_ + kTailMode] = 1;
  const Error error = loadFails(bad);
  EXPECT_EQ(error.code, ErrorCode::kCorrupt);
  EXPECT_NE(error.message.find("saved layers do not match"), std::string::npos) << error.message;
}

TEST_F(DamagedNdtFile, AWrongBlockSizeIsNamed) {
  std::vector<std::uint8_t> bad = good_;
  putLe(bad, tail_ + kTailBlockBytes, 60, 2);
  const Error error = loadFails(bad);
  EXPECT_EQ(error.code, ErrorCode::kCorrupt);
  EXPECT_NE(error.message.find("NDT parameter block of 60 bytes"), std::string::npos)
      << error.message;
}

TEST_F(DamagedNdtFile, AnOutOfRangeParameterIsNamed) {
  std::vector<std::uint8_t> bad = good_;
  putLe(bad, tail_ + kTailSensorNoise, std::bit_cast<std::uint64_t>(-1.0), 8);
  const Error error = loadFails(bad);
  EXPECT_EQ(error.code, ErrorCode::kCorrupt);
  EXPECT_NE(error.message.find("sensor-noise"), std::string::npos) << error.message;
}

TEST_F(DamagedNdtFile, UnknownFlagsAreRejected) {
  std::vector<std::uint8_t> bad = good_;
  putLe(bad, tail_ + kTailFlags, 0x80000001u, 4);
  const Error error = loadFails(bad);
  EXPECT_EQ(error.code, ErrorCode::kCorrupt);
  EXPECT_NE(error.message.find("unknown NDT flags"), std::string::npos) << error.message;
}

TEST_F(DamagedNdtFile, ABadTsdfParameterIsNamed) {
  std::vector<std::uint8_t> bad = good_;
  putLe(bad, tail_ + kTailTsdfTruncation, std::bit_cast<std::uint64_t>(-0.3), 8);
  const Error error = loadFails(bad);
  EXPECT_EQ(error.code, ErrorCode::kCorrupt);
  EXPECT_NE(error.message.find("bad TSDF parameters"), std::string::npos) << error.message;
}

TEST_F(DamagedNdtFile, ABodyCutInsideTheNdtBlockIsNamed) {
  // The body (and its CRC) end 20 bytes into the NDT block.
  std::vector<std::uint8_t> bad(good_.begin(),
                                good_.begin() + static_cast<std::ptrdiff_t>(tail_ + 24));
  bad.resize(bad.size() + 4 + 4096, 0);  // CRC, then stand-ins for the regions
  putLe(bad, 12, tail_ + 24 - test::kMapPrefixBytes, 4);
  const Error error = loadFails(bad);
  EXPECT_EQ(error.code, ErrorCode::kCorrupt);
  EXPECT_NE(error.message.find("NDT parameters run past the header"), std::string::npos)
      << error.message;
}

TEST_F(DamagedNdtFile, AFileCutInTheNdtLayersIsTruncated) {
  // Arrange: cut halfway through the file (inside the region blocks that hold the NDT layers).
  std::vector<std::uint8_t> bad(good_.begin(),
                                good_.begin() + static_cast<std::ptrdiff_t>(good_.size() / 2));
  writeFileBytes(bad_path_, bad);

  // Act
  auto loaded = loadMap(bad_path_);

  // Assert
  ASSERT_FALSE(loaded.has_value());
  EXPECT_EQ(loaded.error().code, ErrorCode::kTruncated) << loaded.error().message;
  EXPECT_EQ(loaded.error().message.rfind(bad_path_ + ": ", 0), 0u) << loaded.error().message;
}

}  // namespace
}  // namespace raymap::io
