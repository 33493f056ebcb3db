// SPDX-License-Identifier: BSD-3-Clause
// openRaySource: ray clouds, point clouds with trajectories, field mapping, chunking, errors.
#include <cmath>
#include <numbers>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "src/io/ray_source.hpp"
#include "tests/support/ply_test_writer.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::io {
namespace {

using test::PlyEncoding;
using test::PlyTestElement;
using test::PlyTestFile;

::testing::AssertionResult startsWith(const std::string& text, const std::string& prefix) {
  if (text.rfind(prefix, 0) == 0) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure() << "'" << text << "' does not start with '" << prefix << "'";
}

/// The ray-cloud layout of the shared data plus alpha: vertex i has sample (i, -i, 0.5 i),
/// normal (1, 2, -0.25 i), time 0.5 i, intensity 10 i, scan i / 2, alpha 0 for every third.
PlyTestElement rayCloudVertices(int count) {
  PlyTestElement vertex{"vertex",
                        {{"double", "x", ""},
                         {"double", "y", ""},
                         {"double", "z", ""},
                         {"double", "time", ""},
                         {"float", "nx", ""},
                         {"float", "ny", ""},
                         {"float", "nz", ""},
                         {"float", "intensity", ""},
                         {"uint", "scan", ""},
                         {"uchar", "alpha", ""}}};
  for (int i = 0; i < count; ++i) {
    const double v = i;
    vertex.add({v, -v, 0.5 * v, 0.5 * v, 1, 2, -0.25 * v, 10 * v, static_cast<double>(i / 2),
                i % 3 == 0 ? 0.0 : 255.0});
  }
  return vertex;
}

std::string writeFile(const test::TempDir& dir, const std::string& name,
                      std::vector<PlyTestElement> elements,
                      PlyEncoding encoding = PlyEncoding::kBinaryLittleEndian, bool gzip = false) {
  PlyTestFile file;
  file.encoding = encoding;
  file.gzip = gzip;
  file.elements = std::move(elements);
  const std::string path = dir.file(name);
  test::writePly(path, file);
  return path;
}

/// Reads every ray, `chunk` at a time; fails the test on an error.
std::vector<Ray> readAll(RaySource& source, std::size_t chunk) {
  std::vector<Ray> all;
  std::vector<Ray> buffer(chunk);
  for (;;) {
    auto got = source.read(buffer);
    EXPECT_TRUE(got.has_value()) << (got ? "" : got.error().message);
    if (!got || *got == 0) {
      break;
    }
    EXPECT_LE(*got, chunk);
    all.insert(all.end(), buffer.begin(), buffer.begin() + static_cast<std::ptrdiff_t>(*got));
  }
  return all;
}

Result<std::vector<Ray>> readAllOrError(const std::string& path, const RaySourceOptions& options) {
  auto source = openRaySource(path, options);
  if (!source) {
    return Unexpected(std::move(source).error());
  }
  std::vector<Ray> all;
  std::vector<Ray> buffer(64);
  for (;;) {
    auto got = (*source)->read(buffer);
    if (!got) {
      return Unexpected(std::move(got).error());
    }
    if (*got == 0) {
      return all;
    }
    all.insert(all.end(), buffer.begin(), buffer.begin() + static_cast<std::ptrdiff_t>(*got));
  }
}

void expectSameRays(const std::vector<Ray>& a, const std::vector<Ray>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].origin, b[i].origin) << i;
    EXPECT_EQ(a[i].sample, b[i].sample) << i;
    EXPECT_EQ(a[i].time_s, b[i].time_s) << i;
    EXPECT_EQ(a[i].intensity, b[i].intensity) << i;
    EXPECT_EQ(a[i].flags, b[i].flags) << i;
    EXPECT_EQ(a[i].scan, b[i].scan) << i;
  }
}

// ---- ray clouds ----

class RayCloudEveryEncoding : public ::testing::TestWithParam<std::tuple<PlyEncoding, bool>> {};

TEST_P(RayCloudEveryEncoding, OriginIsSamplePlusNormal) {
  const auto [encoding, gzip] = GetParam();
  test::TempDir dir;
  const std::string path =
      writeFile(dir, gzip ? "cloud.ply.gz" : "cloud.ply", {rayCloudVertices(6)}, encoding, gzip);

  auto source = openRaySource(path, {});
  ASSERT_TRUE(source.has_value()) << source.error().message;
  const std::vector<Ray> rays = readAll(**source, 4);

  const RaySourceInfo& info = (*source)->info();
  EXPECT_EQ(info.path, path);
  EXPECT_EQ(info.format, test::toString(encoding));
  EXPECT_EQ(info.compressed, gzip);
  EXPECT_TRUE(info.ray_cloud);
  EXPECT_EQ(info.declared_rays, 6u);
  EXPECT_EQ(info.time_property, "time");
  EXPECT_TRUE(info.has_scan);
  EXPECT_TRUE(info.has_intensity);
  EXPECT_TRUE(info.has_alpha);
  EXPECT_DOUBLE_EQ((*source)->progress(), 1.0);
  ASSERT_EQ(rays.size(), 6u);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const double v = static_cast<double>(i);
    EXPECT_EQ(rays[i].sample, (Vec3d{v, -v, 0.5 * v})) << i;
    EXPECT_EQ(rays[i].origin, (Vec3d{v + 1, 2 - v, 0.25 * v})) << i;
    EXPECT_EQ(rays[i].time_s, 0.5 * v);
    EXPECT_EQ(rays[i].intensity, static_cast<float>(10 * v));
    EXPECT_EQ(rays[i].scan, i / 2);
    EXPECT_EQ(rays[i].flags, i % 3 == 0 ? kRayNoReturn : 0u) << "alpha 0 means no return";
  }
}

INSTANTIATE_TEST_SUITE_P(
    Encodings, RayCloudEveryEncoding,
    ::testing::Combine(::testing::Values(PlyEncoding::kAscii, PlyEncoding::kBinaryLittleEndian,
                                         PlyEncoding::kBinaryBigEndian),
                       ::testing::Bool()),
    [](const ::testing::TestParamInfo<std::tuple<PlyEncoding, bool>>& param_info) {
      return std::string(test::toString(std::get<0>(param_info.param))) +
             (std::get<1>(param_info.param) ? "_gz" : "");
    });

TEST(RaySource, PclNormalNamesUppercaseAxesAndNoOptionalFields) {
  test::TempDir dir;
  PlyTestElement vertex{"vertex",
                        {{"float", "normal_z", ""},
                         {"float", "X", ""},
                         {"float", "normal_x", ""},
                         {"float", "Y", ""},
                         {"float", "normal_y", ""},
                         {"float", "Z", ""}}};
  vertex.add({3, 1, 1, 2, 2, 3});
  const std::string path = writeFile(dir, "pcl.ply", {vertex}, PlyEncoding::kAscii);

  auto source = openRaySource(path, {});
  ASSERT_TRUE(source.has_value()) << source.error().message;
  const std::vector<Ray> rays = readAll(**source, 8);

  ASSERT_EQ(rays.size(), 1u);
  EXPECT_EQ(rays[0].sample, (Vec3d{1, 2, 3}));
  EXPECT_EQ(rays[0].origin, (Vec3d{2, 4, 6}));
  EXPECT_EQ(rays[0].time_s, 0.0);
  EXPECT_EQ(rays[0].scan, 0u);
  EXPECT_EQ(rays[0].flags, 0u);
  const RaySourceInfo& info = (*source)->info();
  EXPECT_TRUE(info.time_property.empty());
  EXPECT_FALSE(info.has_scan || info.has_intensity || info.has_alpha);
}

TEST(RaySource, ScanIndexComesFromTimeAndPeriodWithoutScanProperty) {
  test::TempDir dir;
  PlyTestElement vertex{"vertex",
                        {{"float", "x", ""},
                         {"float", "y", ""},
                         {"float", "z", ""},
                         {"float", "nx", ""},
                         {"float", "ny", ""},
                         {"float", "nz", ""},
                         {"double", "timestamp", ""}}};
  for (const double t : {10.0, 10.125, 10.25, 10.75, 11.0}) {
    vertex.add({1, 1, 1, 0, 0, 1, t});
  }
  const std::string path = writeFile(dir, "timed.ply", {vertex});
  RaySourceOptions quarter;
  quarter.scan_period_s = 0.25;
  RaySourceOptions none;
  none.scan_period_s = 0.0;

  const auto by_period = readAllOrError(path, quarter);
  const auto one_scan = readAllOrError(path, none);

  ASSERT_TRUE(by_period.has_value()) << by_period.error().message;
  ASSERT_TRUE(one_scan.has_value()) << one_scan.error().message;
  std::vector<std::uint64_t> scans;
  for (const Ray& ray : *by_period) {
    scans.push_back(ray.scan);
  }
  EXPECT_EQ(scans, (std::vector<std::uint64_t>{0, 0, 1, 3, 4}));
  for (const Ray& ray : *one_scan) {
    EXPECT_EQ(ray.scan, 0u);
  }
}

TEST(RaySource, TimeFieldsFollowTheirPriority) {
  test::TempDir dir;
  PlyTestElement vertex{"vertex",
                        {{"float", "x", ""},
                         {"float", "y", ""},
                         {"float", "z", ""},
                         {"float", "nx", ""},
                         {"float", "ny", ""},
                         {"float", "nz", ""},
                         {"double", "time", ""},
                         {"double", "OffsetTime", ""},
                         {"double", "GpsTime", ""}}};
  vertex.add({0, 0, 0, 0, 0, 1, 1.0, 2.0, 3.0});
  const std::string path = writeFile(dir, "times.ply", {vertex});

  auto source = openRaySource(path, {});
  ASSERT_TRUE(source.has_value()) << source.error().message;
  const std::vector<Ray> rays = readAll(**source, 1);

  EXPECT_EQ((*source)->info().time_property, "GpsTime");
  ASSERT_EQ(rays.size(), 1u);
  EXPECT_EQ(rays[0].time_s, 3.0);
}

TEST(RaySource, IntegerCoordinatesAreTakenAsPlainNumbers) {
  test::TempDir dir;
  PlyTestElement vertex{"vertex",
                        {{"int", "x", ""},
                         {"short", "y", ""},
                         {"char", "z", ""},
                         {"uint", "time", ""},
                         {"int", "nx", ""},
                         {"int", "ny", ""},
                         {"int", "nz", ""}}};
  vertex.add({100000, -300, -5, 4000000000.0, 1, 0, 0});
  const std::string path = writeFile(dir, "ints.ply", {vertex}, PlyEncoding::kBinaryBigEndian);

  const auto rays = readAllOrError(path, {});

  ASSERT_TRUE(rays.has_value()) << rays.error().message;
  ASSERT_EQ(rays->size(), 1u);
  EXPECT_EQ((*rays)[0].sample, (Vec3d{100000, -300, -5}));
  EXPECT_EQ((*rays)[0].origin, (Vec3d{100001, -300, -5}));
  EXPECT_EQ((*rays)[0].time_s, 4000000000.0);
}

TEST(RaySource, ElementsBeforeVertexAreSkipped) {
  test::TempDir dir;
  PlyTestElement camera{"camera", {{"float", "k", "uint"}, {"uchar", "id", ""}}};
  camera.add({4, 1, 2, 3, 4, 9});
  camera.add({0, 8});
  PlyTestElement face{"face", {{"int", "vertex_indices", "uchar"}}};
  face.add({3, 0, 1, 2});
  for (const PlyEncoding encoding : {PlyEncoding::kAscii, PlyEncoding::kBinaryLittleEndian}) {
    const std::string path =
        writeFile(dir, "scene.ply", {camera, rayCloudVertices(3), face}, encoding);

    const auto rays = readAllOrError(path, {});

    ASSERT_TRUE(rays.has_value()) << rays.error().message;
    ASSERT_EQ(rays->size(), 3u);
    EXPECT_EQ((*rays)[2].sample, (Vec3d{2, -2, 1}));
  }
}

// ---- point clouds with a trajectory ----

PlyTestElement timedPoints(std::initializer_list<double> times) {
  PlyTestElement vertex{
      "vertex",
      {{"double", "offset_time", ""}, {"float", "x", ""}, {"float", "y", ""}, {"float", "z", ""}}};
  for (const double t : times) {
    vertex.add({t, 5, 6, 7});
  }
  return vertex;
}

PlyTestElement xyzOnly() {
  PlyTestElement vertex{"vertex", {{"float", "x", ""}, {"float", "y", ""}, {"float", "z", ""}}};
  vertex.add({1, 2, 3});
  return vertex;
}

std::string writeText(const test::TempDir& dir, const std::string& name, const std::string& text) {
  const std::string path = dir.file(name);
  test::writeBytes(path, text);
  return path;
}

TEST(RaySource, PointCloudOriginsFollowTheTrajectoryPlusOffset) {
  test::TempDir dir;
  const std::string path = writeFile(dir, "points.ply", {timedPoints({0.5, 1.0, 1.75, 2.0})});
  RaySourceOptions options;
  options.trajectory_path = writeText(dir, "path.txt", "0 0 0 0\n1 2 0 0\n2 2 2 0\n");
  options.sensor_offset = {0, 0, 0.25};  // no orientations: added as is

  auto source = openRaySource(path, options);
  ASSERT_TRUE(source.has_value()) << source.error().message;
  const std::vector<Ray> rays = readAll(**source, 3);

  EXPECT_FALSE((*source)->info().ray_cloud);
  EXPECT_EQ((*source)->info().time_property, "offset_time");
  ASSERT_EQ(rays.size(), 4u);
  EXPECT_EQ(rays[0].origin, (Vec3d{1, 0, 0.25}));
  EXPECT_EQ(rays[1].origin, (Vec3d{2, 0, 0.25}));
  EXPECT_EQ(rays[2].origin, (Vec3d{2, 1.5, 0.25}));
  EXPECT_EQ(rays[3].origin, (Vec3d{2, 2, 0.25}));
  EXPECT_EQ(rays[2].sample, (Vec3d{5, 6, 7}));
  EXPECT_EQ(rays[2].time_s, 1.75);
}

TEST(RaySource, SensorOffsetIsRotatedByTheTrajectoryOrientation) {
  test::TempDir dir;
  const std::string path = writeFile(dir, "points.ply", {timedPoints({0.0, 0.5, 1.0})});
  // Body turned 90 degrees about z throughout (qw = qz = sqrt(1/2)), moving along x.
  const double c = std::sqrt(0.5);
  RaySourceOptions options;
  options.trajectory_path = writeText(dir, "posed.txt",
                                      "time x y z qw qx qy qz\n0 0 0 0 " + std::to_string(c) +
                                          " 0 0 " + std::to_string(c) + "\n1 4 0 0 " +
                                          std::to_string(c) + " 0 0 " + std::to_string(c) + "\n");
  options.sensor_offset = {1, 0, 0.5};  // body frame: 1 m forward, 0.5 m up

  const auto rays = readAllOrError(path, options);

  ASSERT_TRUE(rays.has_value()) << rays.error().message;
  ASSERT_EQ(rays->size(), 3u);
  const Vec3d expected[] = {{0, 1, 0.5}, {2, 1, 0.5}, {4, 1, 0.5}};  // forward is world +y
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_NEAR((*rays)[i].origin.x, expected[i].x, 1e-12) << i;
    EXPECT_NEAR((*rays)[i].origin.y, expected[i].y, 1e-12) << i;
    EXPECT_NEAR((*rays)[i].origin.z, expected[i].z, 1e-12) << i;
  }
}

TEST(RaySource, TrajectoryNotCoveringThePointsNamesBothFiles) {
  test::TempDir dir;
  const std::string path = writeFile(dir, "late.ply", {timedPoints({1.0, 2.0, 2.5})});
  RaySourceOptions options;
  options.trajectory_path = writeText(dir, "short.txt", "0 0 0 0\n2 1 1 1\n");

  const auto rays = readAllOrError(path, options);

  ASSERT_FALSE(rays.has_value());
  EXPECT_EQ(rays.error().message, path + ": point at time 2.5 is outside the trajectory " +
                                      options.trajectory_path + " [0, 2] (vertex 3)");
}

TEST(RaySource, PointCloudWithoutTrajectoryAsksForOne) {
  test::TempDir dir;
  const std::string path = writeFile(dir, "bare.ply", {timedPoints({0.0})});

  const auto source = openRaySource(path, {});

  ASSERT_FALSE(source.has_value());
  EXPECT_EQ(source.error().message,
            path +
                " has no per-point sensor vector (nx ny nz); give a trajectory with "
                "source.trajectory");
}

TEST(RaySource, RayCloudWithATrajectoryIsAnErrorNamingBothFiles) {
  // A ray cloud carries its origins: a trajectory would be ignored, so it is refused instead.
  test::TempDir dir;
  const std::string path = writeFile(dir, "rays.ply", {rayCloudVertices(3)});
  RaySourceOptions options;
  options.trajectory_path = writeText(dir, "path.txt", "0 0 0 0\n2 1 1 1\n");

  const auto source = openRaySource(path, options);

  ASSERT_FALSE(source.has_value());
  EXPECT_EQ(source.error().code, ErrorCode::kInvalidArgument);
  EXPECT_EQ(source.error().message,
            path +
                " is a ray cloud: its vertices hold the vector to the sensor (nx ny nz), so "
                "the trajectory " +
                options.trajectory_path +
                " would not be used: leave source.trajectory out (it is for point clouds)");
}

TEST(RaySource, PointCloudWithoutTimeCannotUseATrajectory) {
  test::TempDir dir;
  const std::string path = writeFile(dir, "timeless.ply", {xyzOnly()});
  RaySourceOptions options;
  options.trajectory_path = writeText(dir, "t.txt", "0 0 0 0\n");

  const auto source = openRaySource(path, options);

  ASSERT_FALSE(source.has_value());
  EXPECT_TRUE(
      startsWith(source.error().message, path + ": a point cloud needs a per-point time property"));
}

// ---- bad files ----

TEST(RaySource, MissingCoordinateIsNamed) {
  test::TempDir dir;
  PlyTestElement vertex{"vertex", {{"float", "x", ""}, {"float", "z", ""}, {"float", "nx", ""}}};
  vertex.add({1, 2, 3});
  const std::string path = writeFile(dir, "no_y.ply", {vertex});

  const auto source = openRaySource(path, {});

  ASSERT_FALSE(source.has_value());
  EXPECT_EQ(source.error().code, ErrorCode::kFormat);
  EXPECT_EQ(source.error().message,
            path + ": the vertex element has no 'y' property (x, y, z needed)");
}

TEST(RaySource, PartialNormalIsNamed) {
  test::TempDir dir;
  PlyTestElement vertex{"vertex",
                        {{"float", "x", ""},
                         {"float", "y", ""},
                         {"float", "z", ""},
                         {"float", "nx", ""},
                         {"float", "nz", ""}}};
  vertex.add({1, 2, 3, 4, 5});
  const std::string path = writeFile(dir, "half.ply", {vertex});

  const auto source = openRaySource(path, {});

  ASSERT_FALSE(source.has_value());
  EXPECT_EQ(source.error().message, path + ": the vertex element has 'nx' but no 'ny' property");
}

TEST(RaySource, BadHeaderErrorStartsWithThePath) {
  test::TempDir dir;
  const std::string path = dir.file("bad.ply");
  test::writeBytes(path, "ply\nformat binary_middle_endian 1.0\nend_header\n");

  const auto source = openRaySource(path, {});

  ASSERT_FALSE(source.has_value());
  EXPECT_EQ(source.error().message, path + ": line 2: unknown format 'binary_middle_endian'");
}

TEST(RaySource, TruncatedDataFailsAndKeepsFailing) {
  test::TempDir dir;
  PlyTestFile file;
  file.elements = {rayCloudVertices(10)};
  file.truncate_data_to = 2 * 53 + 20;  // 53-byte records: two whole, the third cut
  const std::string path = dir.file("cut.ply");
  test::writePly(path, file);
  auto source = openRaySource(path, {});
  ASSERT_TRUE(source.has_value()) << source.error().message;
  std::vector<Ray> rays(2);

  const auto first = (*source)->read(rays);
  const auto second = (*source)->read(rays);
  const auto third = (*source)->read(rays);

  ASSERT_TRUE(first.has_value()) << first.error().message;
  EXPECT_EQ(*first, 2u);
  ASSERT_FALSE(second.has_value());
  EXPECT_EQ(second.error().code, ErrorCode::kTruncated);
  EXPECT_EQ(second.error().message,
            path + ": truncated: header declares 10 vertices, data ends in vertex 3");
  ASSERT_FALSE(third.has_value());
  EXPECT_EQ(third.error().message, second.error().message);
}

TEST(RaySource, NonIntegerScanIsRejected) {
  test::TempDir dir;
  PlyTestElement vertex{"vertex",
                        {{"float", "x", ""},
                         {"float", "y", ""},
                         {"float", "z", ""},
                         {"float", "nx", ""},
                         {"float", "ny", ""},
                         {"float", "nz", ""},
                         {"float", "scan", ""}}};
  vertex.add({0, 0, 0, 1, 1, 1, 1});
  vertex.add({0, 0, 0, 1, 1, 1, 1.5});
  const std::string path = writeFile(dir, "scan.ply", {vertex});

  const auto rays = readAllOrError(path, {});

  ASSERT_FALSE(rays.has_value());
  EXPECT_EQ(rays.error().message,
            path + ": vertex 2: scan index 1.5 is not a non-negative integer");
}

// ---- chunking and streaming ----

TEST(RaySource, ReadingSevenAtATimeEqualsOneBigRead) {
  test::TempDir dir;
  const std::string path = writeFile(dir, "many.ply.gz", {rayCloudVertices(1000)},
                                     PlyEncoding::kBinaryBigEndian, /*gzip=*/true);
  auto whole = openRaySource(path, {});
  auto pieces = openRaySource(path, {});
  ASSERT_TRUE(whole.has_value() && pieces.has_value());

  const std::vector<Ray> at_once = readAll(**whole, 5000);
  const std::vector<Ray> by_seven = readAll(**pieces, 7);

  EXPECT_EQ(at_once.size(), 1000u);
  expectSameRays(at_once, by_seven);
}

TEST(RaySource, FileLargerThanTheBufferStreamsInChunks) {
  test::TempDir dir;
  constexpr int kVertices = 300000;  // 28 bytes each: 8.4 MB, eight times the read buffer
  PlyTestElement vertex{"vertex",
                        {{"float", "x", ""},
                         {"float", "y", ""},
                         {"float", "z", ""},
                         {"float", "nx", ""},
                         {"float", "ny", ""},
                         {"float", "nz", ""},
                         {"uint", "scan", ""}}};
  vertex.values.reserve(std::size_t{7} * kVertices);
  for (int i = 0; i < kVertices; ++i) {
    const double v = i;
    vertex.add({v, 0.5 * v, 1, 0, 0, -1, static_cast<double>(i / 1000)});
  }
  const std::string path = writeFile(dir, "big.ply", {vertex});
  auto source = openRaySource(path, {});
  ASSERT_TRUE(source.has_value()) << source.error().message;
  std::vector<Ray> chunk(10000);
  std::size_t total = 0;
  std::size_t calls = 0;
  double last_progress = 0.0;
  bool in_order = true;
  bool progress_monotonic = true;

  for (;;) {
    const auto got = (*source)->read(chunk);
    ASSERT_TRUE(got.has_value()) << got.error().message;
    if (*got == 0) {
      break;
    }
    for (std::size_t i = 0; i < *got; ++i) {
      const double v = static_cast<double>(total + i);
      in_order = in_order && chunk[i].sample.x == v && chunk[i].origin.z == 0.0 &&
                 chunk[i].scan == (total + i) / 1000;
    }
    const double progress = (*source)->progress();
    progress_monotonic = progress_monotonic && progress >= last_progress;
    last_progress = progress;
    total += *got;
    ++calls;
  }

  EXPECT_EQ(total, std::size_t{kVertices});
  EXPECT_EQ(calls, 30u);
  EXPECT_TRUE(in_order);
  EXPECT_TRUE(progress_monotonic);
  EXPECT_DOUBLE_EQ((*source)->progress(), 1.0);
}

// ---- the shared real data (skipped when absent) ----

TEST(RaySourceSharedData, OusterRayCloud) {
  const auto data = test::sharedDataDir();
  if (data.empty()) {
    GTEST_SKIP() << "shared data not present";
  }
  const std::string path = (data / "ouster" / "ouster_os1_lb_n3_raycloud.ply.gz").string();
  auto source = openRaySource(path, {});
  ASSERT_TRUE(source.has_value()) << source.error().message;

  const std::vector<Ray> rays = readAll(**source, 65536);

  EXPECT_TRUE((*source)->info().compressed);
  EXPECT_TRUE((*source)->info().ray_cloud);
  ASSERT_EQ(rays.size(), 322536u);
  std::vector<std::uint64_t> per_scan(3, 0);
  for (const Ray& ray : rays) {
    ASSERT_LT(ray.scan, 3u);
    ++per_scan[ray.scan];
  }
  EXPECT_EQ(per_scan, (std::vector<std::uint64_t>{107647, 107357, 107532}));
  EXPECT_NEAR(rays[0].origin.x, 0.0, 1e-3);
  EXPECT_NEAR(rays[0].origin.y, 0.0, 1e-3);
  EXPECT_NEAR(rays[0].origin.z, 0.036, 1e-3);
}

TEST(RaySourceSharedData, ThreeDtkPointsWithTrajectory) {
  const auto data = test::sharedDataDir();
  if (data.empty()) {
    GTEST_SKIP() << "shared data not present";
  }
  RaySourceOptions options;
  options.trajectory_path = (data / "3dtk" / "3dtk_trajectory.txt").string();
  const auto trajectory_rays =
      readAllOrError((data / "3dtk" / "3dtk_points.ply.gz").string(), options);
  const Vec3d positions[] = {{0.0, 0.0, 0.0},
                             {1.567960000, 0.036331000, -0.090831500},
                             {3.377860000, 0.080500800, -0.156539000}};

  ASSERT_TRUE(trajectory_rays.has_value()) << trajectory_rays.error().message;
  ASSERT_EQ(trajectory_rays->size(), 244080u);
  std::vector<std::uint64_t> per_time(3, 0);
  bool exact = true;
  for (const Ray& ray : *trajectory_rays) {
    const auto index = static_cast<std::size_t>(ray.time_s);
    ASSERT_EQ(static_cast<double>(index), ray.time_s);
    ASSERT_LT(index, 3u);
    ++per_time[index];
    exact = exact && ray.origin == positions[index];
  }
  EXPECT_TRUE(exact) << "origins must equal the trajectory positions at times 0, 1, 2";
  EXPECT_EQ(per_time, (std::vector<std::uint64_t>{81360, 81360, 81360}));
}

}  // namespace
}  // namespace raymap::io
