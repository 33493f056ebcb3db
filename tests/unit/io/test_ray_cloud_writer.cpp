// SPDX-License-Identifier: BSD-3-Clause
// RayCloudWriter: header with the final vertex count, record layout, atomic appearance; and the
// AtomicFileWriter::patch it relies on.
#include <bit>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "src/io/atomic_file.hpp"
#include "src/io/ray_cloud_writer.hpp"
#include "src/io/ray_source.hpp"
#include "src/io/trajectory.hpp"
#include "tests/support/file_bytes.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/test_rays.hpp"

namespace raymap::io {
namespace {

using test::getLe;
using test::readFileBytes;
using test::TempDir;

constexpr std::size_t kRecordBytes = 53;

struct RayRecord {
  double x, y, z, time;
  float nx, ny, nz, intensity;
  std::uint32_t scan;
  std::uint8_t alpha;
};

struct ParsedCloud {
  std::vector<std::string> header_lines;
  std::size_t data_offset = 0;
  std::vector<std::uint8_t> bytes;
};

ParsedCloud parseCloud(const std::string& path) {
  ParsedCloud cloud;
  cloud.bytes = readFileBytes(path);
  const std::string text(cloud.bytes.begin(), cloud.bytes.end());
  const std::string end = "end_header\n";
  const std::size_t end_at = text.find(end);
  if (end_at == std::string::npos) {
    ADD_FAILURE() << "no end_header";
    return cloud;
  }
  cloud.data_offset = end_at + end.size();
  std::size_t begin = 0;
  while (begin < cloud.data_offset) {
    const std::size_t eol = text.find('\n', begin);
    cloud.header_lines.push_back(text.substr(begin, eol - begin));
    begin = eol + 1;
  }
  return cloud;
}

RayRecord recordAt(const ParsedCloud& cloud, std::size_t index) {
  const std::size_t at = cloud.data_offset + index * kRecordBytes;
  RayRecord r{};
  r.x = std::bit_cast<double>(getLe(cloud.bytes, at, 8));
  r.y = std::bit_cast<double>(getLe(cloud.bytes, at + 8, 8));
  r.z = std::bit_cast<double>(getLe(cloud.bytes, at + 16, 8));
  r.time = std::bit_cast<double>(getLe(cloud.bytes, at + 24, 8));
  r.nx = std::bit_cast<float>(static_cast<std::uint32_t>(getLe(cloud.bytes, at + 32, 4)));
  r.ny = std::bit_cast<float>(static_cast<std::uint32_t>(getLe(cloud.bytes, at + 36, 4)));
  r.nz = std::bit_cast<float>(static_cast<std::uint32_t>(getLe(cloud.bytes, at + 40, 4)));
  r.intensity = std::bit_cast<float>(static_cast<std::uint32_t>(getLe(cloud.bytes, at + 44, 4)));
  r.scan = static_cast<std::uint32_t>(getLe(cloud.bytes, at + 48, 4));
  r.alpha = cloud.bytes.at(at + 52);
  return r;
}

/// Checks the header lines (comments anywhere before the element are allowed) and the size.
void expectValidCloud(const ParsedCloud& cloud, std::uint64_t count) {
  const std::vector<std::string> expected = {"element vertex " + std::to_string(count),
                                             "property double x",
                                             "property double y",
                                             "property double z",
                                             "property double time",
                                             "property float nx",
                                             "property float ny",
                                             "property float nz",
                                             "property float intensity",
                                             "property uint scan",
                                             "property uchar alpha",
                                             "end_header"};
  ASSERT_GE(cloud.header_lines.size(), 2 + expected.size());
  EXPECT_EQ(cloud.header_lines[0], "ply");
  EXPECT_EQ(cloud.header_lines[1], "format binary_little_endian 1.0");
  const std::size_t tail = cloud.header_lines.size() - expected.size();
  for (std::size_t i = 2; i < tail; ++i) {
    EXPECT_EQ(cloud.header_lines[i].rfind("comment ", 0), 0u) << cloud.header_lines[i];
  }
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(cloud.header_lines[tail + i], expected[i]);
  }
  EXPECT_EQ(cloud.bytes.size(), cloud.data_offset + count * kRecordBytes);
}

Ray ray(Vec3d origin, Vec3d sample, double time_s, float intensity, std::uint64_t scan,
        std::uint32_t flags = 0) {
  Ray r = test::makeRay(origin, sample, flags, scan);
  r.time_s = time_s;
  r.intensity = intensity;
  return r;
}

TEST(RayCloudWriter, WritesTheCountAndEveryField) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("rays.ply");
  const std::vector<Ray> rays = {
      ray({1.0, 2.0, 3.0}, {-4.5, 6.25, -0.125}, 1234.5678, 17.5f, 0),
      ray({0.0, 0.0, 1.5}, {40.0, 0.0, 1.5}, 1234.6, 0.0f, 3, kRayNoReturn),
      ray({-1e5, 2e5, 10.0}, {-1e5 + 0.1, 2e5 - 0.2, 10.3}, -1.0, 255.0f, 4294967295u)};
  auto writer = RayCloudWriter::open(path);
  ASSERT_TRUE(writer.has_value()) << writer.error().message;

  // Act
  ASSERT_TRUE((*writer)->write(rays).has_value());
  ASSERT_TRUE((*writer)->finish().has_value());

  // Assert
  EXPECT_EQ((*writer)->count(), 3u);
  const ParsedCloud cloud = parseCloud(path);
  expectValidCloud(cloud, 3);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const RayRecord r = recordAt(cloud, i);
    EXPECT_EQ(r.x, rays[i].sample.x);
    EXPECT_EQ(r.y, rays[i].sample.y);
    EXPECT_EQ(r.z, rays[i].sample.z);
    EXPECT_EQ(r.time, rays[i].time_s);
    EXPECT_EQ(r.nx, static_cast<float>(rays[i].origin.x - rays[i].sample.x));
    EXPECT_EQ(r.ny, static_cast<float>(rays[i].origin.y - rays[i].sample.y));
    EXPECT_EQ(r.nz, static_cast<float>(rays[i].origin.z - rays[i].sample.z));
    EXPECT_EQ(r.intensity, rays[i].intensity);
    EXPECT_EQ(r.scan, rays[i].scan);
    EXPECT_EQ(static_cast<unsigned>(r.alpha), (rays[i].flags & kRayNoReturn) != 0 ? 0u : 255u);
  }
}

TEST(RayCloudWriter, CountsAcrossManyWritesAndChunks) {
  // Arrange: more rays than one internal chunk, in uneven calls.
  TempDir dir;
  const std::string path = dir.file("many.ply");
  std::vector<Ray> rays;
  for (int i = 0; i < 40000; ++i) {
    rays.push_back(ray({0.0, 0.0, 0.0}, {1.0 + i * 1e-3, 2.0, 3.0}, i * 1e-4, 1.0f,
                       static_cast<std::uint64_t>(i / 1000)));
  }
  auto writer = RayCloudWriter::open(path);
  ASSERT_TRUE(writer.has_value()) << writer.error().message;

  // Act
  const std::span<const Ray> all(rays);
  ASSERT_TRUE((*writer)->write(all.first(7)).has_value());
  ASSERT_TRUE((*writer)->write(all.subspan(7, 30000)).has_value());
  ASSERT_TRUE((*writer)->write({}).has_value());
  ASSERT_TRUE((*writer)->write(all.subspan(30007)).has_value());
  ASSERT_TRUE((*writer)->finish().has_value());

  // Assert
  EXPECT_EQ((*writer)->count(), 40000u);
  const ParsedCloud cloud = parseCloud(path);
  expectValidCloud(cloud, 40000);
  const RayRecord last = recordAt(cloud, 39999);
  EXPECT_EQ(last.x, rays.back().sample.x);
  EXPECT_EQ(last.scan, 39u);
}

TEST(RayCloudWriter, AnEmptyCloudIsValid) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("empty.ply");
  auto writer = RayCloudWriter::open(path);
  ASSERT_TRUE(writer.has_value()) << writer.error().message;

  // Act
  ASSERT_TRUE((*writer)->finish().has_value());

  // Assert
  expectValidCloud(parseCloud(path), 0);
}

TEST(RayCloudWriter, TheFileAppearsOnlyOnFinish) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("late.ply");
  auto writer = RayCloudWriter::open(path);
  ASSERT_TRUE(writer.has_value()) << writer.error().message;
  const std::vector<Ray> rays = {ray({0, 0, 0}, {1, 1, 1}, 0.0, 0.0f, 0)};
  ASSERT_TRUE((*writer)->write(rays).has_value());

  // Act / Assert
  EXPECT_FALSE(std::filesystem::exists(path));
  ASSERT_TRUE((*writer)->finish().has_value());
  EXPECT_TRUE(std::filesystem::exists(path));
  EXPECT_FALSE((*writer)->write(rays).has_value());
  EXPECT_FALSE((*writer)->finish().has_value());
  std::size_t entries = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    ++entries;
  }
  EXPECT_EQ(entries, 1u);
}

TEST(RayCloudWriter, AnAbandonedWriterLeavesNothing) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("abandoned.ply");

  // Act
  {
    auto writer = RayCloudWriter::open(path);
    ASSERT_TRUE(writer.has_value()) << writer.error().message;
    const std::vector<Ray> rays = {ray({0, 0, 0}, {1, 1, 1}, 0.0, 0.0f, 0)};
    ASSERT_TRUE((*writer)->write(rays).has_value());
  }

  // Assert
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(RayCloudWriter, AScanIndexBeyondUint32Fails) {
  // Arrange
  TempDir dir;
  auto writer = RayCloudWriter::open(dir.file("scan.ply"));
  ASSERT_TRUE(writer.has_value()) << writer.error().message;
  const std::vector<Ray> rays = {ray({0, 0, 0}, {1, 1, 1}, 0.0, 0.0f, std::uint64_t{1} << 32)};

  // Act
  auto written = (*writer)->write(rays);

  // Assert
  ASSERT_FALSE(written.has_value());
  EXPECT_EQ(written.error().code, ErrorCode::kInvalidArgument);
}

TEST(RayCloudWriter, AnUnwritablePathFails) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("missing/rays.ply");

  // Act
  auto writer = RayCloudWriter::open(path);

  // Assert
  ASSERT_FALSE(writer.has_value());
  EXPECT_NE(writer.error().message.find(path), std::string::npos) << writer.error().message;
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(AtomicFileWriter, PatchOverwritesInPlaceAndLaterWritesAppend) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("patched.txt");
  auto writer = AtomicFileWriter::open(path);
  ASSERT_TRUE(writer.has_value()) << writer.error().message;
  ASSERT_TRUE(writer->write(std::string("count=000;")).has_value());

  // Act
  ASSERT_TRUE(writer->patch(6, std::string("042")).has_value());
  ASSERT_TRUE(writer->write(std::string("end")).has_value());
  const auto beyond = writer->patch(11, std::string("xyz"));
  ASSERT_TRUE(writer->commit().has_value());

  // Assert
  const std::vector<std::uint8_t> bytes = readFileBytes(path);
  EXPECT_EQ(std::string(bytes.begin(), bytes.end()), "count=042;end");
  ASSERT_FALSE(beyond.has_value());
  EXPECT_EQ(beyond.error().code, ErrorCode::kInvalidArgument);
}

TEST(RayCloudWriter, PointCloudLayoutHoldsTheReturnsForATrajectory) {
  // Arrange: two returns and a no-return ray from a sensor moving along x.
  TempDir dir;
  const std::string points = dir.file("points.ply");
  const std::string path_file = dir.file("path.txt");
  const std::vector<Ray> rays = {ray({0.0, 0.0, 1.0}, {5.0, 0.0, 0.0}, 0.0, 20.0f, 0),
                                 ray({0.5, 0.0, 1.0}, {0.5, 30.0, 1.0}, 0.5, 0.0f, 0, kRayNoReturn),
                                 ray({1.0, 0.0, 1.0}, {1.0, -3.0, 0.5}, 1.0, 30.0f, 1)};
  auto trajectory =
      Trajectory::fromSamples({{0.0, {0.0, 0.0, 1.0}}, {1.0, {1.0, 0.0, 1.0}}}, false, path_file);
  ASSERT_TRUE(trajectory.has_value()) << trajectory.error().message;
  ASSERT_TRUE(saveTrajectory(*trajectory, path_file).has_value());
  auto writer = RayCloudWriter::open(points, PlyLayout::kPointCloud);
  ASSERT_TRUE(writer.has_value()) << writer.error().message;

  // Act
  ASSERT_TRUE((*writer)->write(rays).has_value());
  ASSERT_TRUE((*writer)->finish().has_value());
  RaySourceOptions options;
  options.trajectory_path = path_file;
  auto source = openRaySource(points, options);
  ASSERT_TRUE(source.has_value()) << source.error().message;
  std::vector<Ray> read(4);
  auto n = (*source)->read(read);

  // Assert
  EXPECT_EQ((*writer)->count(), 2u);
  EXPECT_FALSE((*source)->info().ray_cloud);
  EXPECT_FALSE((*source)->info().has_alpha);
  ASSERT_TRUE(n.has_value()) << n.error().message;
  ASSERT_EQ(*n, 2u);
  for (const std::size_t i : {0u, 1u}) {
    const Ray& expected = rays[i == 0 ? 0 : 2];
    EXPECT_EQ(read[i].sample, expected.sample);
    EXPECT_EQ(read[i].origin, expected.origin);
    EXPECT_EQ(read[i].time_s, expected.time_s);
    EXPECT_EQ(read[i].intensity, expected.intensity);
    EXPECT_EQ(read[i].scan, expected.scan);
    EXPECT_EQ(read[i].flags, 0u);
  }
}

}  // namespace
}  // namespace raymap::io
