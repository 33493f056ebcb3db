// SPDX-License-Identifier: BSD-3-Clause
// The library reads rosbag2 bags (issue 55): raymap::RecordingReader gives the scans of a bag
// written by Foxglove's libraries — lidar clouds deskewed with odometry or a TF chain, depth
// images with their CameraInfo — and raymap::Mapper maps them to the same map, byte for byte in
// every layer, as `raymap populate` with the same options. No DDS is involved.
#include <string>
#include <vector>

#include "raymap/mapper.hpp"
#include "raymap/recording.hpp"
#include <gtest/gtest.h>

#include "src/bag/bag_summary.hpp"
#include "tests/rosbag/bag_fixture.hpp"
#include "tests/rosbag/depth_bag.hpp"
#include "tests/support/same_map.hpp"

namespace raymap::test {
namespace {

/// The messages bag::summariseBag counted on `topic`, or -1 when the summary lacks the topic.
std::int64_t messagesOn(const bag::BagSummary& summary, const std::string& topic) {
  for (const bag::TopicSummary& t : summary.topics) {
    if (t.topic.name == topic) {
      return static_cast<std::int64_t>(t.messages);
    }
  }
  return -1;
}

TEST(LibraryBags, ASummaryCountsEachTopicFromTheMcapSummaryOrFromTheMessages) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const Drive drive = makeDrive(dir, DrivePoses::kOdometry, 4);
  const std::string indexed = dir.file("indexed.mcap");
  const std::string unindexed = dir.file("unindexed.mcap");
  writeBag(drive.spec, indexed, {"--file-only", "--compression", "zstd"});
  writeBag(drive.spec, unindexed, {"--file-only", "--unindexed"});

  const Result<bag::BagSummary> stated = bag::summariseBag(indexed, false);
  const Result<bag::BagSummary> counted = bag::summariseBag(indexed, true);
  const Result<bag::BagSummary> linear = bag::summariseBag(unindexed, false);
  const Result<bag::BagSummary> missing = bag::summariseBag(dir.file("none.mcap"), false);

  for (const Result<bag::BagSummary>* s : {&stated, &counted, &linear}) {
    ASSERT_TRUE(s->has_value()) << s->error().message;
    EXPECT_EQ((*s)->storage, "mcap");
    // 4 clouds, the odometry around them and one /tf_static.
    EXPECT_EQ((*s)->messages, 4u + 1u + 51u);
    EXPECT_EQ(messagesOn(**s, "/ouster/points"), 4);
    EXPECT_EQ(messagesOn(**s, "/tf_static"), 1);
    EXPECT_EQ((*s)->start_ns, counted->start_ns);
    EXPECT_EQ((*s)->end_ns, counted->end_ns);
    EXPECT_FALSE((*s)->truncated);
  }
  EXPECT_TRUE(stated->from_summary);
  EXPECT_FALSE(counted->from_summary);
  EXPECT_FALSE(linear->from_summary);
  EXPECT_LT(counted->start_ns, counted->end_ns);
  for (const bag::TopicSummary& topic : counted->topics) {
    EXPECT_GT(topic.bytes, 0u) << topic.topic.name;  // counted: the bytes are known
  }
  ASSERT_FALSE(missing.has_value());
  EXPECT_NE(missing.error().message.find("none.mcap"), std::string::npos)
      << missing.error().message;
}

TEST(LibraryBags, LidarCloudsWithOdometryOrATfChainMapAsPopulateMapsThem) {
  REQUIRE_NODE_HARNESS();
  for (const DrivePoses poses : {DrivePoses::kOdometry, DrivePoses::kTfChain}) {
    const bool odometry = poses == DrivePoses::kOdometry;
    SCOPED_TRACE(odometry ? "odometry" : "tf");
    TempDir dir;
    const Drive drive = makeDrive(dir, poses, 6);
    const std::string bag = dir.file("drive_bag");
    writeBag(drive.spec, bag, {"--compression", "zstd"});
    std::vector<std::string> flags = {"populate", bag,           "-o",  dir.file("cli.rmap"),
                                      "-q",       "--semantics", "scan"};
    RecordingOptions read;
    if (!odometry) {
      flags.insert(flags.end(), {"--pose-source", "tf", "--world-frame", "map"});
      read.bag.pose_source = BagOptions::PoseSource::kTf;
      read.bag.world_frame = "map";
    }
    const RunResult r = runRaymap(flags);
    ASSERT_EQ(r.exit_code, 0) << describe(r);

    MapperConfig config;
    config.map.semantics = Semantics::kPerScan;
    // As world rays, and as the clouds in the lidar's frame with their poses (the sensor on the
    // base from /tf_static, the base's pose interpolated per point time).
    for (const ReadAs read_as : {ReadAs::kScans, ReadAs::kClouds}) {
      SCOPED_TRACE(read_as == ReadAs::kScans ? "scans" : "clouds");
      LibraryRun run;
      ASSERT_NO_FATAL_FAILURE(
          mapWithLibrary(bag, read, config, dir.file("library.rmap"), &run, read_as));
      EXPECT_TRUE(run.bag);
      const RecordingReport& report = run.report;
      EXPECT_EQ(report.scans, drive.scans);
      EXPECT_EQ(report.scans_no_pose, 0u);
      EXPECT_EQ(report.topics, std::vector<std::string>{"/ouster/points"});
      EXPECT_EQ(report.pose_source, odometry ? "odometry /odom" : "tf map -> base_link");
      expectSameMap(dir.file("cli.rmap"), dir.file("library.rmap"));
    }
  }
}

TEST(LibraryBags, DepthImagesWithTheirCameraInfoMapAsPopulateMapsThem) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const DepthBag depth = makeDepthBag(dir, 6, true, true);
  const std::string bag = dir.file("depth_bag");
  writeBag(depth.spec, bag, {});
  const RunResult r = runRaymap({"populate", bag, "-o", dir.file("cli.rmap"), "-q", "--max-range",
                                 "3", "--downsample", "2", "--invalid-as-free"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);

  RecordingOptions read;
  read.bag.downsample = 2;
  read.bag.depth_max_range = 3.0;
  read.bag.invalid_as_free = true;
  MapperConfig config;
  config.rays.max_range = 3.0;
  // As world rays, and as the images' points in the camera's frame with its pose (the
  // free-space points of invalid pixels marked no_return).
  for (const ReadAs read_as : {ReadAs::kScans, ReadAs::kClouds}) {
    SCOPED_TRACE(read_as == ReadAs::kScans ? "scans" : "clouds");
    LibraryRun run;
    ASSERT_NO_FATAL_FAILURE(
        mapWithLibrary(bag, read, config, dir.file("library.rmap"), &run, read_as));
    EXPECT_TRUE(run.bag);
    EXPECT_EQ(run.report.scans, 6u);
    EXPECT_EQ(run.report.images_no_camera_info, 0u);
    expectSameMap(dir.file("cli.rmap"), dir.file("library.rmap"));
  }
}

// The same images given to Mapper::integrate(DepthImageView, CameraIntrinsics, pose) directly,
// as a program with its own camera driver would.
TEST(LibraryDepth, ImagesWithTheirIntrinsicsMapAsPopulateMapsTheBag) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const DepthBag depth = makeDepthBag(dir, 6, true, false);
  const std::string bag = dir.file("depth_bag");
  writeBag(depth.spec, bag, {});
  const RunResult r = runRaymap({"populate", bag, "-o", dir.file("cli.rmap"), "-q", "--max-range",
                                 "3", "--downsample", "2", "--invalid-as-free"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);

  MapperConfig config;
  config.rays.max_range = 3.0;
  auto mapper = Mapper::create(config);
  ASSERT_TRUE(mapper) << mapper.error().message;
  DepthOptions options;
  options.downsample = 2;
  options.max_range = 3.0;
  options.invalid_as_free = true;
  for (const DepthFrame& frame : depth.frames) {
    DepthImageView image;
    image.data = frame.depth.data();
    image.width = depth.camera.width;
    image.height = depth.camera.height;
    image.step = depth.camera.width * sizeof(float);
    image.encoding = DepthEncoding::k32FC1;
    ASSERT_TRUE(mapper->integrate(image, depth.camera, frame.camera_to_world, options));
  }
  ASSERT_TRUE(mapper->save(dir.file("library.rmap")));
  EXPECT_EQ(mapper->counters().scans, 6u);
  expectSameMap(dir.file("cli.rmap"), dir.file("library.rmap"));
}

TEST(LibraryBags, AMissingTopicIsNamedWithTheBagsTopicsOfThatType) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const Drive drive = makeDrive(dir, DrivePoses::kOdometry, 2);
  const std::string bag = dir.file("drive_bag");
  writeBag(drive.spec, bag, {});
  RecordingOptions read;
  read.bag.topics = {"/front/points"};
  auto reader = RecordingReader::open(bag, read);
  ASSERT_FALSE(reader);
  EXPECT_NE(reader.error().message.find("/front/points"), std::string::npos)
      << reader.error().message;
  EXPECT_NE(reader.error().message.find("/ouster/points"), std::string::npos)
      << reader.error().message;
}

TEST(LibraryBags, AReaderReadsScansOrCloudsNotBoth) {
  REQUIRE_NODE_HARNESS();
  TempDir dir;
  const Drive drive = makeDrive(dir, DrivePoses::kOdometry, 3);
  const std::string bag = dir.file("drive_bag");
  writeBag(drive.spec, bag, {});
  std::vector<WorldRay> scan;
  RecordedCloud cloud;

  auto by_scan = RecordingReader::open(bag);
  ASSERT_TRUE(by_scan);
  ASSERT_TRUE(by_scan->nextScan(scan).value_or(false));
  const auto mixed_cloud = by_scan->nextCloud(cloud);
  ASSERT_FALSE(mixed_cloud);
  EXPECT_EQ(mixed_cloud.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(mixed_cloud.error().message.find("drive_bag"), std::string::npos)
      << mixed_cloud.error().message;

  auto by_cloud = RecordingReader::open(bag);
  ASSERT_TRUE(by_cloud);
  std::uint64_t clouds = 0;
  while (by_cloud->nextCloud(cloud).value_or(false)) {
    ++clouds;
    EXPECT_EQ(cloud.topic, "/ouster/points");
    EXPECT_FALSE(cloud.points.empty());
    EXPECT_FALSE(cloud.sensor_poses.empty());
  }
  EXPECT_EQ(clouds, drive.scans);
  EXPECT_EQ(by_cloud->report().scans, drive.scans);
  EXPECT_TRUE(cloud.points.empty()) << "the end leaves the cloud empty";
  const auto mixed_scan = by_cloud->nextScan(scan);
  ASSERT_FALSE(mixed_scan);
  EXPECT_EQ(mixed_scan.error().code, ErrorCode::kInvalidArgument);
}

}  // namespace
}  // namespace raymap::test
