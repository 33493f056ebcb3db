// SPDX-License-Identifier: BSD-3-Clause
// Map export to PLY: header, points at voxel means or centres, probabilities, counts, modes.
#include <bit>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "kernels/common/voxel_mean.h"
#include "src/io/map_export.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::io {
namespace {

using test::TempDir;

struct PlyPoint {
  float x = 0.0f;
  float y = 0.0f;
  float z = 0.0f;
  float probability = 0.0f;
  std::uint32_t count = 0;
};

struct ParsedPly {
  std::vector<std::string> header_lines;
  std::vector<PlyPoint> points;
  std::size_t trailing_bytes = 0;
};

std::uint32_t u32At(const std::vector<std::uint8_t>& bytes, std::size_t at) {
  return std::uint32_t{bytes.at(at)} | std::uint32_t{bytes.at(at + 1)} << 8 |
         std::uint32_t{bytes.at(at + 2)} << 16 | std::uint32_t{bytes.at(at + 3)} << 24;
}

/// Parses the file by hand: header lines up to end_header, then 20-byte little-endian records.
ParsedPly parsePly(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::vector<std::uint8_t> bytes(std::istreambuf_iterator<char>(in), {});
  const std::string text(bytes.begin(), bytes.end());
  ParsedPly ply;
  const std::string end = "end_header\n";
  const std::size_t end_at = text.find(end);
  if (end_at == std::string::npos) {
    ADD_FAILURE() << "no end_header in " << path;
    return ply;
  }
  std::size_t begin = 0;
  while (begin < end_at + end.size()) {
    const std::size_t eol = text.find('\n', begin);
    ply.header_lines.push_back(text.substr(begin, eol - begin));
    begin = eol + 1;
  }
  std::size_t at = end_at + end.size();
  for (; at + 20 <= bytes.size(); at += 20) {
    PlyPoint p;
    p.x = std::bit_cast<float>(u32At(bytes, at));
    p.y = std::bit_cast<float>(u32At(bytes, at + 4));
    p.z = std::bit_cast<float>(u32At(bytes, at + 8));
    p.probability = std::bit_cast<float>(u32At(bytes, at + 12));
    p.count = u32At(bytes, at + 16);
    ply.points.push_back(p);
  }
  ply.trailing_bytes = bytes.size() - at;
  return ply;
}

void expectValidHeader(const ParsedPly& ply, std::size_t points) {
  const std::vector<std::string> expected_tail = {"element vertex " + std::to_string(points),
                                                  "property float x",
                                                  "property float y",
                                                  "property float z",
                                                  "property float probability",
                                                  "property uint count",
                                                  "end_header"};
  ASSERT_GE(ply.header_lines.size(), 2 + expected_tail.size());
  EXPECT_EQ(ply.header_lines[0], "ply");
  EXPECT_EQ(ply.header_lines[1], "format binary_little_endian 1.0");
  for (std::size_t i = 2; i + expected_tail.size() < ply.header_lines.size(); ++i) {
    EXPECT_EQ(ply.header_lines[i].rfind("comment ", 0), 0u) << ply.header_lines[i];
  }
  const std::size_t tail = ply.header_lines.size() - expected_tail.size();
  for (std::size_t i = 0; i < expected_tail.size(); ++i) {
    EXPECT_EQ(ply.header_lines[tail + i], expected_tail[i]);
  }
  EXPECT_EQ(ply.points.size(), points);
  EXPECT_EQ(ply.trailing_bytes, 0u);
}

constexpr double kResolution = 0.25;
constexpr std::int32_t kRegionVoxels = 8;

MapConfig exportConfig(bool voxel_mean) {
  MapConfig config;
  config.geometry.resolution = kResolution;
  config.geometry.region_voxels = kRegionVoxels;
  config.voxel_mean = voxel_mean;
  config.memory_budget_bytes = std::uint64_t{1} << 22;
  return config;
}

/// Sets one voxel's occupancy and (when the map has the layer) mean.
void setVoxel(VoxelMap& map, Vec3i voxel, float value, rm_voxel_mean mean = {0u, 0u}) {
  const std::int32_t n = map.geometry().region_voxels;
  const Vec3i region = map.regionOfVoxel(voxel);
  const auto slot = map.store().findOrCreate(region);
  ASSERT_TRUE(slot.has_value());
  const Vec3i local = voxel - Vec3i{region.x * n, region.y * n, region.z * n};
  const auto index = static_cast<std::size_t>(local.x + n * (local.y + n * local.z));
  map.store().layerData<float>(*slot, map.occupancyLayer())[index] = value;
  if (map.meanLayer() >= 0) {
    map.store().layerData<rm_voxel_mean>(*slot, map.meanLayer())[index] = mean;
  }
}

/// World position (metres) of a voxel-local mean, computed as the exporter documents it.
Vec3d atMean(const VoxelMap& map, Vec3i voxel, rm_voxel_mean mean) {
  const rm_vec3f local = rm_mean_decode(mean.packed, mean.count);
  return map.voxelMinCorner(voxel) + Vec3d{static_cast<double>(local.x),
                                           static_cast<double>(local.y),
                                           static_cast<double>(local.z)} *
                                         kResolution;
}

void expectPoint(const PlyPoint& got, Vec3d p_world, float value, std::uint32_t count) {
  EXPECT_EQ(got.x, static_cast<float>(p_world.x));
  EXPECT_EQ(got.y, static_cast<float>(p_world.y));
  EXPECT_EQ(got.z, static_cast<float>(p_world.z));
  EXPECT_EQ(got.probability, static_cast<float>(probability(value)));
  EXPECT_EQ(got.count, count);
}

/// A map with one voxel of each kind, in two regions (one at negative coordinates). Voxels are
/// listed in export order (regions by z, y, x; voxels by index).
struct Scene {
  VoxelMap map;
  Vec3i occupied_with_mean{-3, -5, -2};  // region (-1, -1, -1)
  rm_voxel_mean occupied_mean{rm_mean_encode(rm_vec3f_make(0.1f, 0.9f, 0.25f)), 7u};
  Vec3i occupied_no_mean{1, 2, 3};  // region (0, 0, 0)
  Vec3i free_with_mean{2, 2, 3};    // a hit once, then cleared
  rm_voxel_mean free_mean{rm_mean_encode(rm_vec3f_make(1.0f, 0.0f, 0.5f)), 2u};
  Vec3i free_no_mean{4, 6, 7};
  float occupied_value = 2.5f;
  float free_value = -1.5f;
};

Scene makeScene(bool voxel_mean) {
  Scene s{test::makeMap(exportConfig(voxel_mean))};
  setVoxel(s.map, s.occupied_with_mean, s.occupied_value, s.occupied_mean);
  setVoxel(s.map, s.occupied_no_mean, s.occupied_value);
  setVoxel(s.map, s.free_with_mean, s.free_value, s.free_mean);
  setVoxel(s.map, s.free_no_mean, s.free_value);
  return s;
}

TEST(MapExport, OccupiedVoxelsAreAtTheirMeansOrCentres) {
  // Arrange
  Scene s = makeScene(true);
  TempDir dir;
  const std::string path = dir.file("occupied.ply");

  // Act
  auto written = exportPly(s.map, ExportMode::kOccupied, path);

  // Assert
  ASSERT_TRUE(written.has_value()) << written.error().message;
  EXPECT_EQ(*written, 2u);
  const ParsedPly ply = parsePly(path);
  expectValidHeader(ply, 2);
  ASSERT_EQ(ply.points.size(), 2u);
  expectPoint(ply.points[0], atMean(s.map, s.occupied_with_mean, s.occupied_mean), s.occupied_value,
              7u);
  expectPoint(ply.points[1], s.map.voxelCentre(s.occupied_no_mean), s.occupied_value, 0u);
  // The mean really is off-centre, near (0.1, 0.9, 0.25) of the voxel.
  EXPECT_NEAR(ply.points[0].x, -3 * kResolution + 0.1 * kResolution, 1e-3);
  EXPECT_NEAR(ply.points[0].y, -5 * kResolution + 0.9 * kResolution, 1e-3);
}

TEST(MapExport, FreeVoxelsAreAtTheirCentres) {
  // Arrange
  Scene s = makeScene(true);
  TempDir dir;
  const std::string path = dir.file("free.ply");

  // Act
  auto written = exportPly(s.map, ExportMode::kFree, path);

  // Assert
  ASSERT_TRUE(written.has_value()) << written.error().message;
  EXPECT_EQ(*written, 2u);
  const ParsedPly ply = parsePly(path);
  expectValidHeader(ply, 2);
  ASSERT_EQ(ply.points.size(), 2u);
  expectPoint(ply.points[0], s.map.voxelCentre(s.free_with_mean), s.free_value, 2u);
  expectPoint(ply.points[1], s.map.voxelCentre(s.free_no_mean), s.free_value, 0u);
}

TEST(MapExport, MeanModeExportsEveryVoxelWithSamples) {
  // Arrange
  Scene s = makeScene(true);
  TempDir dir;
  const std::string path = dir.file("mean.ply");

  // Act
  auto written = exportPly(s.map, ExportMode::kMean, path);

  // Assert
  ASSERT_TRUE(written.has_value()) << written.error().message;
  EXPECT_EQ(*written, 2u);
  const ParsedPly ply = parsePly(path);
  expectValidHeader(ply, 2);
  ASSERT_EQ(ply.points.size(), 2u);
  expectPoint(ply.points[0], atMean(s.map, s.occupied_with_mean, s.occupied_mean), s.occupied_value,
              7u);
  expectPoint(ply.points[1], atMean(s.map, s.free_with_mean, s.free_mean), s.free_value, 2u);
}

TEST(MapExport, WithoutVoxelMeansOccupiedVoxelsAreAtCentres) {
  // Arrange
  Scene s = makeScene(false);
  TempDir dir;
  const std::string occupied = dir.file("occupied.ply");
  const std::string mean = dir.file("mean.ply");

  // Act
  auto written = exportPly(s.map, ExportMode::kOccupied, occupied);
  auto written_mean = exportPly(s.map, ExportMode::kMean, mean);

  // Assert
  ASSERT_TRUE(written.has_value()) << written.error().message;
  const ParsedPly ply = parsePly(occupied);
  expectValidHeader(ply, 2);
  ASSERT_EQ(ply.points.size(), 2u);
  expectPoint(ply.points[0], s.map.voxelCentre(s.occupied_with_mean), s.occupied_value, 0u);
  expectPoint(ply.points[1], s.map.voxelCentre(s.occupied_no_mean), s.occupied_value, 0u);
  ASSERT_TRUE(written_mean.has_value()) << written_mean.error().message;
  EXPECT_EQ(*written_mean, 0u);
  expectValidHeader(parsePly(mean), 0);
}

TEST(MapExport, AnIntegratedRoomExportsItsWalls) {
  // Arrange: every wall voxel of the cube room is hit once, at its centre.
  MapConfig config;
  config.memory_budget_bytes = std::uint64_t{64} << 20;
  VoxelMap map = test::makeMap(config);
  auto backend = test::cpuBackend(map, 1);
  const std::vector<Ray> rays = test::cubeRoomRays(config.geometry.resolution, 6);
  test::integrate(map, *backend, rays);
  TempDir dir;
  const std::string path = dir.file("room.ply");

  // Act
  auto written = exportPly(map, ExportMode::kOccupied, path);

  // Assert
  ASSERT_TRUE(written.has_value()) << written.error().message;
  EXPECT_EQ(*written, map.summarise().voxels_occupied);
  EXPECT_EQ(*written, rays.size());
  const ParsedPly ply = parsePly(path);
  expectValidHeader(ply, rays.size());
  for (const PlyPoint& p : ply.points) {
    EXPECT_EQ(p.count, 1u);
    EXPECT_GT(p.probability, 0.5f);
    // The mean of one sample at a voxel centre is the centre, to the 1/1023 quantisation.
    const Vec3i voxel =
        map.voxelOf({static_cast<double>(p.x), static_cast<double>(p.y), static_cast<double>(p.z)});
    const Vec3d centre = map.voxelCentre(voxel);
    EXPECT_NEAR(p.x, centre.x, 1e-3);
    EXPECT_NEAR(p.y, centre.y, 1e-3);
    EXPECT_NEAR(p.z, centre.z, 1e-3);
  }
}

TEST(MapExport, AnEmptyMapGivesAValidEmptyCloud) {
  // Arrange
  const VoxelMap map = test::makeMap(exportConfig(true));
  TempDir dir;
  const std::string path = dir.file("empty.ply");

  // Act
  auto written = exportPly(map, ExportMode::kOccupied, path);

  // Assert
  ASSERT_TRUE(written.has_value()) << written.error().message;
  EXPECT_EQ(*written, 0u);
  expectValidHeader(parsePly(path), 0);
}

TEST(MapExport, AnUnwritablePathFailsAndLeavesNothing) {
  // Arrange
  Scene s = makeScene(true);
  TempDir dir;
  const std::string path = dir.file("missing/out.ply");

  // Act
  auto written = exportPly(s.map, ExportMode::kOccupied, path);

  // Assert
  ASSERT_FALSE(written.has_value());
  EXPECT_NE(written.error().message.find(path), std::string::npos) << written.error().message;
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(MapExport, ModesRoundTripThroughTheirNames) {
  for (const ExportMode mode : {ExportMode::kOccupied, ExportMode::kFree, ExportMode::kMean}) {
    // Act
    auto parsed = exportModeFromString(toString(mode));

    // Assert
    ASSERT_TRUE(parsed.has_value());
    EXPECT_EQ(*parsed, mode);
  }
  auto bad = exportModeFromString("occupancy");
  ASSERT_FALSE(bad.has_value());
  EXPECT_EQ(bad.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(bad.error().message.find("'occupancy'"), std::string::npos);
}

}  // namespace
}  // namespace raymap::io
