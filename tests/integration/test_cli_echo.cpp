// SPDX-License-Identifier: BSD-3-Clause
// `raymap topics` and `raymap echo` end to end: the real binary against GridMaps, diagnostics,
// best-effort clouds, undecodable maps and a topic of an unknown type that this test process
// publishes on loopback DDS (CYCLONEDDS_URI is pinned by the test harness).
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "grid_map_msgs.h"
#include "std_msgs.h"
#include "tf2_msgs.h"
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include "platform/errno_text.hpp"
#include "src/dds/diagnostics_message.hpp"
#include "src/dds/entities.hpp"
#include "src/dds/grid_map_message.hpp"
#include "src/dds/occupancy_grid_message.hpp"
#include "src/dds/point_cloud_message.hpp"
#include "src/dds/topic_types.hpp"
#include "src/heightmap/costmap.hpp"
#include "tests/support/cli_runner.hpp"
#include "tests/support/json_doc.hpp"

namespace raymap::test {
namespace {

using Clock = std::chrono::steady_clock;

/// The domain of this test process: 40 + pid % 40. The DDS unit tests use 100..199 and the
/// service tests 200..229, so a parallel run of those never shares it; never 0 (a robot's).
std::uint32_t cliTestDomain() { return 40U + static_cast<std::uint32_t>(getpid() % 40); }
/// A domain nobody publishes on (80..99).
std::uint32_t emptyDomain() { return 80U + static_cast<std::uint32_t>(getpid() % 20); }

constexpr double kResolution = 0.2;
constexpr double kCentreX = 12.5;
constexpr double kCentreY = -3.25;
constexpr int kCellsX = 40;
constexpr int kCellsY = 30;
constexpr std::size_t kNanCells = 100;  // the first cells of elevation are unknown
constexpr std::int64_t kFirstStampNs = 1'700'000'000'000'000'000LL;
constexpr std::int64_t kStampStepNs = 50'000'000LL;

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (!line.empty()) {
      out.push_back(line);
    }
  }
  return out;
}

double numberAt(const Json& object, const std::string& key) {
  const Json* value = findPath(object, {key});
  if (value == nullptr || !value->is_number()) {
    ADD_FAILURE() << "no number under \"" << key << "\"";
    return std::nan("");
  }
  return value->get<double>();
}

std::string textAt(const Json& object, const std::string& key) {
  const Json* value = findPath(object, {key});
  if (value == nullptr || !value->is_string()) {
    ADD_FAILURE() << "no string under \"" << key << "\"";
    return {};
  }
  return value->get<std::string>();
}

/// Publishes, every 50 ms until destroyed, what raymapd and its neighbours would: GridMaps on
/// rt/height_map and diagnostics on rt/diagnostics (reliable), a cloud on rt/points (best
/// effort, as lidar drivers), GridMaps of which every second one is inconsistent on
/// rt/bad_map, and a std_msgs/Header (a type raymap does not know) on rt/unknown_type.
class TrafficPublisher {
 public:
  explicit TrafficPublisher(std::uint32_t domain)
      : map_message_(kCellsX, kCellsY), costmap_message_(kCellsX, kCellsY), cloud_(64) {
    auto participant = dds::Participant::create(domain);
    if (!participant) {
      ADD_FAILURE() << participant.error().message;
      return;
    }
    participant_.emplace(std::move(participant).value());
    const auto writer = [this](const char* topic, const dds_topic_descriptor_t* type,
                               dds::Reliability reliability) -> std::optional<dds::Writer> {
      auto created = dds::Writer::create(*participant_, topic, type, reliability, 1);
      if (!created) {
        ADD_FAILURE() << created.error().message;
        return std::nullopt;
      }
      return std::move(created).value();
    };
    map_writer_ = writer("rt/height_map", dds::gridMapType(), dds::Reliability::kReliable);
    costmap_writer_ = writer("rt/costmap", dds::occupancyGridType(), dds::Reliability::kReliable);
    diagnostics_writer_ =
        writer("rt/diagnostics", dds::diagnosticArrayType(), dds::Reliability::kReliable);
    cloud_writer_ = writer("rt/points", dds::pointCloud2Type(), dds::Reliability::kBestEffort);
    bad_map_writer_ = writer("rt/bad_map", dds::gridMapType(), dds::Reliability::kReliable);
    unknown_writer_ =
        writer("rt/unknown_type", &std_msgs_msg_dds__Header__desc, dds::Reliability::kReliable);

    map_.resolution = kResolution;
    map_.cells_x = kCellsX;
    map_.cells_y = kCellsY;
    map_.centre_x = kCentreX;
    map_.centre_y = kCentreY;
    map_.resizeLayers();
    for (std::size_t i = 0; i < map_.cellCount(); ++i) {
      map_.elevation[i] = i < kNanCells ? std::nanf("") : 0.01F * static_cast<float>(i % 100);
      map_.clearance[i] = 2.0F;
      map_.kind[i] = 1;
      map_.observed_count[i] = 3;
    }
    // Valid CDR, but two layer names and no data arrays: decodeGridMap refuses it.
    // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): idlc strings are char*
    bad_names_[0] = const_cast<char*>("elevation");
    // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): idlc strings are char*
    bad_names_[1] = const_cast<char*>("clearance");
    // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): idlc strings are char*
    bad_map_.header.frame_id = const_cast<char*>("odom");
    bad_map_.info.resolution = kResolution;
    bad_map_.info.pose.orientation.w = 1.0;
    bad_map_.layers._buffer = bad_names_;
    bad_map_.layers._length = 2;
    bad_map_.layers._maximum = 2;
    bad_map_.layers._release = false;
    // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): idlc strings are char*
    header_.frame_id = const_cast<char*>("unknown");
    thread_ = std::thread([this] { run(); });
  }
  ~TrafficPublisher() {
    stop_ = true;
    if (thread_.joinable()) {
      thread_.join();
    }
  }
  TrafficPublisher(const TrafficPublisher&) = delete;
  TrafficPublisher& operator=(const TrafficPublisher&) = delete;

 private:
  void run() {
    dds::DiagnosticsMessage diagnostics(2, 4);
    std::vector<float> xyz;
    for (int i = 0; i < 64; ++i) {
      // 4 of 64 points at the origin: no return, by raymapd's convention
      const float r = i % 16 == 0 ? 0.0F : 5.0F;
      xyz.insert(xyz.end(), {r * std::cos(0.1F * static_cast<float>(i)),
                             r * std::sin(0.1F * static_cast<float>(i)), r > 0.0F ? 0.5F : 0.0F});
    }
    std::int64_t stamp_ns = kFirstStampNs;
    for (std::uint64_t cycle = 0; !stop_; ++cycle) {
      map_message_.fill(map_, stamp_ns, "odom");
      if (map_writer_) {
        static_cast<void>(map_writer_->write(map_message_.sample()));
      }
      heightmap::computeCostmap(map_, heightmap::CostmapParams{}, costmap_message_.cells());
      costmap_message_.fill(kResolution, heightmap::costmapOrigin(map_), stamp_ns, "odom");
      if (costmap_writer_) {
        static_cast<void>(costmap_writer_->write(costmap_message_.sample()));
      }
      if (bad_map_writer_) {
        static_cast<void>(bad_map_writer_->write(
            cycle % 2 == 0 ? map_message_.sample() : static_cast<const void*>(&bad_map_)));
      }
      diagnostics.begin(stamp_ns);
      const int status = diagnostics.addStatus(msgs::kDiagnosticWarn, "raymapd: pipeline",
                                               "dropping input", "raymapd");
      diagnostics.addValue(status, "backend", "%s", "cpu");
      diagnostics.addValue(status, "clouds_received", "%llu",
                           static_cast<unsigned long long>(cycle));
      diagnostics.addStatus(msgs::kDiagnosticOk, "raymapd: height map", "ok", "raymapd");
      if (diagnostics_writer_) {
        static_cast<void>(diagnostics_writer_->write(diagnostics.sample()));
      }
      cloud_.fill(xyz, stamp_ns, "lidar");
      if (cloud_writer_) {
        static_cast<void>(cloud_writer_->write(cloud_.sample()));
      }
      if (unknown_writer_) {
        static_cast<void>(unknown_writer_->write(&header_));
      }
      stamp_ns += kStampStepNs;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }

  std::optional<dds::Participant> participant_;
  std::optional<dds::Writer> map_writer_, costmap_writer_, diagnostics_writer_, cloud_writer_,
      bad_map_writer_, unknown_writer_;
  heightmap::HeightMap map_;
  dds::GridMapMessage map_message_;
  dds::OccupancyGridMessage costmap_message_;
  dds::PointCloudMessage cloud_;
  grid_map_msgs_msg_dds__GridMap_ bad_map_{};
  char* bad_names_[2] = {};
  std_msgs_msg_dds__Header_ header_{};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

class CliEcho : public ::testing::Test {
 protected:
  void SetUp() override { publisher_ = std::make_unique<TrafficPublisher>(cliTestDomain()); }
  void TearDown() override { publisher_.reset(); }
  std::string domain() const { return std::to_string(cliTestDomain()); }
  std::unique_ptr<TrafficPublisher> publisher_;
};

// ---------------------------------------------------------------- raymap topics

// `topics` lists what discovery finds within --wait: 5 s, for a loaded machine to find them all.
TEST_F(CliEcho, TopicsJsonListsThePublishedTopicsWithTypesAndQos) {
  const RunResult r = runRaymap({"topics", "--domain", domain(), "--wait", "5", "--json"});

  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const auto parsed = parseJson(r.out);
  ASSERT_TRUE(parsed.has_value());
  ASSERT_TRUE(parsed->is_array()) << r.out;
  const auto topic = [&](const std::string& name) -> const Json* {
    for (const Json& item : *parsed) {
      if (item.value("topic", "") == name) {
        return &item;
      }
    }
    return nullptr;
  };
  const Json* map = topic("rt/height_map");
  ASSERT_NE(map, nullptr) << r.out;
  EXPECT_EQ(textAt(*map, "ros_topic"), "/height_map");
  EXPECT_EQ(textAt(*map, "type"), "grid_map_msgs/msg/GridMap");
  EXPECT_EQ(textAt(*map, "dds_type"), "grid_map_msgs::msg::dds_::GridMap_");
  // At least: a test process that happens to share the domain may add its own endpoints.
  EXPECT_GE(numberAt(*map, "publishers"), 1.0);
  EXPECT_GE(numberAt(*map, "subscribers"), 0.0);
  EXPECT_EQ(textAt(*map, "reliability"), "reliable");
  EXPECT_EQ(textAt(*map, "durability"), "volatile");
  ASSERT_NE(findPath(*map, {"known_type"}), nullptr);
  EXPECT_EQ(*findPath(*map, {"known_type"}), true);
  const Json* diagnostics = topic("rt/diagnostics");
  ASSERT_NE(diagnostics, nullptr) << r.out;
  EXPECT_EQ(textAt(*diagnostics, "type"), "diagnostic_msgs/msg/DiagnosticArray");
  const Json* points = topic("rt/points");
  ASSERT_NE(points, nullptr) << r.out;
  EXPECT_EQ(textAt(*points, "type"), "sensor_msgs/msg/PointCloud2");
  EXPECT_EQ(textAt(*points, "reliability"), "best_effort");
  const Json* unknown = topic("rt/unknown_type");
  ASSERT_NE(unknown, nullptr) << r.out;
  EXPECT_EQ(textAt(*unknown, "type"), "std_msgs/msg/Header");
  EXPECT_EQ(unknown->value("known_type", true), false);
  // sorted by name
  for (std::size_t i = 1; i < parsed->size(); ++i) {
    EXPECT_LT(textAt((*parsed)[i - 1], "topic"), textAt((*parsed)[i], "topic"));
  }
}

TEST_F(CliEcho, TopicsPrintsATableAndHonoursRosDomainId) {
  // No --domain: the domain comes from ROS_DOMAIN_ID, as for ROS 2 tools.
  ASSERT_EQ(::setenv("ROS_DOMAIN_ID", domain().c_str(), 1), 0);
  const RunResult r = runRaymap({"topics", "--wait", "5"});
  ::unsetenv("ROS_DOMAIN_ID");

  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const std::vector<std::string> rows = lines(r.out);
  ASSERT_GE(rows.size(), 6U) << r.out;
  EXPECT_NE(rows[0].find("TOPIC"), std::string::npos);
  EXPECT_NE(rows[0].find("RELIABILITY"), std::string::npos);
  bool map_row = false;
  for (const std::string& row : rows) {
    if (row.rfind("rt/height_map ", 0) == 0) {
      map_row = true;
      EXPECT_NE(row.find("/height_map"), std::string::npos) << row;
      EXPECT_NE(row.find("grid_map_msgs/msg/GridMap"), std::string::npos) << row;
      EXPECT_NE(row.find("reliable"), std::string::npos) << row;
    }
  }
  EXPECT_TRUE(map_row) << r.out;
}

TEST(CliTopics, SaysSoWhenTheDomainIsEmpty) {
  const std::string domain = std::to_string(emptyDomain());
  const RunResult r = runRaymap({"topics", "--domain", domain, "--wait", "0.3"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(r.out, "no topics seen in 0.3 s on domain " + domain + "\n");

  const RunResult json = runRaymap({"topics", "--domain", domain, "--wait", "0.3", "--json"});
  ASSERT_EQ(json.exit_code, 0) << describe(json);
  const auto parsed = parseJson(json.out);
  ASSERT_TRUE(parsed.has_value()) << json.out;
  EXPECT_TRUE(parsed->is_array());
  EXPECT_TRUE(parsed->empty());
}

TEST(CliTopics, RefusesABadDomain) {
  const RunResult r = runRaymap({"topics", "--domain", "300"});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  ASSERT_EQ(::setenv("ROS_DOMAIN_ID", "seven", 1), 0);
  const RunResult env = runRaymap({"topics", "--wait", "0"});
  ::unsetenv("ROS_DOMAIN_ID");
  EXPECT_EQ(env.exit_code, 2) << describe(env);
  EXPECT_NE(env.err.find("ROS_DOMAIN_ID=\"seven\" is not a domain id"), std::string::npos)
      << env.err;
}

// ---------------------------------------------------------------- raymap echo

TEST_F(CliEcho, EchoGridMapJsonPrintsOneParseableLinePerMessage) {
  const RunResult r =
      runRaymap({"echo", "rt/height_map", "--domain", domain(), "--count", "3", "--json"});

  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(r.err, "");
  const std::vector<std::string> messages = lines(r.out);
  ASSERT_EQ(messages.size(), 3U) << r.out;
  double previous_stamp = 0.0;
  for (std::size_t i = 0; i < messages.size(); ++i) {
    const auto line = parseJson(messages[i]);
    ASSERT_TRUE(line.has_value());
    EXPECT_EQ(textAt(*line, "topic"), "rt/height_map");
    EXPECT_EQ(textAt(*line, "type"), "grid_map_msgs/msg/GridMap");
    EXPECT_EQ(numberAt(*line, "index"), static_cast<double>(i + 1));
    EXPECT_GT(numberAt(*line, "arrival_unix_ns"), 1.6e18);
    EXPECT_GT(numberAt(*line, "arrival_monotonic_ns"), 0.0);
    const double stamp = numberAt(*line, "stamp_ns");
    EXPECT_GE(stamp, static_cast<double>(kFirstStampNs));
    EXPECT_GT(stamp, previous_stamp);
    previous_stamp = stamp;
    EXPECT_EQ(textAt(*line, "frame"), "odom");
    EXPECT_DOUBLE_EQ(numberAt(*line, "resolution"), kResolution);
    EXPECT_DOUBLE_EQ(numberAt(*line, "centre_x"), kCentreX);
    EXPECT_DOUBLE_EQ(numberAt(*line, "centre_y"), kCentreY);
    EXPECT_NEAR(numberAt(*line, "length_x"), kCellsX * kResolution, 1e-9);
    EXPECT_NEAR(numberAt(*line, "length_y"), kCellsY * kResolution, 1e-9);
    EXPECT_EQ(numberAt(*line, "cells_x"), kCellsX);
    EXPECT_EQ(numberAt(*line, "cells_y"), kCellsY);
    const Json* layers = findPath(*line, {"layers"});
    ASSERT_NE(layers, nullptr);
    ASSERT_EQ(layers->size(), 4U);
    const Json& elevation = (*layers)[0];
    EXPECT_EQ(textAt(elevation, "name"), "elevation");
    EXPECT_EQ(numberAt(elevation, "cells"), kCellsX * kCellsY);
    EXPECT_EQ(numberAt(elevation, "finite"), kCellsX * kCellsY - static_cast<int>(kNanCells));
    EXPECT_NEAR(numberAt(elevation, "min"), 0.0, 1e-6);
    EXPECT_NEAR(numberAt(elevation, "max"), 0.99, 1e-6);
    EXPECT_EQ(textAt((*layers)[3], "name"), "observed_count");
    EXPECT_EQ(numberAt((*layers)[3], "min"), 3.0);
  }
}

TEST_F(CliEcho, EchoCostmapJsonCountsItsCells) {
  const RunResult r =
      runRaymap({"echo", "/costmap", "--domain", domain(), "--count", "2", "--json"});

  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const std::vector<std::string> messages = lines(r.out);
  ASSERT_EQ(messages.size(), 2U) << r.out;
  for (const std::string& message : messages) {
    const auto line = parseJson(message);
    ASSERT_TRUE(line.has_value());
    EXPECT_EQ(textAt(*line, "type"), "nav_msgs/msg/OccupancyGrid");
    EXPECT_EQ(textAt(*line, "frame"), "odom");
    EXPECT_EQ(numberAt(*line, "width"), kCellsX);
    EXPECT_EQ(numberAt(*line, "height"), kCellsY);
    EXPECT_NEAR(numberAt(*line, "origin_x"), kCentreX - 0.5 * kCellsX * kResolution, 1e-6);
    EXPECT_NEAR(numberAt(*line, "resolution"), kResolution, 1e-6);
    // The cells without an elevation are unknown; every cell is counted once.
    EXPECT_EQ(numberAt(*line, "unknown"), static_cast<double>(kNanCells));
    EXPECT_EQ(numberAt(*line, "invalid"), 0.0);
    EXPECT_EQ(numberAt(*line, "unknown") + numberAt(*line, "free") + numberAt(*line, "costed") +
                  numberAt(*line, "lethal"),
              kCellsX * kCellsY);
  }
}

TEST_F(CliEcho, EchoAcceptsTheRosNameAndPrintsAHumanBlock) {
  const RunResult r = runRaymap({"echo", "/height_map", "--domain", domain(), "--count", "1"});

  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(r.out.rfind("#1 rt/height_map grid_map_msgs/msg/GridMap stamp 1700000000.", 0), 0U)
      << r.out;
  EXPECT_NE(r.out.find(" frame odom\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("resolution 0.2 m, 8 x 6 m (40 x 30 cells), centre (12.5, -3.25, 0) m"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("layers elevation, clearance, kind, observed_count (basic: elevation)"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("elevation      1100 / 1200 finite, min 0, max 0.99"), std::string::npos)
      << r.out;
  EXPECT_NE(r.err.find("1 message from rt/height_map, 0 undecodable"), std::string::npos) << r.err;
}

TEST_F(CliEcho, EchoDiagnosticsJsonHasEveryStatusAndValue) {
  const RunResult r =
      runRaymap({"echo", "rt/diagnostics", "--domain", domain(), "--count", "2", "--json"});

  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const std::vector<std::string> messages = lines(r.out);
  ASSERT_EQ(messages.size(), 2U) << r.out;
  for (const std::string& text : messages) {
    const auto line = parseJson(text);
    ASSERT_TRUE(line.has_value()) << text;
    EXPECT_EQ(textAt(*line, "type"), "diagnostic_msgs/msg/DiagnosticArray");
    ASSERT_NE(findPath(*line, {"stamp_ns"}), nullptr);
    const Json* statuses = findPath(*line, {"statuses"});
    ASSERT_NE(statuses, nullptr);
    ASSERT_EQ(statuses->size(), 2U) << text;
    const Json& pipeline = (*statuses)[0];
    EXPECT_EQ(numberAt(pipeline, "level"), 1.0);
    EXPECT_EQ(textAt(pipeline, "level_name"), "WARN");
    EXPECT_EQ(textAt(pipeline, "name"), "raymapd: pipeline");
    EXPECT_EQ(textAt(pipeline, "message"), "dropping input");
    const Json* values = findPath(pipeline, {"values"});
    ASSERT_NE(values, nullptr);
    EXPECT_EQ(textAt(*values, "backend"), "cpu");
    EXPECT_FALSE(textAt(*values, "clouds_received").empty());
    EXPECT_EQ(textAt((*statuses)[1], "level_name"), "OK");
  }
}

TEST_F(CliEcho, EchoReadsABestEffortCloudWithAMatchingReader) {
  // A reliable reader would not match this best-effort writer: nothing would arrive.
  const RunResult r =
      runRaymap({"echo", "rt/points", "--domain", domain(), "--count", "2", "--json"});

  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const std::vector<std::string> messages = lines(r.out);
  ASSERT_EQ(messages.size(), 2U) << r.out;
  const auto line = parseJson(messages[0]);
  ASSERT_TRUE(line.has_value()) << messages[0];
  EXPECT_EQ(textAt(*line, "type"), "sensor_msgs/msg/PointCloud2");
  EXPECT_EQ(textAt(*line, "frame"), "lidar");
  EXPECT_EQ(numberAt(*line, "width"), 64.0);
  EXPECT_EQ(numberAt(*line, "height"), 1.0);
  EXPECT_EQ(numberAt(*line, "points"), 64.0);
  EXPECT_EQ(numberAt(*line, "valid_points"), 60.0);
  EXPECT_EQ(numberAt(*line, "no_return"), 4.0);
  const Json* fields = findPath(*line, {"fields"});
  ASSERT_NE(fields, nullptr);
  ASSERT_GE(fields->size(), 3U);
  EXPECT_EQ(textAt((*fields)[0], "name"), "x");
  EXPECT_EQ(textAt((*fields)[0], "type"), "float32");

  const RunResult human = runRaymap({"echo", "/points", "--domain", domain(), "--count", "1"});
  ASSERT_EQ(human.exit_code, 0) << describe(human);
  EXPECT_NE(human.out.find("64 x 1 points, point_step "), std::string::npos) << human.out;
  EXPECT_NE(human.out.find("fields x:float32 y:float32 z:float32"), std::string::npos) << human.out;
  EXPECT_NE(human.out.find("60 valid points, 4 no return"), std::string::npos) << human.out;
}

TEST_F(CliEcho, EchoReportsUndecodableMessagesAndCarriesOn) {
  const RunResult r =
      runRaymap({"echo", "rt/bad_map", "--domain", domain(), "--count", "6", "--json"});

  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const std::vector<std::string> good = lines(r.out);
  std::size_t errors = 0;
  for (const std::string& line : lines(r.err)) {
    if (line.find("does not decode: layer_count_mismatch") != std::string::npos) {
      EXPECT_EQ(line.rfind("raymap echo: error: rt/bad_map message #", 0), 0U) << line;
      ++errors;
    }
  }
  EXPECT_EQ(good.size() + errors, 6U) << describe(r);
  EXPECT_GE(good.size(), 1U) << describe(r);
  EXPECT_GE(errors, 1U) << describe(r);
  for (const std::string& line : good) {
    EXPECT_TRUE(parseJson(line).has_value()) << line;
  }
  EXPECT_NE(r.err.find(std::to_string(errors) + " undecodable"), std::string::npos) << r.err;
}

TEST(CliEchoLatched, ShowsATfStaticTransformPublishedBeforeEchoStarted) {
  // A static_transform_publisher: reliable, transient-local, one message long before echo.
  // 20..39: no other test publishes there (the empty-domain tests use 80..99).
  const std::uint32_t domain = 20U + static_cast<std::uint32_t>(getpid() % 20);
  auto participant = dds::Participant::create(domain);
  ASSERT_TRUE(participant.has_value());
  auto writer =
      dds::Writer::create(participant.value(), "rt/tf_static", dds::tfMessageType(),
                          dds::Reliability::kReliable, 1, dds::Durability::kTransientLocal);
  ASSERT_TRUE(writer.has_value());
  geometry_msgs_msg_dds__TransformStamped_ t{};
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): read-only for dds_write
  t.header.frame_id = const_cast<char*>("base_link");
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): read-only for dds_write
  t.child_frame_id = const_cast<char*>("lidar");
  t.transform.translation = {0.1, 0.0, 1.2};
  t.transform.rotation = {0.0, 0.0, 0.0, 1.0};
  tf2_msgs_msg_dds__TFMessage_ m{};
  m.transforms._buffer = &t;
  m.transforms._length = m.transforms._maximum = 1;
  ASSERT_TRUE(writer.value().write(&m).has_value());
  // Generous waits (discovery on a loaded machine); --count 1 ends it at the message.
  const RunResult r = runRaymap({"echo", "/tf_static", "--domain", std::to_string(domain),
                                 "--count", "1", "--wait", "30", "--duration", "30", "--json"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(jsonValue(r.out, "child_frame"), "lidar") << describe(r);
}

TEST_F(CliEcho, EchoWithoutAPublisherFailsWithinTheWait) {
  const auto start = Clock::now();
  const RunResult r = runRaymap({"echo", "rt/nobody", "--domain", domain(), "--wait", "0.5"});
  const double elapsed_s = std::chrono::duration<double>(Clock::now() - start).count();

  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_EQ(r.out, "");
  EXPECT_NE(r.err.find("raymap echo: error: no publisher of rt/nobody seen in 0.5 s on domain " +
                       domain() + " (raymap topics lists the topics)"),
            std::string::npos)
      << r.err;
  // Not before its wait, and before the default wait of 5 s (--wait taken): the widest bound
  // that still tells them apart, dozens of times the start-up (under 0.1 s on the dev VM).
  EXPECT_GE(elapsed_s, 0.5);
  EXPECT_LT(elapsed_s, 5.0);
}

TEST_F(CliEcho, EchoOfAnUnknownTypeFailsNamingItAndTheKnownTypes) {
  const RunResult r = runRaymap({"echo", "/unknown_type", "--domain", domain()});

  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_EQ(r.out, "");
  EXPECT_NE(r.err.find("rt/unknown_type has type std_msgs::msg::dds_::Header_ "
                       "(std_msgs/msg/Header), which raymap cannot decode; known types: "
                       "sensor_msgs/msg/PointCloud2, nav_msgs/msg/Odometry, "
                       "tf2_msgs/msg/TFMessage, grid_map_msgs/msg/GridMap, "
                       "diagnostic_msgs/msg/DiagnosticArray"),
            std::string::npos)
      << r.err;
}

TEST_F(CliEcho, EchoStopsAfterItsDuration) {
  const auto start = Clock::now();
  const RunResult r =
      runRaymap({"echo", "rt/height_map", "--domain", domain(), "--duration", "2", "--json"});
  const double elapsed_s = std::chrono::duration<double>(Clock::now() - start).count();

  ASSERT_EQ(r.exit_code, 0) << describe(r);
  // Published at 20 Hz: 40 in the 2 s, less the time a loaded machine takes to match.
  EXPECT_GE(lines(r.out).size(), 5U) << r.out;
  // Not before its duration (counted once it reads), and by itself: without --duration it would
  // run until a signal.
  EXPECT_GE(elapsed_s, 2.0);
  EXPECT_LT(elapsed_s, 30.0);
}

TEST(CliEchoUsage, RefusesBadOptions) {
  EXPECT_EQ(runRaymap({"echo"}).exit_code, 2);
  EXPECT_EQ(runRaymap({"echo", "rt/x", "--domain", "233"}).exit_code, 2);
  EXPECT_EQ(runRaymap({"echo", "rt/x", "--count", "-1"}).exit_code, 2);
  EXPECT_EQ(runRaymap({"echo", "rt/x", "--wait", "-2"}).exit_code, 2);
  const RunResult empty = runRaymap({"echo", ""});
  EXPECT_EQ(empty.exit_code, 2) << describe(empty);
  EXPECT_NE(empty.err.find("TOPIC is empty"), std::string::npos) << empty.err;
}

/// A running `raymap echo`: its stdout is read line by line while it runs (as a soak script
/// does), then it is stopped with a signal.
class SignalledEcho : public ::testing::TestWithParam<int> {};

TEST_P(SignalledEcho, StreamsLinesLiveAndExitsCleanlyOnTheSignal) {
  TrafficPublisher publisher(cliTestDomain());
  const std::string domain = std::to_string(cliTestDomain());
  std::vector<std::string> words = {RAYMAP_CLI_PATH, "echo", "rt/height_map",
                                    "--domain",      domain, "--json"};
  std::vector<char*> argv;
  for (std::string& word : words) {
    argv.push_back(word.data());
  }
  argv.push_back(nullptr);
  int out_pipe[2] = {-1, -1};
  ASSERT_EQ(::pipe2(out_pipe, O_CLOEXEC), 0) << platform::errnoText(errno);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, out_pipe[1], STDOUT_FILENO);
  pid_t pid = -1;
  const int spawned = ::posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(out_pipe[1]);
  ASSERT_EQ(spawned, 0) << platform::errnoText(spawned);

  // Read until two complete lines arrived: the process is still running, so they can only be
  // here because echo flushes each line.
  std::string out;
  const auto deadline = Clock::now() + std::chrono::seconds(15);
  while (lines(out).size() < 2 || out.back() != '\n') {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) {
      break;
    }
    pollfd fd{out_pipe[0], POLLIN, 0};
    if (::poll(&fd, 1, static_cast<int>(left)) <= 0) {
      continue;
    }
    char buffer[4096];
    const ssize_t n = ::read(out_pipe[0], buffer, sizeof(buffer));
    if (n <= 0) {
      break;
    }
    out.append(buffer, static_cast<std::size_t>(n));
  }
  const std::vector<std::string> live = lines(out);
  EXPECT_GE(live.size(), 2U) << out;
  for (const std::string& line : live) {
    EXPECT_TRUE(parseJson(line).has_value()) << line;
  }

  const auto signalled = Clock::now();
  ASSERT_EQ(::kill(pid, GetParam()), 0);
  // Drain to end of file, then reap.
  char buffer[4096];
  while (::read(out_pipe[0], buffer, sizeof(buffer)) > 0) {
  }
  ::close(out_pipe[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  const double stop_s = std::chrono::duration<double>(Clock::now() - signalled).count();
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 0);
  // By itself, at the signal (it checks between waits of at most a fraction of a second);
  // generous for a loaded machine.
  EXPECT_LT(stop_s, 20.0);
}

INSTANTIATE_TEST_SUITE_P(Signals, SignalledEcho, ::testing::Values(SIGINT, SIGTERM),
                         [](const ::testing::TestParamInfo<int>& signal) {
                           return std::string(signal.param == SIGINT ? "Sigint" : "Sigterm");
                         });

}  // namespace
}  // namespace raymap::test
