// SPDX-License-Identifier: BSD-3-Clause
// NDT maps through the raymap program: populate --mode ndt-om / ndt-tm, info, and export as
// ellipsoids and as oriented points, checked against a wall whose position and normal are known.
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/cli_runner.hpp"
#include "tests/support/json_doc.hpp"
#include "tests/support/ply_test_writer.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::test {
namespace {

// The wall: the plane x = kWallX (the middle of voxel column 30 at 0.1 m), seen from a sensor at
// (0, 0, 1), samples on a 2 cm grid over y in [-0.5, 0.5), z in [0.5, 1.5).
constexpr double kWallX = 3.05;
// Floats of a PLY against a double: the ellipsoids' minimum half-axis is 0.05 voxel = 5 mm.
constexpr double kOnWallTolerance = 0.006;

std::vector<Ray> wallRays() {
  std::vector<Ray> rays;
  for (int i = 0; i < 50; ++i) {
    for (int j = 0; j < 50; ++j) {
      Ray ray;
      ray.origin = Vec3d{0.0, 0.0, 1.0};
      ray.sample = Vec3d{kWallX, -0.5 + 0.02 * i + 0.01, 0.5 + 0.02 * j + 0.01};
      ray.intensity = static_cast<float>(10 + (i + j) % 7);
      rays.push_back(ray);
    }
  }
  return rays;
}

/// The same wall without an intensity property (float x y z nx ny nz: a ray cloud).
void writeRayCloudWithoutIntensity(const std::string& path) {
  PlyTestFile file;
  PlyTestElement vertex("vertex", {{"float", "x", ""},
                                   {"float", "y", ""},
                                   {"float", "z", ""},
                                   {"float", "nx", ""},
                                   {"float", "ny", ""},
                                   {"float", "nz", ""}});
  for (const Ray& ray : wallRays()) {
    const Vec3d to_sensor = ray.origin - ray.sample;
    vertex.add({ray.sample.x, ray.sample.y, ray.sample.z, to_sensor.x, to_sensor.y, to_sensor.z});
  }
  file.elements.push_back(vertex);
  writePly(path, file);
}

/// A binary little-endian PLY as the exports write it: header lines and the data bytes.
struct PlyFile {
  std::vector<std::string> header;
  std::string data;

  std::optional<std::uint64_t> count(const std::string& element) const {
    const std::string prefix = "element " + element + " ";
    for (const std::string& line : header) {
      if (line.rfind(prefix, 0) == 0) {
        return std::stoull(line.substr(prefix.size()));
      }
    }
    return std::nullopt;
  }
  double f32(std::size_t at) const {
    std::uint32_t bits = 0;
    for (int i = 0; i < 4; ++i) {
      bits |= std::uint32_t{static_cast<unsigned char>(data.at(at + static_cast<std::size_t>(i)))}
              << (8 * i);
    }
    return static_cast<double>(std::bit_cast<float>(bits));
  }
  std::uint32_t u32(std::size_t at) const {
    return std::bit_cast<std::uint32_t>(static_cast<float>(f32(at)));
  }
};

std::optional<PlyFile> readPly(const std::string& path) {
  const std::string bytes = readFile(path);
  const std::string end = "end_header\n";
  const std::size_t header_end = bytes.find(end);
  if (bytes.rfind("ply\nformat binary_little_endian 1.0\n", 0) != 0 ||
      header_end == std::string::npos) {
    return std::nullopt;
  }
  PlyFile ply;
  std::size_t at = 0;
  while (at < header_end) {
    const std::size_t eol = bytes.find('\n', at);
    ply.header.push_back(bytes.substr(at, eol - at));
    at = eol + 1;
  }
  ply.data = bytes.substr(header_end + end.size());
  return ply;
}

std::optional<double> jsonNumberAt(const Json& root, const std::string& object,
                                   const std::string& key) {
  const Json* v = findPath(root, {object, key});
  return v != nullptr && v->is_number() ? std::optional(v->get<double>()) : std::nullopt;
}

class CliNdt : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    writeRayCloud(input_, wallRays());
    const RunResult populated =
        runRaymap({"populate", input_, "--output", map_, "--mode", GetParam(), "--resolution",
                   "0.1", "--ndt-sensor-noise", "0.02", "--ndt-sample-threshold", "5", "--quiet"});
    ASSERT_EQ(populated.exit_code, 0) << describe(populated);
  }

  TempDir dir_;
  const std::string input_ = dir_.file("wall.ply");
  const std::string map_ = dir_.file("wall.rmap");
};

TEST_P(CliNdt, InfoReportsTheModeLayersAndParameters) {
  // Act
  const RunResult text = runRaymap({"info", map_});
  const RunResult json = runRaymap({"info", "--json", map_});

  // Assert
  ASSERT_EQ(text.exit_code, 0) << describe(text);
  EXPECT_TRUE(contains(text.out, "mode           " + GetParam()));
  EXPECT_TRUE(contains(text.out, "ndt (40 B)"));
  EXPECT_TRUE(contains(text.out, "sensor noise 0.02 m"));
  EXPECT_TRUE(contains(text.out, "sample threshold 5"));
  EXPECT_TRUE(contains(text.out, "adaptation rate 0.2 (from miss probability)"));
  ASSERT_EQ(json.exit_code, 0) << describe(json);
  const std::optional<Json> root = parseJson(json.out);
  ASSERT_TRUE(root.has_value());
  EXPECT_EQ(root->value("mode", ""), GetParam());
  EXPECT_EQ(jsonNumberAt(*root, "ndt", "sensor_noise_m"), 0.02);
  EXPECT_EQ(jsonNumberAt(*root, "ndt", "sample_threshold"), 5.0);
  // Derived from the float log-odds miss, so 0.2 to float precision.
  EXPECT_NEAR(jsonNumberAt(*root, "ndt", "adaptation_rate").value_or(-1), 0.2, 1e-6);
  const Json* layers = findPath(*root, {"layer_details"});
  ASSERT_NE(layers, nullptr);
  const std::size_t expected_layers = GetParam() == "ndt-tm" ? 5u : 3u;  // + occupancy, mean
  ASSERT_TRUE(layers->is_array());
  ASSERT_EQ(layers->size(), expected_layers);
  EXPECT_EQ((*layers)[2].value("bytes_per_voxel", -1), 40);
}

TEST_P(CliNdt, PointsLieOnTheWallWithItsNormalAndEllipsoidsSurroundThem) {
  // Arrange
  const std::string points_ply = dir_.file("points.ply");
  const std::string mesh_ply = dir_.file("mesh.ply");
  const std::string colour = GetParam() == "ndt-tm" ? "permeability" : "height";

  // Act
  const RunResult points =
      runRaymap({"export", map_, "--mode", "ndt-points", "--ply", points_ply, "--quiet"});
  const RunResult mesh = runRaymap(
      {"export", map_, "--mode", "ndt", "--ply", mesh_ply, "--sigmas", "2", "--colour", colour});

  // Assert: points on the wall, normals along x, one per occupied wall voxel (10 x 10).
  ASSERT_EQ(points.exit_code, 0) << describe(points);
  ASSERT_EQ(mesh.exit_code, 0) << describe(mesh);
  const std::optional<PlyFile> p = readPly(points_ply);
  ASSERT_TRUE(p.has_value());
  const std::optional<std::uint64_t> n = p->count("vertex");
  ASSERT_TRUE(n.has_value());
  EXPECT_EQ(*n, 100u);
  constexpr std::size_t kPointBytes = 6 * 4 + 3 + 4;
  ASSERT_EQ(p->data.size(), *n * kPointBytes);
  for (std::size_t i = 0; i < *n; ++i) {
    const std::size_t at = i * kPointBytes;
    EXPECT_NEAR(p->f32(at), kWallX, kOnWallTolerance) << "point " << i;
    EXPECT_NEAR(std::abs(p->f32(at + 12)), 1.0, 1e-3) << "normal of point " << i;
    EXPECT_GE(p->f32(at + 20), 0.0) << "normal turned up";
    EXPECT_EQ(p->u32(at + 27), 25u) << "samples of point " << i;  // 5 x 5 per voxel
  }
  // The mesh: 42 vertices and 80 triangles per Gaussian; each ellipsoid centred on its point,
  // flat across the wall (x within the minimum half-axis) and within the voxel's 2-sigma spread.
  const std::optional<PlyFile> m = readPly(mesh_ply);
  ASSERT_TRUE(m.has_value());
  EXPECT_EQ(m->count("vertex"), std::optional<std::uint64_t>(*n * 42));
  EXPECT_EQ(m->count("face"), std::optional<std::uint64_t>(*n * 80));
  constexpr std::size_t kVertexBytes = 3 * 4 + 3;
  constexpr std::size_t kFaceBytes = 1 + 3 * 4;
  ASSERT_EQ(m->data.size(), *n * (42 * kVertexBytes + 80 * kFaceBytes));
  for (std::size_t e = 0; e < *n; ++e) {
    double centre[3] = {0, 0, 0};
    for (std::size_t v = 0; v < 42; ++v) {
      const std::size_t at = (e * 42 + v) * kVertexBytes;
      EXPECT_NEAR(m->f32(at), kWallX, kOnWallTolerance);
      for (std::size_t axis = 0; axis < 3; ++axis) {
        centre[axis] += m->f32(at + 4 * axis) / 42.0;
      }
    }
    for (std::size_t axis = 0; axis < 3; ++axis) {
      EXPECT_NEAR(centre[axis], p->f32(e * kPointBytes + 4 * axis), 1e-4) << "ellipsoid " << e;
    }
  }
  const std::size_t faces_at = *n * 42 * kVertexBytes;
  EXPECT_EQ(static_cast<unsigned char>(m->data[faces_at]), 3u);
  EXPECT_LT(m->u32(faces_at + 1), 42u);
  EXPECT_TRUE(contains(mesh.out, "wrote 100 NDT ellipsoids"));
}

INSTANTIATE_TEST_SUITE_P(BothModes, CliNdt, ::testing::Values("ndt-om", "ndt-tm"));

TEST(CliNdtErrors, NdtWithScanSemanticsIsAUsageError) {
  TempDir dir;
  const std::string input = dir.file("wall.ply");
  writeRayCloud(input, wallRays());
  const RunResult r = runRaymap({"populate", input, "--output", dir.file("m.rmap"), "--mode",
                                 "ndt-om", "--semantics", "scan", "--quiet"});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_TRUE(contains(r.err, "--mode ndt-om needs --semantics ray"));
}

TEST(CliNdtErrors, NdtOptionsWithoutAnNdtModeAndBadValuesAreNamed) {
  TempDir dir;
  const std::string input = dir.file("wall.ply");
  writeRayCloud(input, wallRays());
  const RunResult without =
      runRaymap({"populate", input, "--output", dir.file("m.rmap"), "--ndt-sensor-noise", "0.1"});
  const RunResult negative = runRaymap({"populate", input, "--output", dir.file("m.rmap"), "--mode",
                                        "ndt-tm", "--ndt-sensor-noise", "-1"});
  EXPECT_EQ(without.exit_code, 2) << describe(without);
  EXPECT_TRUE(
      contains(without.err, "--ndt-sensor-noise applies only to populate --mode ndt-om or ndt-tm"));
  EXPECT_EQ(negative.exit_code, 2) << describe(negative);
  EXPECT_TRUE(contains(negative.err, "--ndt-sensor-noise must be a positive distance"));
}

TEST(CliNdtErrors, NdtTmWarnsWhenTheInputHasNoIntensity) {
  TempDir dir;
  const std::string input = dir.file("plain.ply");
  writeRayCloudWithoutIntensity(input);
  const RunResult r =
      runRaymap({"populate", input, "--output", dir.file("m.rmap"), "--mode", "ndt-tm", "--quiet"});
  const RunResult om = runRaymap(
      {"populate", input, "--output", dir.file("om.rmap"), "--mode", "ndt-om", "--quiet"});
  EXPECT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(contains(r.err, "warning: " + input + " has no 'intensity' property"));
  EXPECT_EQ(om.exit_code, 0) << describe(om);
  EXPECT_EQ(om.err.find("intensity"), std::string::npos) << om.err;
}

TEST(CliNdtErrors, NdtExportOfAnOccupancyMapOrTmColourOfAnOmMapIsRefused) {
  TempDir dir;
  const std::string input = dir.file("wall.ply");
  writeRayCloud(input, wallRays());
  const std::string occupancy = dir.file("occupancy.rmap");
  const std::string om = dir.file("om.rmap");
  ASSERT_EQ(runRaymap({"populate", input, "--output", occupancy, "--quiet"}).exit_code, 0);
  ASSERT_EQ(runRaymap({"populate", input, "--output", om, "--mode", "ndt-om", "--quiet"}).exit_code,
            0);
  const RunResult plain =
      runRaymap({"export", occupancy, "--mode", "ndt", "--ply", dir.file("a.ply")});
  const RunResult colour = runRaymap(
      {"export", om, "--mode", "ndt", "--colour", "intensity", "--ply", dir.file("b.ply")});
  EXPECT_EQ(plain.exit_code, 1) << describe(plain);
  EXPECT_TRUE(contains(plain.err, occupancy + ": the map is an occupancy map without NDT"));
  EXPECT_EQ(colour.exit_code, 1) << describe(colour);
  EXPECT_TRUE(contains(colour.err, "colour by intensity needs an ndt-tm map"));
}

TEST(CliNdtBench, BenchMeasuresNdtAgainstOccupancyInTheSameJson) {
  TempDir dir;
  const std::string input = dir.file("wall.ply");
  writeRayCloud(input, wallRays());
  const RunResult ndt =
      runRaymap({"bench", input, "--mode", "ndt-tm", "--threads-list", "1", "--repeat", "1"});
  ASSERT_EQ(ndt.exit_code, 0) << describe(ndt);
  const std::optional<Json> root = parseJson(ndt.out);
  ASSERT_TRUE(root.has_value());
  const Json* runs = findPath(*root, {"runs"});
  ASSERT_NE(runs, nullptr);
  ASSERT_TRUE(runs->is_array());
  ASSERT_EQ(runs->size(), 1u);  // the default semantics list shrinks to "ray"
  EXPECT_EQ((*runs)[0].value("mode", ""), "ndt-tm");
  EXPECT_NE(findPath((*runs)[0], {"rays_per_second"}), nullptr);
}

}  // namespace
}  // namespace raymap::test
