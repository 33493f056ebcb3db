// SPDX-License-Identifier: BSD-3-Clause
// Writes the seed corpora of the fuzz targets with raymap's own writers: fuzz_make_seeds OUTDIR
// (tools/fuzz-seeds.sh runs it, adds the map files `raymap populate` writes and the shipped YAML,
// and replaces tests/fuzz/corpus). Each seed is small (a fuzzer mutates small inputs faster) and
// valid, so that mutations start from the paths a real input takes.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <sqlite3.h>

#include "src/bag/rosbag_writer.hpp"
#include "src/dds/diagnostics_message.hpp"
#include "src/dds/grid_map_message.hpp"
#include "src/dds/occupancy_grid_message.hpp"
#include "src/heightmap/height_map.hpp"
#include "src/io/ray_cloud_writer.hpp"
#include "src/io/trajectory.hpp"
#include "src/record/record_log_writer.hpp"
#include "tests/support/ply_test_writer.hpp"
#include "tests/unit/dds/cdr_test_writer.hpp"
#include "tests/unit/dds/loopback_bytes.hpp"

namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::byte>;

[[noreturn]] void die(const std::string& what) {
  std::fprintf(stderr, "fuzz_make_seeds: %s\n", what.c_str());
  std::exit(1);
}

template <typename T>
T orDie(raymap::Result<T> result, const std::string& what) {
  if (!result) {
    die(what + ": " + result.error().message);
  }
  return std::move(*result);
}

void check(const raymap::Expected<void, raymap::Error>& result, const std::string& what) {
  if (!result) {
    die(what + ": " + result.error().message);
  }
}

void writeFile(const fs::path& path, const void* data, std::size_t size) {
  std::ofstream out(path, std::ios::binary);
  out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!out) {
    die("cannot write " + path.string());
  }
}

void writeFile(const fs::path& path, const Bytes& bytes) {
  writeFile(path, bytes.data(), bytes.size());
}

fs::path folder(const fs::path& out, const std::string& target) {
  fs::create_directories(out / target);
  return out / target;
}

// ---- PLY: every encoding, ray clouds and point clouds, optional properties ----

using raymap::test::PlyEncoding;
using raymap::test::PlyTestElement;
using raymap::test::PlyTestFile;

PlyTestFile rayCloud(PlyEncoding encoding) {
  PlyTestFile file;
  file.encoding = encoding;
  file.comments = {"fuzz seed: ray cloud"};
  PlyTestElement vertex("vertex", {{"double", "x", ""},
                                   {"double", "y", ""},
                                   {"double", "z", ""},
                                   {"double", "time", ""},
                                   {"float", "nx", ""},
                                   {"float", "ny", ""},
                                   {"float", "nz", ""},
                                   {"float", "intensity", ""},
                                   {"uint", "scan", ""},
                                   {"uchar", "alpha", ""}});
  for (int i = 0; i < 12; ++i) {
    const double a = 0.5 * i;
    vertex.add({3.0 * std::cos(a), 3.0 * std::sin(a), 0.2 * i, 0.05 * i, -3.0 * std::cos(a),
                -3.0 * std::sin(a), -0.2 * i, 10.0 * i, static_cast<double>(i / 4),
                i == 7 ? 0.0 : 255.0});
  }
  file.elements.push_back(vertex);
  return file;
}

PlyTestFile pointCloud(PlyEncoding encoding) {
  PlyTestFile file;
  file.encoding = encoding;
  file.comments = {"fuzz seed: point cloud read with a trajectory"};
  PlyTestElement vertex("vertex", {{"float", "x", ""},
                                   {"float", "y", ""},
                                   {"float", "z", ""},
                                   {"double", "timestamp", ""},
                                   {"ushort", "intensity", ""}});
  for (int i = 0; i < 12; ++i) {
    vertex.add({1.0 + i, 2.0 - i, 0.5, 0.4 * i, 100.0 + i});
  }
  file.elements.push_back(vertex);
  // An element the reader must skip, with a list property.
  PlyTestElement face("face", {{"int", "vertex_indices", "uchar"}});
  face.add({3, 0, 1, 2});
  file.elements.push_back(face);
  return file;
}

void plySeeds(const fs::path& out) {
  const fs::path ply = folder(out, "ply");
  const fs::path gz = folder(out, "ply_gzip");
  const fs::path header = folder(out, "ply_header");
  const std::pair<PlyEncoding, const char*> encodings[] = {{PlyEncoding::kAscii, "ascii"},
                                                           {PlyEncoding::kBinaryLittleEndian, "le"},
                                                           {PlyEncoding::kBinaryBigEndian, "be"}};
  for (const auto& [encoding, name] : encodings) {
    for (auto [file, kind] :
         {std::pair{rayCloud(encoding), "rays"}, std::pair{pointCloud(encoding), "points"}}) {
      const std::string stem = std::string(kind) + "_" + name;
      raymap::test::writePly((ply / (stem + ".ply")).string(), file);
      file.gzip = true;
      raymap::test::writePly((gz / (stem + ".ply.gz")).string(), file);
      const std::string text = raymap::test::encodePlyHeader(file);
      writeFile(header / (stem + ".txt"), text.data(), text.size());
    }
  }
  // What raymap itself writes (raymap simulate, export --ply): both layouts.
  for (auto [layout, name] : {std::pair{raymap::io::PlyLayout::kRayCloud, "writer_rays.ply"},
                              std::pair{raymap::io::PlyLayout::kPointCloud, "writer_points.ply"}}) {
    auto writer = orDie(raymap::io::RayCloudWriter::open((ply / name).string(), layout), name);
    std::vector<raymap::Ray> rays(8);
    for (std::size_t i = 0; i < rays.size(); ++i) {
      rays[i].origin = {0.0, 0.0, 1.0};
      rays[i].sample = {2.0 + static_cast<double>(i), 1.0, 0.0};
      rays[i].time_s = 0.1 * static_cast<double>(i);
      rays[i].scan = i / 3;
    }
    check(writer->write(rays), name);
    check(writer->finish(), name);
  }
}

// ---- trajectories ----

void trajectorySeeds(const fs::path& out) {
  const fs::path dir = folder(out, "trajectory");
  for (bool oriented : {false, true}) {
    std::vector<raymap::io::TrajectorySample> samples(5);
    for (std::size_t i = 0; i < samples.size(); ++i) {
      samples[i].time_s = 0.5 * static_cast<double>(i);
      samples[i].position = {static_cast<double>(i), 0.5, 0.0};
      if (oriented) {
        samples[i].orientation = Eigen::Quaterniond(
            Eigen::AngleAxisd(0.3 * static_cast<double>(i), Eigen::Vector3d::UnitZ()));
      }
    }
    auto trajectory =
        orDie(raymap::io::Trajectory::fromSamples(samples, oriented, "seed"), "trajectory");
    const std::string name = oriented ? "with_orientation.txt" : "positions.txt";
    check(raymap::io::saveTrajectory(trajectory, (dir / name).string()), name);
  }
  const std::string csv = "time,x,y,z\n0,0,0,0\n1.5,1,2,3\n3,2,2,2\n";
  writeFile(dir / "header_and_commas.csv", csv.data(), csv.size());
}

// ---- CDR messages ----

namespace dtest = raymap::dds::test;

Bytes ousterLikeCloud(bool cdr_little_endian, bool big_endian_points) {
  dtest::TestCloud cloud;
  cloud.width = 6;
  cloud.height = 2;
  cloud.is_bigendian = big_endian_points;
  cloud.fields = {{"x", 0, 7},          {"y", 4, 7},  {"z", 8, 7},
                  {"intensity", 16, 7}, {"t", 20, 6}, {"ring", 24, 4}};
  cloud.point_step = 32;
  cloud.row_step = cloud.point_step * cloud.width;
  cloud.data.assign(std::size_t{cloud.row_step} * cloud.height, 0);
  for (std::uint32_t i = 0; i < cloud.width * cloud.height; ++i) {
    const std::size_t at = std::size_t{i} * cloud.point_step;
    dtest::putValue(cloud.data, at + 0, 7, 1.0 + i, big_endian_points);
    dtest::putValue(cloud.data, at + 4, 7, i == 3 ? std::nan("") : 0.5 * i, big_endian_points);
    dtest::putValue(cloud.data, at + 8, 7, 0.25, big_endian_points);
    dtest::putValue(cloud.data, at + 16, 7, 40.0 + i, big_endian_points);
    dtest::putValue(cloud.data, at + 20, 6, 1000.0 * i, big_endian_points);
    dtest::putValue(cloud.data, at + 24, 4, i / 6, big_endian_points);
  }
  return dtest::encodeCloud(cloud, cdr_little_endian);
}

dtest::TestImage depthImage(bool millimetres, bool big_endian) {
  const std::uint32_t width = 8;
  const std::uint32_t height = 6;
  std::vector<float> depth(width * height);
  for (std::size_t i = 0; i < depth.size(); ++i) {
    depth[i] = 0.5f + 0.1f * static_cast<float>(i % 7);
  }
  depth[5] = 0.0f;  // no return
  if (!millimetres) {
    depth[9] = NAN;
    depth[10] = -INFINITY;
  }
  return dtest::makeDepthImage(width, height, depth, millimetres, big_endian, big_endian ? 4 : 0);
}

struct CdrSeeds {
  std::vector<std::pair<std::string, Bytes>> clouds, odometry, tf, images, infos;
};

CdrSeeds cdrSeeds() {
  CdrSeeds s;
  s.clouds.emplace_back("xyz.cdr", dtest::encodeCloud(dtest::makeXyzCloud({1, 2, 3, 4, 5, 6})));
  s.clouds.emplace_back("ouster_le.cdr", ousterLikeCloud(true, false));
  s.clouds.emplace_back("ouster_be_cdr_be_points.cdr", ousterLikeCloud(false, true));
  dtest::TestPose pose;
  pose.q[2] = std::sin(0.2);
  pose.q[3] = std::cos(0.2);
  s.odometry.emplace_back("le.cdr", dtest::encodeOdometry(pose, true));
  s.odometry.emplace_back("be.cdr", dtest::encodeOdometry(pose, false));
  dtest::TestPose second = pose;
  second.parent = "base_link";
  second.child = "lidar";
  s.tf.emplace_back("one.cdr", dtest::encodeTfMessage({pose}, true));
  s.tf.emplace_back("three_be.cdr", dtest::encodeTfMessage({pose, second, pose}, false));
  s.images.emplace_back("mm_le.cdr", dtest::encodeImage(depthImage(true, false), true));
  s.images.emplace_back("metres_be.cdr", dtest::encodeImage(depthImage(false, true), false));
  dtest::TestImage mono = depthImage(true, false);
  mono.encoding = "mono16";
  s.images.emplace_back("mono16.cdr", dtest::encodeImage(mono, true));
  dtest::TestCameraInfo info;
  info.width = 8;
  info.height = 6;
  info.k[0] = info.k[4] = 7.0;
  info.k[2] = 4.0;
  info.k[5] = 3.0;
  s.infos.emplace_back("no_distortion.cdr", dtest::encodeCameraInfo(info, true));
  info.d = {-0.1, 0.02, 0.001, -0.001, 0.0};
  s.infos.emplace_back("plumb_bob_be.cdr", dtest::encodeCameraInfo(info, false));
  info.binning_x = 2;
  info.binning_y = 2;
  info.roi_x_offset = 1;
  info.roi_y_offset = 1;
  info.roi_width = 4;
  info.roi_height = 2;
  s.infos.emplace_back("binning_roi.cdr", dtest::encodeCameraInfo(info, true));
  return s;
}

void writeAll(const fs::path& dir, const std::vector<std::pair<std::string, Bytes>>& seeds) {
  for (const auto& [name, bytes] : seeds) {
    writeFile(dir / name, bytes);
  }
}

/// raymapd's outputs, serialized by Cyclone itself (a loopback participant).
void outputSeeds(const fs::path& out) {
  raymap::heightmap::HeightMap map;
  map.resolution = 0.2;
  map.cells_x = 4;
  map.cells_y = 3;
  map.has_normals = true;
  map.resizeLayers();
  for (std::size_t i = 0; i < map.cellCount(); ++i) {
    map.elevation[i] = i == 2 ? NAN : 0.1f * static_cast<float>(i);
    map.clearance[i] = 2.0f;
    map.kind[i] = static_cast<std::uint32_t>(i % 3);
    map.observed_count[i] = static_cast<std::uint32_t>(i);
    map.normal_x[i] = 0.0f;
    map.normal_y[i] = 0.0f;
    map.normal_z[i] = 1.0f;
  }
  raymap::dds::GridMapMessage grid(map.cells_x, map.cells_y, true);
  grid.fill(map, 1'700'000'000'000'000'000, "odom");
  raymap::dds::DiagnosticsMessage diagnostics(2, 3);
  diagnostics.begin(1'700'000'000'000'000'000);
  const int status =
      diagnostics.addStatus(1, "raymapd: pipeline", "clouds dropped: wrong_frame", "raymapd@robot");
  diagnostics.addValue(status, "cloud_rate_hz", "%.1f", 10.0);
  diagnostics.addValue(status, "clouds_wrong_frame", "%d", 3);
  diagnostics.addStatus(0, "raymapd: sensor lidar", "OK", "raymapd@robot");
  raymap::dds::OccupancyGridMessage occupancy(4, 3);
  std::int8_t value = -1;
  for (auto& cell : occupancy.cells()) {
    cell = value;
    value = static_cast<std::int8_t>(value == 100 ? -1 : value + 25);
  }
  occupancy.fill(0.2, {-0.4, -0.3, 0.0}, 1'700'000'000'000'000'000, "odom");
  const std::pair<const char*, std::pair<const dds_topic_descriptor_t*, const void*>> outputs[] = {
      {"cdr_grid_map", {raymap::dds::GridMapMessage::descriptor(), grid.sample()}},
      {"cdr_diagnostics", {raymap::dds::DiagnosticsMessage::descriptor(), diagnostics.sample()}},
      {"cdr_occupancy_grid",
       {raymap::dds::OccupancyGridMessage::descriptor(), occupancy.sample()}}};
  for (const auto& [target, message] : outputs) {
    const std::string topic = std::string("raymap_fuzz_seed_") + target;
    const auto bytes = dtest::cyclonesBytes(topic.c_str(), message.first, {message.second});
    if (bytes.size() != 1) {
      die(std::string("Cyclone did not serialize the ") + target + " seed");
    }
    writeFile(folder(out, target) / "raymapd.cdr", bytes.front());
  }
}

// ---- record logs and bags of those messages ----

void recordLogSeed(const fs::path& out, const CdrSeeds& s) {
  const fs::path path = folder(out, "record_log") / "lidar_and_odometry.rmlog";
  auto writer = orDie(raymap::record::RecordLogWriter::create(path.string()), "record log");
  const auto points = orDie(writer->addTopic("rt/points", "sensor_msgs::msg::dds_::PointCloud2_",
                                             raymap::record::LogReliability::kBestEffort,
                                             raymap::record::LogDurability::kVolatile),
                            "record topic");
  const auto odom = orDie(writer->addTopic("rt/odom", "nav_msgs::msg::dds_::Odometry_",
                                           raymap::record::LogReliability::kReliable,
                                           raymap::record::LogDurability::kVolatile),
                          "record topic");
  std::int64_t t = 1'700'000'000'000'000'000;
  for (int i = 0; i < 2; ++i, t += 100'000'000) {
    check(writer->write(odom, t, t, t, s.odometry.front().second), "record");
    check(writer->write(points, t + 1, t + 1, t, s.clouds[1].second), "record");
  }
  check(writer->close(), "record log");
}

struct BagTopicSeed {
  const char* name;
  const char* type;
  const Bytes* cdr;
};

std::vector<BagTopicSeed> bagTopics(const CdrSeeds& s) {
  return {{"/points", "sensor_msgs/msg/PointCloud2", &s.clouds[1].second},
          {"/odom", "nav_msgs/msg/Odometry", &s.odometry[0].second},
          {"/tf_static", "tf2_msgs/msg/TFMessage", &s.tf[1].second},
          {"/camera/depth/image_rect_raw", "sensor_msgs/msg/Image", &s.images[0].second},
          {"/camera/depth/camera_info", "sensor_msgs/msg/CameraInfo", &s.infos[1].second}};
}

void mcapSeeds(const fs::path& out, const CdrSeeds& s, const fs::path& scratch) {
  const fs::path dir = folder(out, "mcap");
  for (const char* compression : {"none", "zstd", "lz4"}) {
    raymap::bag::RosbagWriterOptions options;
    options.compression = orDie(raymap::bag::parseChunkCompression(compression), "compression");
    options.chunk_bytes = 1024;  // several chunks, and a summary that indexes them
    const fs::path bag_dir = scratch / (std::string("bag_") + compression);
    auto writer = orDie(raymap::bag::RosbagWriter::create(bag_dir.string(), options), "bag");
    std::vector<std::uint32_t> ids;
    for (const auto& topic : bagTopics(s)) {
      ids.push_back(orDie(
          writer->addTopic(topic.name, topic.type, raymap::bag::offeredQosYaml(true, false, 10)),
          topic.name));
    }
    std::int64_t t = 1'700'000'000'000'000'000;
    for (std::size_t i = 0; i < ids.size(); ++i, t += 50'000'000) {
      check(writer->write(ids[i], t, t, *bagTopics(s)[i].cdr), "bag write");
    }
    check(writer->close(), "bag close");
    for (const auto& entry : fs::directory_iterator(bag_dir)) {
      if (entry.path().extension() == ".mcap") {
        fs::copy_file(entry.path(), dir / (std::string(compression) + ".mcap"));
      }
    }
  }
}

void sqliteSeed(const fs::path& out, const CdrSeeds& s) {
  const fs::path path = folder(out, "sqlite_bag") / "humble.db3";
  fs::remove(path);
  sqlite3* db = nullptr;
  if (sqlite3_open(path.c_str(), &db) != SQLITE_OK) {
    die("cannot create " + path.string());
  }
  // The tables rosbag2 (Humble) creates, on small pages so that the seed stays small.
  std::string sql =
      "PRAGMA page_size=512;"
      "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY,ros_distro TEXT NOT NULL);"
      "INSERT INTO schema VALUES(3,'humble');"
      "CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT NULL,"
      "serialization_format TEXT NOT NULL,offered_qos_profiles TEXT NOT NULL);"
      "CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,"
      "timestamp INTEGER NOT NULL, data BLOB NOT NULL);"
      "CREATE INDEX timestamp_idx ON messages (timestamp ASC);";
  if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr) != SQLITE_OK) {
    die(std::string("sqlite: ") + sqlite3_errmsg(db));
  }
  sqlite3_stmt* topic = nullptr;
  sqlite3_stmt* message = nullptr;
  sqlite3_prepare_v2(db, "INSERT INTO topics VALUES(?,?,?,'cdr','')", -1, &topic, nullptr);
  sqlite3_prepare_v2(db, "INSERT INTO messages(topic_id,timestamp,data) VALUES(?,?,?)", -1,
                     &message, nullptr);
  const auto topics = bagTopics(s);
  std::int64_t t = 1'700'000'000'000'000'000;
  for (std::size_t i = 0; i < 3; ++i, t += 50'000'000) {  // points, odometry, tf_static
    sqlite3_bind_int64(topic, 1, static_cast<sqlite3_int64>(i + 1));
    sqlite3_bind_text(topic, 2, topics[i].name, -1, SQLITE_STATIC);
    sqlite3_bind_text(topic, 3, topics[i].type, -1, SQLITE_STATIC);
    sqlite3_bind_int64(message, 1, static_cast<sqlite3_int64>(i + 1));
    sqlite3_bind_int64(message, 2, t);
    sqlite3_bind_blob(message, 3, topics[i].cdr->data(), static_cast<int>(topics[i].cdr->size()),
                      SQLITE_STATIC);
    if (sqlite3_step(topic) != SQLITE_DONE || sqlite3_step(message) != SQLITE_DONE) {
      die(std::string("sqlite: ") + sqlite3_errmsg(db));
    }
    sqlite3_reset(topic);
    sqlite3_reset(message);
  }
  sqlite3_finalize(topic);
  sqlite3_finalize(message);
  sqlite3_close(db);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_make_seeds OUTDIR (an empty or missing folder)\n");
    return 2;
  }
  const fs::path out(argv[1]);
  fs::create_directories(out);
  const fs::path scratch = out / ".scratch";
  fs::remove_all(scratch);
  fs::create_directories(scratch);

  plySeeds(out);
  trajectorySeeds(out);
  const CdrSeeds s = cdrSeeds();
  writeAll(folder(out, "cdr_point_cloud"), s.clouds);
  writeAll(folder(out, "cdr_odometry"), s.odometry);
  writeAll(folder(out, "cdr_tf"), s.tf);
  writeAll(folder(out, "cdr_depth_image"), s.images);
  writeAll(folder(out, "cdr_camera_info"), s.infos);
  outputSeeds(out);
  recordLogSeed(out, s);
  mcapSeeds(out, s, scratch);
  sqliteSeed(out, s);
  fs::remove_all(scratch);
  std::printf("seeds written to %s\n", out.c_str());
  return 0;
}
