// SPDX-License-Identifier: BSD-3-Clause
// TSDF maps through the raymap program: populate --mode tsdf with its parameters, info, the map
// file round trip, export --mode tsdf and tsdf-mesh (the surface of a simulated plane, where it
// should be), and the errors.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include <gtest/gtest.h>

#include "src/io/map_file.hpp"
#include "src/io/ply_header.hpp"
#include "tests/support/cli_runner.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"
#include "tests/support/tsdf_scenes.hpp"

namespace raymap::test {
namespace {

// The body of a binary PLY written by export --mode tsdf: 7 floats a point (x y z nx ny nz
// weight).
std::vector<float> plyFloats(const std::string& text) {
  const std::size_t body = text.find("end_header\n");
  if (body == std::string::npos) {
    return {};
  }
  std::vector<float> values((text.size() - body - 11) / 4);
  std::memcpy(values.data(), text.data() + body + 11, values.size() * 4);
  return values;
}

TEST(CliTsdf, PopulateInfoAndExportThePlanesSurface) {
  TempDir dir;
  const std::string rays = dir.file("plane.ply");
  const std::string map = dir.file("plane.rmap");
  const std::string ply = dir.file("surface.ply");
  const TsdfScene scene = planeScene(3000);
  writeRayCloud(rays, scene.rays);

  const RunResult populated =
      runRaymap({"populate", rays, "--output", map, "--mode", "tsdf", "--tsdf-truncation", "0.25",
                 "--tsdf-max-weight", "500", "--tsdf-dropoff", "0.05"});
  ASSERT_EQ(populated.exit_code, 0) << describe(populated);
  EXPECT_TRUE(contains(populated.out, "TSDF voxels updated")) << populated.out;
  const RunResult info = runRaymap({"info", map});
  ASSERT_EQ(info.exit_code, 0) << describe(info);
  EXPECT_TRUE(contains(info.out, "mode           tsdf")) << info.out;
  EXPECT_TRUE(
      contains(info.out, "tsdf           truncation 0.25 m, max weight 500, drop-off 0.05 m"))
      << info.out;
  EXPECT_TRUE(contains(info.out, "tsdf (8 B)")) << info.out;
  EXPECT_FALSE(contains(info.out, "occupancy      hit")) << info.out;

  // The file keeps the parameters and the field.
  auto loaded = io::loadMap(map);
  ASSERT_TRUE(loaded) << loaded.error().message;
  EXPECT_EQ(loaded->mode(), MapMode::kTsdf);
  EXPECT_EQ(loaded->config().tsdf.truncationMetres(0.1), 0.25);
  EXPECT_EQ(loaded->config().tsdf.max_weight, 500.0);
  EXPECT_EQ(loaded->config().tsdf.dropoffMetres(0.1), 0.05);
  EXPECT_LT(loaded->tsdf(loaded->voxelOf({0.05, 0.05, 0.45})).distance, 0.0f);
  EXPECT_GT(loaded->tsdf(loaded->voxelOf({0.05, 0.05, 0.65})).distance, 0.0f);

  const RunResult exported =
      runRaymap({"export", map, "--mode", "tsdf", "--min-weight", "20", "--ply", ply});
  ASSERT_EQ(exported.exit_code, 0) << describe(exported);
  EXPECT_TRUE(contains(exported.out, "TSDF surface points")) << exported.out;
  const std::string text = readFile(ply);
  EXPECT_TRUE(contains(text, "property float weight\n"));
  const std::vector<float> values = plyFloats(text);
  ASSERT_GT(values.size(), 7u * 100u);
  ASSERT_EQ(values.size() % 7, 0u);
  std::size_t up = 0;
  for (std::size_t i = 0; i < values.size(); i += 7) {
    // Within a quarter voxel of the plane z = 0.537 m, weights at least 20.
    EXPECT_NEAR(values[i + 2], 0.537f, 0.025f);
    EXPECT_GE(values[i + 6], 20.0f);
    up += values[i + 5] == 1.0f ? 1u : 0u;
  }
  // Nearly all crossings are between a voxel and the one above it (a few lie between
  // neighbours in the layer just above the plane, whose distance of 0.013 m averages to
  // either sign).
  std::printf("%zu of %zu crossings vertical\n", up, values.size() / 7);
  EXPECT_GE(up, values.size() / 7 * 9 / 10);
}

TEST(CliTsdf, ExportThePlanesSurfaceAsATriangleMesh) {
  TempDir dir;
  const std::string rays = dir.file("plane.ply");
  const std::string map = dir.file("plane.rmap");
  const std::string ply = dir.file("mesh.ply");
  writeRayCloud(rays, planeScene(3000).rays);
  ASSERT_EQ(runRaymap({"populate", rays, "--output", map, "--mode", "tsdf", "-q"}).exit_code, 0);

  const RunResult exported =
      runRaymap({"export", map, "--mode", "tsdf-mesh", "--min-weight", "20", "--ply", ply});
  ASSERT_EQ(exported.exit_code, 0) << describe(exported);
  EXPECT_TRUE(contains(exported.out, "TSDF surface mesh of")) << exported.out;
  const std::string text = readFile(ply);
  auto header = io::parsePlyHeader(std::string_view(text), ply);
  ASSERT_TRUE(header) << header.error().message;
  ASSERT_EQ(header->elements.size(), 2u);
  const io::PlyElement& vertex = header->elements[0];
  const io::PlyElement& face = header->elements[1];
  ASSERT_EQ(vertex.name, "vertex");
  ASSERT_EQ(vertex.properties.size(), 7u);  // x y z nx ny nz weight
  ASSERT_EQ(face.name, "face");
  ASSERT_TRUE(face.hasLists());
  ASSERT_GT(face.count, 200u);
  ASSERT_EQ(text.size(), header->header_bytes + vertex.count * 28 + face.count * 13);
  const char* body = text.data() + header->header_bytes;
  std::size_t up = 0;
  for (std::uint64_t i = 0; i < vertex.count; ++i) {
    float v[7];
    std::memcpy(v, body + i * 28, sizeof(v));
    EXPECT_NEAR(v[2], 0.537f, 0.025f);  // within a quarter voxel of the plane z = 0.537 m
    EXPECT_GE(v[6], 20.0f);
    up += v[5] > 0.9f ? 1u : 0u;  // the normal points up, towards the sensors
  }
  EXPECT_GE(up, vertex.count * 9 / 10);
  const char* faces = body + vertex.count * 28;
  for (std::uint64_t i = 0; i < face.count; ++i) {
    ASSERT_EQ(faces[i * 13], 3);
    std::int32_t index[3];
    std::memcpy(index, faces + i * 13 + 1, sizeof(index));
    for (const std::int32_t k : index) {
      ASSERT_GE(k, 0);
      ASSERT_LT(static_cast<std::uint64_t>(k), vertex.count);
    }
  }
}

TEST(CliTsdf, ErrorsNameTheOptionOrTheMapAndTheReason) {
  TempDir dir;
  const std::string rays = dir.file("plane.ply");
  writeRayCloud(rays, planeScene(50).rays);
  const std::string tsdf = dir.file("tsdf.rmap");
  const std::string plain = dir.file("plain.rmap");
  ASSERT_EQ(runRaymap({"populate", rays, "--output", tsdf, "--mode", "tsdf", "-q"}).exit_code, 0);
  ASSERT_EQ(runRaymap({"populate", rays, "--output", plain, "-q"}).exit_code, 0);

  const RunResult dropoff = runRaymap(
      {"populate", rays, "--output", dir.file("x.rmap"), "--mode", "tsdf", "--tsdf-dropoff", "1"});
  EXPECT_NE(dropoff.exit_code, 0);
  EXPECT_TRUE(contains(dropoff.err, "--tsdf-dropoff")) << dropoff.err;
  const RunResult scan = runRaymap(
      {"populate", rays, "--output", dir.file("x.rmap"), "--mode", "tsdf", "--semantics", "scan"});
  EXPECT_NE(scan.exit_code, 0);
  EXPECT_TRUE(contains(scan.err, "--semantics ray")) << scan.err;
  const RunResult stray =
      runRaymap({"populate", rays, "--output", dir.file("x.rmap"), "--tsdf-truncation", "0.3"});
  EXPECT_NE(stray.exit_code, 0);
  EXPECT_TRUE(contains(stray.err, "--tsdf-truncation applies only to populate --mode tsdf"))
      << stray.err;

  const RunResult no_layer =
      runRaymap({"export", plain, "--mode", "tsdf", "--ply", dir.file("x.ply")});
  EXPECT_NE(no_layer.exit_code, 0);
  EXPECT_TRUE(contains(no_layer.err, "no TSDF layer")) << no_layer.err;
  const RunResult occupied = runRaymap({"export", tsdf, "--ply", dir.file("x.ply")});
  EXPECT_NE(occupied.exit_code, 0);
  EXPECT_TRUE(contains(occupied.err, "no occupancy layer")) << occupied.err;
  const RunResult weight = runRaymap(
      {"export", plain, "--mode", "occupied", "--min-weight", "3", "--ply", dir.file("x.ply")});
  EXPECT_NE(weight.exit_code, 0);
  EXPECT_TRUE(contains(weight.err, "--min-weight applies only to --mode tsdf")) << weight.err;
  const RunResult mesh_of_plain =
      runRaymap({"export", plain, "--mode", "tsdf-mesh", "--ply", dir.file("x.ply")});
  EXPECT_NE(mesh_of_plain.exit_code, 0);
  EXPECT_TRUE(contains(mesh_of_plain.err, "no TSDF layer")) << mesh_of_plain.err;
  const RunResult mesh_threshold = runRaymap(
      {"export", tsdf, "--mode", "tsdf-mesh", "--threshold", "1", "--ply", dir.file("x.ply")});
  EXPECT_NE(mesh_threshold.exit_code, 0);
  EXPECT_TRUE(
      contains(mesh_threshold.err,
               "--threshold does not apply to --mode tsdf-mesh (its option is --min-weight)"))
      << mesh_threshold.err;
  const RunResult unknown =
      runRaymap({"export", tsdf, "--mode", "mesh", "--ply", dir.file("x.ply")});
  EXPECT_NE(unknown.exit_code, 0);
  EXPECT_TRUE(contains(unknown.err, "unknown mode 'mesh'")) << unknown.err;
  EXPECT_TRUE(contains(unknown.err, "tsdf-mesh")) << unknown.err;
  const RunResult heightmap = runRaymap({"heightmap", tsdf, "--csv", dir.file("h.csv")});
  EXPECT_NE(heightmap.exit_code, 0);
  EXPECT_TRUE(contains(heightmap.err, "occupancy")) << heightmap.err;
}

}  // namespace
}  // namespace raymap::test
