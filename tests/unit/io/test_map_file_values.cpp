// SPDX-License-Identifier: BSD-3-Clause
// Map files whose checksums are right but whose voxels hold values no writer makes (NaN, an
// infinity where a layer's numbers are finite): refused on load, naming the region, the layer
// and the voxel.
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <zlib.h>

#include "src/io/map_file.hpp"
#include "tests/support/file_bytes.hpp"
#include "tests/support/map_file_layout.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::io {
namespace {

using test::Bytes;
using test::crc32;
using test::getLe;
using test::putLe;
using test::readFileBytes;
using test::TempDir;
using test::writeFileBytes;

// ---- file bytes (docs/map-format.md) ----

/// The file with region block `block` (in file order) re-encoded after `edit` changed its
/// decoded voxel bytes, and every size, offset and checksum after it made to match, as a writer
/// would have written those voxels.
Bytes withEditedRegion(const Bytes& file, std::size_t block,
                       const std::function<void(Bytes& raw)>& edit) {
  const std::size_t footer = file.size() - test::kMapFooterBytes;
  const auto index = static_cast<std::size_t>(getLe(file, footer + 12, 8));
  std::size_t at = test::kMapPrefixBytes + static_cast<std::size_t>(getLe(file, 12, 4)) + 4;
  for (std::size_t b = 0; b < block; ++b) {
    at += test::kMapBlockHeaderBytes + static_cast<std::size_t>(getLe(file, at + 20, 4));
  }
  const auto raw_bytes = static_cast<std::size_t>(getLe(file, at + 16, 4));
  const auto packed_bytes = static_cast<std::size_t>(getLe(file, at + 20, 4));
  Bytes raw(raw_bytes);
  uLongf raw_size = static_cast<uLongf>(raw.size());
  EXPECT_EQ(::uncompress(raw.data(), &raw_size, file.data() + at + test::kMapBlockHeaderBytes,
                         static_cast<uLong>(packed_bytes)),
            Z_OK);
  edit(raw);
  Bytes packed(::compressBound(static_cast<uLong>(raw.size())));
  uLongf packed_size = static_cast<uLongf>(packed.size());
  EXPECT_EQ(::compress2(packed.data(), &packed_size, raw.data(), static_cast<uLong>(raw.size()),
                        Z_BEST_SPEED),
            Z_OK);
  packed.resize(packed_size);

  const std::size_t old_end = at + test::kMapBlockHeaderBytes + packed_bytes;
  Bytes out(file.begin(),
            file.begin() + static_cast<std::ptrdiff_t>(at + test::kMapBlockHeaderBytes));
  out.insert(out.end(), packed.begin(), packed.end());
  out.insert(out.end(), file.begin() + static_cast<std::ptrdiff_t>(old_end), file.end());
  putLe(out, at + 20, packed.size(), 4);
  putLe(out, at + 24, crc32(packed.data(), packed.size()), 4);
  putLe(out, at + 28, crc32(out.data() + at, 28), 4);
  // Blocks after this one moved: the index's offsets, its checksum, and the footer's pointer.
  const std::size_t shift = packed.size() - packed_bytes;  // modulo 2^64 for a shrink
  const std::size_t new_index = index + shift;
  const std::size_t new_footer = out.size() - test::kMapFooterBytes;
  const auto regions = static_cast<std::size_t>(getLe(out, new_footer + 4, 8));
  for (std::size_t i = 0; i < regions; ++i) {
    const std::size_t entry = new_index + 4 + i * test::kMapIndexEntryBytes + 12;
    const std::uint64_t offset = getLe(out, entry, 8);
    if (offset > at) {
      putLe(out, entry, offset + shift, 8);
    }
  }
  const std::size_t index_crc = new_index + 4 + regions * test::kMapIndexEntryBytes;
  putLe(out, index_crc, crc32(out.data() + new_index, index_crc - new_index), 4);
  putLe(out, new_footer + 12, new_index, 8);
  putLe(out, new_footer + 20, crc32(out.data() + new_footer, 20), 4);
  return out;
}

/// Stores `value` as voxel `voxel`'s word `word` of the layer that starts `layer_offset` bytes
/// into a region's decoded bytes (each 32-bit word of a layer is four byte planes of n voxels).
void putWord(Bytes& raw, std::size_t layer_offset, std::uint32_t voxels, std::uint32_t word,
             std::uint32_t voxel, float value) {
  const auto bits = std::bit_cast<std::uint32_t>(value);
  for (std::uint32_t b = 0; b < 4; ++b) {
    raw[layer_offset + (std::size_t{word} * 4 + b) * voxels + voxel] =
        static_cast<std::uint8_t>(bits >> (8 * b));
  }
}

// ---- the maps ----

struct BadValueCase {
  const char* name;
  MapConfig config;
  const char* layer;     ///< the layer's name in the file
  std::uint32_t word;    ///< which 32-bit word of the voxel
  float value;           ///< what the forged file holds there
  const char* expected;  ///< how the message describes the value
};

void PrintTo(const BadValueCase& c, std::ostream* os) { *os << c.name; }

MapConfig smallConfig(MapMode mode) {
  MapConfig config;
  config.geometry.resolution = 0.25;
  config.geometry.region_voxels = 4;
  config.memory_budget_bytes = std::uint64_t{1} << 22;
  config.mode = mode;
  return config;
}

std::vector<BadValueCase> badValueCases() {
  constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
  constexpr float kInf = std::numeric_limits<float>::infinity();
  MapConfig decay = smallConfig(MapMode::kOccupancy);
  decay.decay_rate = true;
  return {
      {"OccupancyNan", smallConfig(MapMode::kOccupancy), "occupancy", 0, kNan, "NaN"},
      {"OccupancyMinusInfinity", smallConfig(MapMode::kOccupancy), "occupancy", 0, -kInf, "-inf"},
      {"NdtMeanNan", smallConfig(MapMode::kNdtOm), "ndt", 1, kNan, "NaN"},
      {"NdtCovarianceInfinity", smallConfig(MapMode::kNdtOm), "ndt", 5, kInf, "inf"},
      {"IntensityVarianceNan", smallConfig(MapMode::kNdtTm), "intensity", 1, kNan, "NaN"},
      {"TraversalInfinity", decay, "traversal", 0, kInf, "inf"},
      {"TsdfDistanceNan", smallConfig(MapMode::kOccupancy).forTsdf(), "tsdf", 0, kNan, "NaN"},
      {"TsdfWeightInfinity", smallConfig(MapMode::kOccupancy).forTsdf(), "tsdf", 1, kInf, "inf"},
  };
}

class NonFiniteVoxel : public ::testing::TestWithParam<BadValueCase> {};

TEST_P(NonFiniteVoxel, IsRefusedNamingTheRegionLayerAndVoxel) {
  // Arrange: a saved map of two regions whose second region (in file order) gets the value.
  const BadValueCase& c = GetParam();
  TempDir dir;
  VoxelMap map = test::makeMap(c.config);
  ASSERT_TRUE(map.store().findOrCreate({0, 0, 0}).has_value());
  ASSERT_TRUE(map.store().findOrCreate({2, -1, 3}).has_value());
  const std::string good = dir.file("good.rmap");
  ASSERT_TRUE(saveMap(map, good).has_value());
  ASSERT_TRUE(loadMap(good).has_value());
  const std::uint32_t voxels = map.store().voxelsPerRegion();
  std::size_t layer_offset = 0;
  bool found = false;
  const auto header = readMapHeader(good);
  ASSERT_TRUE(header.has_value()) << header.error().message;
  for (const LayerKind kind : header->saved_layers) {
    const std::optional<LayerSpec> spec = layerSpec(kind);
    ASSERT_TRUE(spec.has_value());
    if (spec->name == c.layer) {
      found = true;
      break;
    }
    layer_offset += std::size_t{spec->bytes_per_voxel} * voxels;
  }
  ASSERT_TRUE(found) << c.layer;
  constexpr std::uint32_t kVoxel = 5;
  const std::string bad = dir.file("bad.rmap");
  writeFileBytes(bad, withEditedRegion(readFileBytes(good), 1, [&](Bytes& raw) {
                   putWord(raw, layer_offset, voxels, c.word, kVoxel, c.value);
                 }));
  const Vec3i region = map.regionCoordsInOrder()[1];
  const Vec3i voxel = map.voxelAt(region, kVoxel);

  // Act
  auto loaded = loadMap(bad);

  // Assert
  ASSERT_FALSE(loaded.has_value()) << "a forged " << c.name << " loaded";
  EXPECT_EQ(loaded.error().code, ErrorCode::kCorrupt);
  // snprintf rather than "(" + std::to_string(...): GCC 12 at -O3 reports a false -Wrestrict
  // overlap in the inlined string concatenation.
  const auto text = [](Vec3i v) {
    char buffer[64];
    std::snprintf(buffer, sizeof(buffer), "(%d, %d, %d)", static_cast<int>(v.x),
                  static_cast<int>(v.y), static_cast<int>(v.z));
    return std::string(buffer);
  };
  const std::string coords = text(region);
  const std::string voxel_coords = text(voxel);
  const std::string& message = loaded.error().message;
  EXPECT_EQ(message.rfind(bad + ": region " + coords, 0), 0u) << message;
  EXPECT_NE(message.find("layer '" + std::string(c.layer) + "'"), std::string::npos) << message;
  EXPECT_NE(message.find("voxel " + voxel_coords), std::string::npos) << message;
  EXPECT_NE(message.find(std::string(" ") + c.expected + " "), std::string::npos) << message;
}

INSTANTIATE_TEST_SUITE_P(EveryFloatLayer, NonFiniteVoxel, ::testing::ValuesIn(badValueCases()),
                         [](const ::testing::TestParamInfo<BadValueCase>& param_info) {
                           return std::string(param_info.param.name);
                         });

TEST(NonFiniteVoxel, PlusInfinityIsAnUnobservedOccupancyAndLoads) {
  // Arrange: +inf is how the occupancy layer says "unobserved" (its clear value).
  TempDir dir;
  VoxelMap map = test::makeMap(smallConfig(MapMode::kOccupancy));
  ASSERT_TRUE(map.store().findOrCreate({0, 0, 0}).has_value());
  const std::string good = dir.file("good.rmap");
  ASSERT_TRUE(saveMap(map, good).has_value());
  const std::string edited = dir.file("edited.rmap");
  writeFileBytes(edited, withEditedRegion(readFileBytes(good), 0, [&](Bytes& raw) {
                   putWord(raw, 0, map.store().voxelsPerRegion(), 0, 7, 1.5f);
                 }));

  // Act
  auto loaded = loadMap(edited);

  // Assert: the edit itself is a valid file (the helper keeps every checksum right).
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  EXPECT_EQ(loaded->state(loaded->voxelAt({0, 0, 0}, 7)), VoxelState::kOccupied);
  EXPECT_EQ(loaded->state(loaded->voxelAt({0, 0, 0}, 8)), VoxelState::kUnobserved);
}

}  // namespace
}  // namespace raymap::io
