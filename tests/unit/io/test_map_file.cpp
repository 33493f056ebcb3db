// SPDX-License-Identifier: BSD-3-Clause
// Map files: bit-exact round trips of every parameter and voxel, and clean failures on corrupt,
// truncated, foreign and newer files.
#include <algorithm>
#include <bit>
#include <cstring>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "kernels/common/scan_mark.h"
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

// ---- file bytes (the layout of docs/map-format.md) ----

// Offsets inside the header body (see docs/map-format.md).
constexpr std::size_t kBodyLayerCount = 34;
constexpr std::size_t kBodyFirstLayerKind = 36;
// Version 2 ends the body with the map mode (4 bytes) and the 52-byte NDT block.
// Version 2's mode and NDT block, then version 3's TSDF block, end the header body.
constexpr std::size_t kBodyModeAndNdtBytes = 4 + 52 + 4 + 24;

std::size_t headerBodyBytes(const std::vector<std::uint8_t>& bytes) {
  return static_cast<std::size_t>(getLe(bytes, 12, 4));
}

/// Recomputes the header CRC after a test edited the header.
void resealHeader(std::vector<std::uint8_t>& bytes) {
  const std::size_t covered = test::kMapPrefixBytes + headerBodyBytes(bytes);
  putLe(bytes, covered, crc32(bytes.data(), covered), 4);
}

/// File offset of the first region block (right after the header CRC).
std::size_t firstBlockOffset(const std::vector<std::uint8_t>& bytes) {
  return test::kMapPrefixBytes + headerBodyBytes(bytes) + 4;
}

/// Block offsets from the region index the footer points to.
std::vector<std::size_t> blockOffsets(const std::vector<std::uint8_t>& bytes) {
  const std::size_t footer = bytes.size() - test::kMapFooterBytes;
  const auto count = static_cast<std::size_t>(getLe(bytes, footer + 4, 8));
  const auto index = static_cast<std::size_t>(getLe(bytes, footer + 12, 8));
  std::vector<std::size_t> offsets;
  for (std::size_t i = 0; i < count; ++i) {
    offsets.push_back(
        static_cast<std::size_t>(getLe(bytes, index + 4 + i * test::kMapIndexEntryBytes + 12, 8)));
  }
  return offsets;
}

// ---- maps ----

MapConfig smallConfig(Semantics semantics, bool voxel_mean) {
  MapConfig config;
  config.geometry.resolution = 0.25;
  config.geometry.region_voxels = 8;
  config.semantics = semantics;
  config.voxel_mean = voxel_mean;
  config.memory_budget_bytes = std::uint64_t{1} << 22;
  return config;
}

/// Gives a region every kind of content a map holds: unobserved voxels, both clamps, values in
/// between, means with and without samples, and (per-scan maps) non-zero scan marks.
void fillRegion(VoxelMap& map, Vec3i coord, std::uint32_t seed) {
  const auto slot = map.store().findOrCreate(coord);
  ASSERT_TRUE(slot.has_value());
  std::mt19937 rng(seed);
  const auto draw = [&rng]() { return static_cast<std::uint32_t>(rng()); };
  const OccupancyParams& p = map.occupancy();
  std::uniform_real_distribution<float> between(p.clamp_min, p.clamp_max);
  const std::uint32_t voxels = map.store().voxelsPerRegion();
  float* occupancy = map.store().layerData<float>(*slot, map.occupancyLayer());
  for (std::uint32_t v = 0; v < voxels; ++v) {
    switch (draw() % 4u) {
      case 0:
        occupancy[v] = std::numeric_limits<float>::infinity();
        break;
      case 1:
        occupancy[v] = p.clamp_min;
        break;
      case 2:
        occupancy[v] = p.clamp_max;
        break;
      default:
        occupancy[v] = between(rng);
        break;
    }
  }
  if (map.meanLayer() >= 0) {
    auto* means = map.store().layerData<rm_voxel_mean>(*slot, map.meanLayer());
    for (std::uint32_t v = 0; v < voxels; ++v) {
      means[v].packed = draw() & 0x3FFFFFFFu;
      means[v].count = draw() % 3u == 0u ? 0u : draw() % 100000u;
    }
  }
  if (map.scanMarkLayer() >= 0) {
    auto* marks = map.store().layerData<std::uint32_t>(*slot, map.scanMarkLayer());
    for (std::uint32_t v = 0; v < voxels; ++v) {
      marks[v] = draw() | 1u;
    }
  }
}

const std::vector<Vec3i> kRegions = {{0, 0, 0}, {-1, 0, 0}, {3, -2, 7}, {-5, -6, -7}, {0, 0, -1}};

VoxelMap filledMap(Semantics semantics, bool voxel_mean) {
  VoxelMap map = test::makeMap(smallConfig(semantics, voxel_mean));
  std::uint32_t seed = 11;
  for (const Vec3i& region : kRegions) {
    fillRegion(map, region, seed++);
  }
  map.setInfo("source", "yard.ply");
  map.setInfo("rays", "123456");
  map.setInfo("", "empty key");
  map.setInfo("binary", std::string("a\0b\xff", 4));
  return map;
}

bool sameBits(float a, float b) {
  return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b);
}

void expectSameParameters(const MapConfig& expected, const MapConfig& actual) {
  EXPECT_EQ(std::bit_cast<std::uint64_t>(actual.geometry.resolution),
            std::bit_cast<std::uint64_t>(expected.geometry.resolution));
  EXPECT_EQ(actual.geometry.region_voxels, expected.geometry.region_voxels);
  EXPECT_TRUE(sameBits(actual.occupancy.hit, expected.occupancy.hit));
  EXPECT_TRUE(sameBits(actual.occupancy.miss, expected.occupancy.miss));
  EXPECT_TRUE(sameBits(actual.occupancy.clamp_min, expected.occupancy.clamp_min));
  EXPECT_TRUE(sameBits(actual.occupancy.clamp_max, expected.occupancy.clamp_max));
  EXPECT_TRUE(sameBits(actual.occupancy.threshold, expected.occupancy.threshold));
  EXPECT_EQ(actual.semantics, expected.semantics);
  EXPECT_EQ(actual.voxel_mean, expected.voxel_mean);
  EXPECT_EQ(actual.policy, StorePolicy::kGlobal);
}

/// Every saved layer of every region is bit-identical; layers that are not saved are clear.
void expectSameVoxels(const VoxelMap& expected, const VoxelMap& actual) {
  ASSERT_EQ(actual.store().size(), expected.store().size());
  const LayerSchema& schema = expected.store().schema();
  expected.store().forEachRegion([&](std::uint32_t slot, Vec3i coord) {
    const std::uint32_t other = actual.store().find(coord);
    ASSERT_NE(other, RegionStore::kNoSlot)
        << "region (" << coord.x << ", " << coord.y << ", " << coord.z << ") is missing";
    for (int l = 0; l < schema.size(); ++l) {
      const LayerSpec& spec = schema.at(l);
      const int other_layer = actual.store().schema().indexOf(spec.kind);
      ASSERT_GE(other_layer, 0);
      const std::size_t bytes = expected.store().layerRegionBytes(l);
      const std::byte* got = actual.store().layerBytes(other, other_layer);
      if (spec.saved) {
        EXPECT_EQ(std::memcmp(got, expected.store().layerBytes(slot, l), bytes), 0)
            << "layer " << spec.name << " of region (" << coord.x << ", " << coord.y << ", "
            << coord.z << ")";
      } else {
        EXPECT_TRUE(std::all_of(got, got + bytes, [](std::byte b) { return b == std::byte{0}; }))
            << "layer " << spec.name << " is not fresh";
      }
    }
  });
}

Error expectLoadFails(const std::string& path) {
  auto loaded = loadMap(path);
  EXPECT_FALSE(loaded.has_value());
  if (loaded.has_value()) {
    return Error{};
  }
  EXPECT_NE(loaded.error().message.find(path), std::string::npos) << loaded.error().message;
  return loaded.error();
}

// ---- round trips ----

class MapFileRoundTrip : public ::testing::TestWithParam<std::tuple<Semantics, bool>> {};

TEST_P(MapFileRoundTrip, KeepsEveryParameterVoxelAndInfoString) {
  // Arrange
  const auto [semantics, voxel_mean] = GetParam();
  TempDir dir;
  const std::string path = dir.file("map.rmap");
  const VoxelMap map = filledMap(semantics, voxel_mean);

  // Act
  ASSERT_TRUE(saveMap(map, path).has_value());
  auto loaded = loadMap(path);

  // Assert
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  expectSameParameters(map.config(), loaded->config());
  EXPECT_TRUE(loaded->store().schema() == map.config().schema());
  EXPECT_EQ(loaded->scanMarkLayer() >= 0, semantics == Semantics::kPerScan);
  EXPECT_EQ(loaded->meanLayer() >= 0, voxel_mean);
  expectSameVoxels(map, *loaded);
  EXPECT_EQ(loaded->info(), map.info());
  EXPECT_EQ(loaded->store().capacity(), kRegions.size());
}

INSTANTIATE_TEST_SUITE_P(AllSchemas, MapFileRoundTrip,
                         ::testing::Combine(::testing::Values(Semantics::kPerRay,
                                                              Semantics::kPerScan),
                                            ::testing::Bool()));

TEST(MapFile, RoundTripsAnIntegratedMap) {
  // Arrange: a real integration (default 32^3 regions) on both sides of the origin.
  for (const Semantics semantics : {Semantics::kPerRay, Semantics::kPerScan}) {
    MapConfig config;
    config.semantics = semantics;
    config.memory_budget_bytes = std::uint64_t{64} << 20;
    VoxelMap map = test::makeMap(config);
    auto backend = test::cpuBackend(map, 1);
    const std::vector<Ray> rays = test::cubeRoomRays(config.geometry.resolution, 20);
    test::integrate(map, *backend, rays);
    TempDir dir;
    const std::string path = dir.file("room.rmap");

    // Act
    ASSERT_TRUE(saveMap(map, path).has_value());
    auto loaded = loadMap(path);

    // Assert
    ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
    expectSameVoxels(map, *loaded);
    const MapSummary a = map.summarise();
    const MapSummary b = loaded->summarise();
    EXPECT_EQ(b.regions, 8u);
    EXPECT_EQ(b.voxels_occupied, a.voxels_occupied);
    EXPECT_EQ(b.voxels_free, a.voxels_free);
    EXPECT_GT(b.voxels_occupied, 0u);
  }
}

TEST(MapFile, NonDefaultParametersSurvive) {
  // Arrange
  MapConfig config;
  config.geometry.resolution = 0.037;
  config.geometry.region_voxels = 16;
  config.occupancy.hit = logOdds(0.83);
  config.occupancy.miss = logOdds(0.31);
  config.occupancy.clamp_min = -1.2345f;
  config.occupancy.clamp_max = 2.71828f;
  config.occupancy.threshold = logOdds(0.61);
  config.semantics = Semantics::kPerScan;
  config.voxel_mean = false;
  config.memory_budget_bytes = std::uint64_t{1} << 24;
  VoxelMap map = test::makeMap(config);
  fillRegion(map, {2, -3, 4}, 5);
  map.setInfo("tool", "raymap 0.1.0");
  TempDir dir;
  const std::string path = dir.file("params.rmap");

  // Act
  ASSERT_TRUE(saveMap(map, path).has_value());
  auto header = readMapHeader(path);
  auto loaded = loadMap(path);

  // Assert
  ASSERT_TRUE(header.has_value()) << header.error().message;
  EXPECT_EQ(header->format_version, kMapFormatVersion);
  expectSameParameters(config, header->config);
  EXPECT_EQ(header->saved_layers, std::vector<LayerKind>{LayerKind::kOccupancy});
  EXPECT_EQ(header->region_count, 1u);
  EXPECT_EQ(header->config.capacityRegions(), 1u);
  ASSERT_EQ(header->info.size(), 1u);
  EXPECT_EQ(header->info[0].second, "raymap 0.1.0");
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  expectSameParameters(config, loaded->config());
  expectSameVoxels(map, *loaded);
}

TEST(MapFile, HeaderListsTheSavedLayersWithoutScanMarks) {
  // Arrange
  const VoxelMap map = filledMap(Semantics::kPerScan, true);
  TempDir dir;
  const std::string path = dir.file("layers.rmap");
  ASSERT_TRUE(saveMap(map, path).has_value());

  // Act
  auto header = readMapHeader(path);

  // Assert
  ASSERT_TRUE(header.has_value()) << header.error().message;
  EXPECT_EQ(header->saved_layers,
            (std::vector<LayerKind>{LayerKind::kOccupancy, LayerKind::kVoxelMean}));
  EXPECT_EQ(header->region_count, kRegions.size());
  EXPECT_EQ(header->info, map.info());
}

TEST(MapFile, LoadsIntoABiggerBudgetThatKeepsGrowing) {
  // Arrange
  const VoxelMap map = filledMap(Semantics::kPerRay, true);
  TempDir dir;
  const std::string path = dir.file("grow.rmap");
  ASSERT_TRUE(saveMap(map, path).has_value());
  const std::uint64_t per_region =
      map.config().schema().bytesPerRegion(map.geometry().voxelsPerRegion());
  MapLoadOptions options;
  options.memory_budget_bytes = 100 * per_region + 7;

  // Act
  auto loaded = loadMap(path, options);

  // Assert
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  EXPECT_EQ(loaded->store().capacity(), 100u);
  EXPECT_EQ(loaded->config().capacityRegions(), 100u);
  expectSameVoxels(map, *loaded);
  EXPECT_TRUE(loaded->acquireRegion({40, 40, 40}).has_value());
}

TEST(MapFile, ABudgetSmallerThanTheFileStillLoadsEveryRegion) {
  // Arrange
  const VoxelMap map = filledMap(Semantics::kPerRay, true);
  TempDir dir;
  const std::string path = dir.file("small-budget.rmap");
  ASSERT_TRUE(saveMap(map, path).has_value());
  MapLoadOptions options;
  options.memory_budget_bytes = 1;

  // Act
  auto loaded = loadMap(path, options);

  // Assert
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  EXPECT_EQ(loaded->store().capacity(), kRegions.size());
  expectSameVoxels(map, *loaded);
}

TEST(MapFile, RoundTripsAnEmptyMap) {
  // Arrange
  const VoxelMap map = test::makeMap(smallConfig(Semantics::kPerRay, true));
  TempDir dir;
  const std::string path = dir.file("empty.rmap");

  // Act
  ASSERT_TRUE(saveMap(map, path).has_value());
  auto loaded = loadMap(path);

  // Assert
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  EXPECT_EQ(loaded->store().size(), 0u);
  EXPECT_EQ(loaded->store().capacity(), 1u);
}

TEST(MapFile, EqualMapsGiveEqualFilesWhateverTheirRegionOrder) {
  // Arrange
  VoxelMap forward = test::makeMap(smallConfig(Semantics::kPerRay, true));
  VoxelMap backward = test::makeMap(smallConfig(Semantics::kPerRay, true));
  for (std::size_t i = 0; i < kRegions.size(); ++i) {
    fillRegion(forward, kRegions[i], static_cast<std::uint32_t>(i));
    const std::size_t j = kRegions.size() - 1 - i;
    fillRegion(backward, kRegions[j], static_cast<std::uint32_t>(j));
  }
  TempDir dir;

  // Act
  ASSERT_TRUE(saveMap(forward, dir.file("a.rmap")).has_value());
  ASSERT_TRUE(saveMap(backward, dir.file("b.rmap")).has_value());

  // Assert
  EXPECT_EQ(readFileBytes(dir.file("a.rmap")), readFileBytes(dir.file("b.rmap")));
}

TEST(MapFile, MostlyUnobservedRegionsTakeLittleSpace) {
  // Arrange: the cube room fills 8 default regions (32^3 voxels, 12 bytes each in memory).
  MapConfig config;
  config.memory_budget_bytes = std::uint64_t{64} << 20;
  VoxelMap map = test::makeMap(config);
  auto backend = test::cpuBackend(map, 1);
  test::integrate(map, *backend, test::cubeRoomRays(config.geometry.resolution, 20));
  for (std::int32_t x = 5; x < 15; ++x) {  // and ten regions nobody observed
    ASSERT_TRUE(map.store().findOrCreate({x, 9, 9}).has_value());
  }
  TempDir dir;
  const std::string path = dir.file("room.rmap");
  const std::uint64_t in_memory = std::uint64_t{map.store().size()} * 32768u * 12u;

  // Act
  ASSERT_TRUE(saveMap(map, path).has_value());
  const std::uint64_t on_disk = std::filesystem::file_size(path);

  // Assert: well under 2% of the voxels' size; an unobserved region shrinks more than 200-fold.
  EXPECT_LT(on_disk * 50u, in_memory) << on_disk << " bytes on disk for " << in_memory;
  const std::vector<std::size_t> blocks = blockOffsets(readFileBytes(path));
  ASSERT_EQ(blocks.size(), 18u);
  const std::vector<std::uint8_t> bytes = readFileBytes(path);
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    const auto x = static_cast<std::int32_t>(getLe(bytes, blocks[i] + 4, 4));
    if (x >= 5) {
      EXPECT_LT(getLe(bytes, blocks[i] + 20, 4) * 200u, 32768u * 12u) << "block " << i;
    }
  }
}

// ---- saving ----

TEST(MapFile, SavingOverAnExistingMapReplacesIt) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("map.rmap");
  const VoxelMap first = filledMap(Semantics::kPerRay, false);
  VoxelMap second = test::makeMap(smallConfig(Semantics::kPerRay, true));
  fillRegion(second, {9, 9, 9}, 99);
  ASSERT_TRUE(saveMap(first, path).has_value());

  // Act
  ASSERT_TRUE(saveMap(second, path).has_value());

  // Assert: the new map, and no temporary file left beside it.
  auto loaded = loadMap(path);
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  expectSameVoxels(second, *loaded);
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    names.push_back(entry.path().filename().string());
  }
  EXPECT_EQ(names, std::vector<std::string>{"map.rmap"});
}

TEST(MapFile, SavingIntoAMissingDirectoryFailsAndLeavesNothing) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("missing/map.rmap");
  const VoxelMap map = filledMap(Semantics::kPerRay, true);

  // Act
  auto saved = saveMap(map, path);

  // Assert
  ASSERT_FALSE(saved.has_value());
  EXPECT_EQ(saved.error().code, ErrorCode::kIo);
  EXPECT_NE(saved.error().message.find(path), std::string::npos) << saved.error().message;
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(MapFile, RefusesInfoItThatCouldNotBeReadBack) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("map.rmap");
  VoxelMap map = filledMap(Semantics::kPerRay, true);
  map.setInfo("huge", std::string((std::size_t{1} << 20) + 1, 'x'));

  // Act
  auto saved = saveMap(map, path);

  // Assert
  ASSERT_FALSE(saved.has_value());
  EXPECT_EQ(saved.error().code, ErrorCode::kInvalidArgument);
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

// ---- loading bad files ----

/// A tiny map (4^3-voxel regions) whose file is small enough to damage at every byte.
class DamagedMapFile : public ::testing::Test {
 protected:
  void SetUp() override {
    MapConfig config = smallConfig(Semantics::kPerRay, true);
    config.geometry.region_voxels = 4;
    VoxelMap map = test::makeMap(config);
    fillRegion(map, {0, 0, 0}, 1);
    fillRegion(map, {-1, 2, -3}, 2);
    fillRegion(map, {4, 4, 4}, 3);
    map.setInfo("source", "test");
    ASSERT_TRUE(saveMap(map, good_path_).has_value());
    good_ = readFileBytes(good_path_);
    ASSERT_GT(good_.size(), 200u);
  }

  TempDir dir_;
  const std::string good_path_ = dir_.file("good.rmap");
  const std::string bad_path_ = dir_.file("bad.rmap");
  std::vector<std::uint8_t> good_;
};

TEST_F(DamagedMapFile, EveryTruncationFailsAsTruncated) {
  for (std::size_t size = 0; size < good_.size(); ++size) {
    // Arrange
    writeFileBytes(bad_path_,
                   std::vector<std::uint8_t>(good_.begin(),
                                             good_.begin() + static_cast<std::ptrdiff_t>(size)));

    // Act
    auto loaded = loadMap(bad_path_);
    auto header = readMapHeader(bad_path_);

    // Assert
    ASSERT_FALSE(loaded.has_value()) << "loaded a file cut to " << size << " bytes";
    EXPECT_EQ(loaded.error().code, size == 0 ? ErrorCode::kFormat : ErrorCode::kTruncated)
        << size << ": " << loaded.error().message;
    EXPECT_NE(loaded.error().message.find(bad_path_), std::string::npos);
    if (size < firstBlockOffset(good_)) {
      EXPECT_FALSE(header.has_value()) << size;
    }
  }
}

TEST_F(DamagedMapFile, ATruncatedRegionIsNamed) {
  // Arrange: cut in the middle of the last region block.
  const std::vector<std::size_t> blocks = blockOffsets(good_);
  ASSERT_EQ(blocks.size(), 3u);
  const std::size_t cut = blocks[2] + 40;
  writeFileBytes(bad_path_, std::vector<std::uint8_t>(
                                good_.begin(), good_.begin() + static_cast<std::ptrdiff_t>(cut)));

  // Act
  const Error error = expectLoadFails(bad_path_);

  // Assert
  EXPECT_EQ(error.code, ErrorCode::kTruncated);
  EXPECT_EQ(error.message,
            bad_path_ + ": truncated in region 3 of 3 (offset " + std::to_string(blocks[2]) + ")");
}

TEST_F(DamagedMapFile, EveryFlippedByteFails) {
  for (std::size_t at = 0; at < good_.size(); ++at) {
    // Arrange
    std::vector<std::uint8_t> bad = good_;
    bad[at] ^= 0xFFu;
    writeFileBytes(bad_path_, bad);

    // Act
    auto loaded = loadMap(bad_path_);

    // Assert
    ASSERT_FALSE(loaded.has_value()) << "loaded a file with byte " << at << " flipped";
    EXPECT_NE(loaded.error().message.find(bad_path_), std::string::npos);
  }
}

TEST_F(DamagedMapFile, AFlippedHeaderByteIsAHeaderChecksumMismatch) {
  // Arrange: a byte of the resolution.
  std::vector<std::uint8_t> bad = good_;
  bad[test::kMapPrefixBytes + 3] ^= 0x10u;
  writeFileBytes(bad_path_, bad);

  // Act
  const Error error = expectLoadFails(bad_path_);

  // Assert
  EXPECT_EQ(error.code, ErrorCode::kCorrupt);
  EXPECT_EQ(error.message, bad_path_ + ": header checksum mismatch");
}

TEST_F(DamagedMapFile, AFlippedPayloadByteNamesTheRegion) {
  // Arrange: a byte in the middle of region 2's compressed voxels.
  const std::vector<std::size_t> blocks = blockOffsets(good_);
  ASSERT_EQ(blocks.size(), 3u);
  std::vector<std::uint8_t> bad = good_;
  bad[blocks[1] + 32 + 10] ^= 0x01u;
  writeFileBytes(bad_path_, bad);

  // Act
  const Error error = expectLoadFails(bad_path_);

  // Assert
  EXPECT_EQ(error.code, ErrorCode::kCorrupt);
  EXPECT_EQ(error.message, bad_path_ + ": region 2 of 3 (offset " + std::to_string(blocks[1]) +
                               "): checksum mismatch");
}

TEST_F(DamagedMapFile, AFlippedChecksumIsACorruption) {
  // Arrange: the stored payload CRC of region 1 (block bytes 24..27).
  const std::vector<std::size_t> blocks = blockOffsets(good_);
  ASSERT_FALSE(blocks.empty());
  std::vector<std::uint8_t> bad = good_;
  bad[blocks[0] + 25] ^= 0x80u;
  writeFileBytes(bad_path_, bad);

  // Act
  const Error error = expectLoadFails(bad_path_);

  // Assert
  EXPECT_EQ(error.code, ErrorCode::kCorrupt);
  EXPECT_NE(error.message.find("region 1 of 3"), std::string::npos) << error.message;
  EXPECT_NE(error.message.find("checksum mismatch"), std::string::npos) << error.message;
}

TEST_F(DamagedMapFile, TrailingBytesAreACorruption) {
  // Arrange
  std::vector<std::uint8_t> bad = good_;
  bad.push_back(0);
  writeFileBytes(bad_path_, bad);

  // Act
  const Error error = expectLoadFails(bad_path_);

  // Assert
  EXPECT_EQ(error.code, ErrorCode::kCorrupt);
  EXPECT_NE(error.message.find("after the end marker"), std::string::npos) << error.message;
}

TEST_F(DamagedMapFile, ADuplicateRegionIsRejected) {
  // Arrange: region 2 gets region 1's coordinate, with every checksum made to match.
  const std::vector<std::size_t> blocks = blockOffsets(good_);
  ASSERT_EQ(blocks.size(), 3u);
  std::vector<std::uint8_t> bad = good_;
  std::copy_n(good_.begin() + static_cast<std::ptrdiff_t>(blocks[0] + 4), 12,
              bad.begin() + static_cast<std::ptrdiff_t>(blocks[1] + 4));
  putLe(bad, blocks[1] + 28, crc32(bad.data() + blocks[1], 28), 4);
  writeFileBytes(bad_path_, bad);

  // Act
  const Error error = expectLoadFails(bad_path_);

  // Assert
  EXPECT_EQ(error.code, ErrorCode::kCorrupt);
  EXPECT_NE(error.message.find("region 2 of 3"), std::string::npos) << error.message;
  EXPECT_NE(error.message.find("duplicate region"), std::string::npos) << error.message;
}

TEST_F(DamagedMapFile, AnUnknownLayerKindIsUnsupported) {
  // Arrange: the first layer's kind becomes 200, header checksum made to match.
  std::vector<std::uint8_t> bad = good_;
  ASSERT_EQ(getLe(bad, test::kMapPrefixBytes + kBodyLayerCount, 2), 2u);
  ASSERT_EQ(bad[test::kMapPrefixBytes + kBodyFirstLayerKind], 1u);
  bad[test::kMapPrefixBytes + kBodyFirstLayerKind] = 200;
  resealHeader(bad);
  writeFileBytes(bad_path_, bad);

  // Act
  const Error error = expectLoadFails(bad_path_);
  auto header = readMapHeader(bad_path_);

  // Assert
  EXPECT_EQ(error.code, ErrorCode::kUnsupported);
  EXPECT_NE(error.message.find("kind 200"), std::string::npos) << error.message;
  EXPECT_FALSE(header.has_value());
}

TEST_F(DamagedMapFile, AnImpossibleRegionCountFailsBeforeAllocating) {
  // Arrange: the header claims 2^29 regions (its checksum made to match).
  std::vector<std::uint8_t> bad = good_;
  const std::size_t count_at =
      test::kMapPrefixBytes + headerBodyBytes(bad) - kBodyModeAndNdtBytes - 8;
  ASSERT_EQ(getLe(bad, count_at, 8), 3u);
  putLe(bad, count_at, std::uint64_t{1} << 29, 8);
  resealHeader(bad);
  writeFileBytes(bad_path_, bad);

  // Act
  const Error error = expectLoadFails(bad_path_);

  // Assert
  EXPECT_EQ(error.code, ErrorCode::kTruncated);
  EXPECT_NE(error.message.find("536870912 regions"), std::string::npos) << error.message;
}

TEST_F(DamagedMapFile, ForgedHeaderFieldsNeverCrash) {
  // Every header byte set to 0, 0xFF and its value + 1, with the checksum made to match: the
  // parser must reject what is wrong without reading out of bounds or allocating wildly. Some
  // edits are harmless (a letter of an info string), so success is allowed, not required.
  const std::size_t body_end = test::kMapPrefixBytes + headerBodyBytes(good_);
  std::size_t failures = 0;
  for (std::size_t at = test::kMapPrefixBytes; at < body_end; ++at) {
    for (const int edit : {0, 1, 2}) {
      // Arrange
      std::vector<std::uint8_t> bad = good_;
      bad[at] = edit == 0
                    ? std::uint8_t{0}
                    : (edit == 1 ? std::uint8_t{0xFF} : static_cast<std::uint8_t>(bad[at] + 1u));
      if (bad[at] == good_[at]) {
        continue;
      }
      resealHeader(bad);
      writeFileBytes(bad_path_, bad);

      // Act
      auto loaded = loadMap(bad_path_);
      auto header = readMapHeader(bad_path_);

      // Assert
      if (!loaded.has_value()) {
        ++failures;
        EXPECT_NE(loaded.error().message.find(bad_path_), std::string::npos)
            << loaded.error().message;
      }
      if (!header.has_value()) {
        EXPECT_FALSE(loaded.has_value()) << "byte " << at;
      }
    }
  }
  EXPECT_GT(failures, 0u);
}

TEST_F(DamagedMapFile, AZlibStreamOfTheWrongSizeIsRejected) {
  // Arrange: region 3's payload becomes a valid zlib stream (one stored block) of 10 zero bytes,
  // with its sizes and checksums made to match.
  const std::vector<std::size_t> blocks = blockOffsets(good_);
  ASSERT_EQ(blocks.size(), 3u);
  const std::vector<std::uint8_t> stream = {0x78, 0x01, 0x01, 0x0A, 0x00, 0xF5, 0xFF,
                                            0,    0,    0,    0,    0,    0,    0,
                                            0,    0,    0,    0x00, 0x0A, 0x00, 0x01};
  std::vector<std::uint8_t> bad(good_.begin(),
                                good_.begin() + static_cast<std::ptrdiff_t>(blocks[2] + 32));
  bad.insert(bad.end(), stream.begin(), stream.end());
  bad.insert(bad.end(), 64, 0);  // stands in for the index and footer, never reached
  putLe(bad, blocks[2] + 20, stream.size(), 4);
  putLe(bad, blocks[2] + 24, crc32(stream.data(), stream.size()), 4);
  putLe(bad, blocks[2] + 28, crc32(bad.data() + blocks[2], 28), 4);
  writeFileBytes(bad_path_, bad);

  // Act
  const Error error = expectLoadFails(bad_path_);

  // Assert
  EXPECT_EQ(error.code, ErrorCode::kCorrupt);
  EXPECT_NE(error.message.find("region 3 of 3"), std::string::npos) << error.message;
  EXPECT_NE(error.message.find("do not decode"), std::string::npos) << error.message;
}

TEST_F(DamagedMapFile, AnOutOfRangeRegionCoordinateIsRejected) {
  // Arrange: region 1's x becomes INT32_MIN, block checksum made to match.
  const std::vector<std::size_t> blocks = blockOffsets(good_);
  ASSERT_FALSE(blocks.empty());
  std::vector<std::uint8_t> bad = good_;
  putLe(bad, blocks[0] + 4, 0x80000000u, 4);
  putLe(bad, blocks[0] + 28, crc32(bad.data() + blocks[0], 28), 4);
  writeFileBytes(bad_path_, bad);

  // Act
  const Error error = expectLoadFails(bad_path_);

  // Assert
  EXPECT_EQ(error.code, ErrorCode::kCorrupt);
  EXPECT_NE(error.message.find("out of range"), std::string::npos) << error.message;
}

TEST_F(DamagedMapFile, ANewerVersionIsUnsupported) {
  // Arrange: a header a newer writer sealed (its checksum covers the version).
  std::vector<std::uint8_t> bad = good_;
  putLe(bad, 8, 7, 4);
  resealHeader(bad);
  writeFileBytes(bad_path_, bad);

  // Act
  const Error error = expectLoadFails(bad_path_);
  auto header = readMapHeader(bad_path_);

  // Assert
  EXPECT_EQ(error.code, ErrorCode::kUnsupported);
  EXPECT_EQ(error.message, bad_path_ +
                               ": map format version 7 is newer than this raymap, which reads "
                               "versions 1 to 3");
  ASSERT_FALSE(header.has_value());
  EXPECT_EQ(header.error().message, error.message);
}

TEST_F(DamagedMapFile, AFlippedVersionByteIsDamageNotANewerVersion) {
  // Arrange: 3 -> 252 in the version field; the header checksum no longer matches.
  std::vector<std::uint8_t> bad = good_;
  bad[8] ^= 0xFF;
  writeFileBytes(bad_path_, bad);

  // Act
  const Error error = expectLoadFails(bad_path_);

  // Assert
  EXPECT_EQ(error.code, ErrorCode::kCorrupt);
  EXPECT_EQ(error.message, bad_path_ +
                               ": damaged header: its checksum does not match, and its version "
                               "field reads 252 (this raymap reads map format versions 1 to 3)");
}

TEST_F(DamagedMapFile, AVersionFarAheadIsMoreLikelyDamageThanNew) {
  // Arrange: a sealed header with version 252.
  std::vector<std::uint8_t> bad = good_;
  putLe(bad, 8, 252, 4);
  resealHeader(bad);
  writeFileBytes(bad_path_, bad);

  // Act
  const Error error = expectLoadFails(bad_path_);

  // Assert
  EXPECT_EQ(error.code, ErrorCode::kUnsupported);
  EXPECT_EQ(error.message,
            bad_path_ +
                ": unsupported map format version 252 (this raymap reads versions 1 to 3); a "
                "version this far ahead is more likely a damaged or foreign file than a newer "
                "raymap's");
}

TEST_F(DamagedMapFile, AWrongMagicIsNotAMap) {
  // Arrange
  std::vector<std::uint8_t> bad = good_;
  bad[0] = 'X';
  writeFileBytes(bad_path_, bad);

  // Act
  const Error error = expectLoadFails(bad_path_);

  // Assert
  EXPECT_EQ(error.code, ErrorCode::kFormat);
  EXPECT_NE(error.message.find("not a raymap map"), std::string::npos) << error.message;
}

TEST(MapFileLoad, ATextFileIsNotAMap) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("notes.txt");
  const std::string text = "ply\nformat ascii 1.0\nend_header\n";
  writeFileBytes(path, std::vector<std::uint8_t>(text.begin(), text.end()));

  // Act
  const Error error = expectLoadFails(path);

  // Assert
  EXPECT_EQ(error.code, ErrorCode::kFormat);
}

TEST(MapFileLoad, AnEmptyFileFails) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("empty.rmap");
  writeFileBytes(path, {});

  // Act
  const Error error = expectLoadFails(path);

  // Assert
  EXPECT_EQ(error.code, ErrorCode::kFormat);
  EXPECT_EQ(error.message, path + " is empty (0 bytes): not a raymap map file");
}

TEST(MapFileLoad, AMissingFileFails) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("nowhere.rmap");

  // Act
  const Error error = expectLoadFails(path);
  auto header = readMapHeader(path);

  // Assert
  EXPECT_EQ(error.code, ErrorCode::kIo);
  ASSERT_FALSE(header.has_value());
  EXPECT_EQ(header.error().code, ErrorCode::kIo);
}

TEST(MapFileLoad, ADirectoryFails) {
  // Arrange
  TempDir dir;

  // Act
  const Error error = expectLoadFails(dir.path().string());

  // Assert
  EXPECT_EQ(error.code, ErrorCode::kIo);
}

}  // namespace
}  // namespace raymap::io
