// SPDX-License-Identifier: BSD-3-Clause
// `raymap record` and the replay of its logs: bit-for-bit reproduction of the recorded traffic,
// a recorder killed mid-recording, and corrupt logs.
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <signal.h>

#include "platform/clock.hpp"
#include "src/dds/topic_types.hpp"
#include "src/record/record_log_writer.hpp"
#include "tests/replay/replay_harness.hpp"
#include "tests/service/service_fixture.hpp"
#include "tests/support/cli_runner.hpp"

namespace raymap::test {
namespace {

using Payloads = std::vector<std::vector<std::byte>>;

/// Keeps every sample of a topic, as bytes.
struct Capture {
  Capture(const dds::Participant& participant, const char* topic,
          const dds_topic_descriptor_t* type)
      : reader(std::move(dds::RawReader::create(participant, topic, type,
                                                dds::Reliability::kBestEffort, 256))
                   .value()) {}
  void poll() {
    reader.takeEach([this](std::span<const std::byte> cdr,
                           std::int64_t) { samples.emplace_back(cdr.begin(), cdr.end()); },
                    64);
  }
  dds::RawReader reader;
  Payloads samples;
};

/// Waits until `text` appears in the file at `path` (a child's log), up to `seconds`.
bool waitForText(const std::string& path, const std::string& text, double seconds) {
  const std::int64_t end = platform::monotonicNowNs() + static_cast<std::int64_t>(seconds * 1e9);
  while (platform::monotonicNowNs() < end) {
    if (readFile(path).find(text) != std::string::npos) {
      return true;
    }
    platform::sleepUntilMonotonicNs(platform::monotonicNowNs() + 20'000'000);
  }
  return false;
}

/// Publishes `scans` scans of the (still) yard lidar and odometry at 10 Hz while `capture`
/// witnesses what went out.
void publishDrive(driver::DriverPublisher& publisher, int scans, Capture& clouds,
                  Capture& odometry) {
  const driver::SimulatedLidar lidar = yardLidar(8, 256, /*moving=*/false);
  std::vector<msgs::ScanPoint> points;
  std::vector<std::uint16_t> rings;
  const std::int64_t stamp0 = platform::realtimeNowNs();
  for (int k = 0; k < scans; ++k) {
    lidar.scan(static_cast<std::uint64_t>(k), points, rings);
    const std::int64_t stamp = stamp0 + k * 100'000'000LL;
    publisher.publishOdometry(stamp, lidar.poseAt(0.1 * k), "odom", "base_link");
    publisher.publishCloud(points, rings, stamp, "lidar");
    platform::sleepUntilMonotonicNs(platform::monotonicNowNs() + 100'000'000);
    clouds.poll();
    odometry.poll();
  }
  // The last messages reach the witnesses (as long as that takes on a loaded machine), and the
  // recorder, which reads the same loopback traffic, a moment more.
  const auto all = static_cast<std::size_t>(scans);
  const std::int64_t give_up = startWaitEndNs();
  do {
    platform::sleepUntilMonotonicNs(platform::monotonicNowNs() + 300'000'000);
    clouds.poll();
    odometry.poll();
  } while ((clouds.samples.size() < all || odometry.samples.size() < all) &&
           platform::monotonicNowNs() < give_up);
}

/// Records a drive of `scans` scans with `raymap record` on `domain`; the recorder is stopped
/// with `stop_signal`. Returns the witnessed clouds and odometry.
std::pair<Payloads, Payloads> recordDrive(const TempDir& dir, std::uint32_t domain,
                                          const std::string& log, int scans, int stop_signal) {
  auto publisher_participant = dds::Participant::create(domain);
  auto witness_participant = dds::Participant::create(domain);
  auto publisher = std::move(driver::DriverPublisher::create(publisher_participant.value(),
                                                             "rt/points", "rt/odom", 70000))
                       .value();
  Capture clouds(witness_participant.value(), "rt/points", dds::pointCloud2Type());
  Capture odometry(witness_participant.value(), "rt/odom", dds::odometryType());
  const std::string recorder_log = dir.file("record.log");
  auto recorder = startRaymap(
      {"record", "-o", log, "--domain", std::to_string(domain), "-t", "/points", "-t", "/odom"},
      recorder_log);
  EXPECT_TRUE(waitForText(recorder_log, "recording rt/points", kStartWaitS))
      << readFile(recorder_log);
  EXPECT_TRUE(waitForText(recorder_log, "recording rt/odom", kStartWaitS))
      << readFile(recorder_log);
  // Until the recorder's readers are matched on this side too (the witnesses' are the other
  // two), as long as that takes: best-effort data sent before would not reach it.
  const std::int64_t give_up = startWaitEndNs();
  while ((publisher->matchedCloudReaders() < 2 || publisher->matchedOdometryReaders() < 2) &&
         platform::monotonicNowNs() < give_up) {
    platform::sleepUntilMonotonicNs(platform::monotonicNowNs() + 20'000'000);
  }
  EXPECT_GE(publisher->matchedCloudReaders(), 2U);
  EXPECT_GE(publisher->matchedOdometryReaders(), 2U);
  publishDrive(*publisher, scans, clouds, odometry);
  const auto stopped = recorder->stop(stop_signal, kStopWait);
  EXPECT_TRUE(stopped.has_value());
  if (stop_signal == SIGINT) {
    EXPECT_EQ(stopped->first, 0) << readFile(recorder_log);
  }
  return {clouds.samples, odometry.samples};
}

/// Replays `log` on a fresh domain and captures what comes out.
std::pair<Payloads, Payloads> replayLog(const TempDir& dir, const std::string& log,
                                        std::string* output, int* exit_code) {
  const std::uint32_t domain = uniqueDomain();
  auto participant = dds::Participant::create(domain);
  Capture clouds(participant.value(), "rt/points", dds::pointCloud2Type());
  Capture odometry(participant.value(), "rt/odom", dds::odometryType());
  const std::string replay_log = dir.file("replay.log");
  auto replay = startRaymap(
      {"replay", log, "--domain", std::to_string(domain), "--stats-json", dir.file("replay.json")},
      replay_log);
  const std::int64_t end = platform::monotonicNowNs() + 30'000'000'000LL;
  while (replay->running() && platform::monotonicNowNs() < end) {
    clouds.poll();
    odometry.poll();
    platform::sleepUntilMonotonicNs(platform::monotonicNowNs() + 5'000'000);
  }
  const auto status = replay->stop(SIGTERM, std::chrono::milliseconds(100));
  *exit_code = status ? status->first : -1;
  clouds.poll();
  odometry.poll();
  *output = readFile(replay_log) + readFile(dir.file("replay.json"));
  return {clouds.samples, odometry.samples};
}

TEST(Record, ReplayOfARecordingReproducesTheMessagesByteForByte) {
  TempDir dir;
  const std::string log = dir.file("drive.rmlog");
  const auto [clouds, odometry] = recordDrive(dir, uniqueDomain(), log, 15, SIGINT);
  ASSERT_EQ(clouds.size(), 15U);
  ASSERT_EQ(odometry.size(), 15U);
  ASSERT_TRUE(std::filesystem::exists(log));
  EXPECT_FALSE(std::filesystem::exists(log + ".partial"));

  std::string output;
  int exit_code = -1;
  const auto [replayed_clouds, replayed_odometry] = replayLog(dir, log, &output, &exit_code);
  EXPECT_EQ(exit_code, 0) << output;
  EXPECT_EQ(jsonNumber(readFile(dir.file("replay.json")), "log_messages"), 30) << output;
  ASSERT_EQ(replayed_clouds.size(), clouds.size()) << output;
  ASSERT_EQ(replayed_odometry.size(), odometry.size()) << output;
  for (std::size_t i = 0; i < clouds.size(); ++i) {
    EXPECT_EQ(replayed_clouds[i], clouds[i]) << "cloud " << i << " differs";
    EXPECT_EQ(replayed_odometry[i], odometry[i]) << "odometry " << i << " differs";
  }
}

TEST(Record, AKilledRecorderLeavesALogThatReplaysToTheLastCompleteMessage) {
  TempDir dir;
  const std::string log = dir.file("killed.rmlog");
  const auto [clouds, odometry] = recordDrive(dir, uniqueDomain(), log, 10, SIGKILL);
  ASSERT_EQ(clouds.size(), 10U);
  EXPECT_FALSE(std::filesystem::exists(log)) << "only a clean stop renames the log";
  const std::string partial = log + ".partial";
  ASSERT_TRUE(std::filesystem::exists(partial));
  // SIGKILL between two records leaves whole records; one arriving inside a write leaves part of
  // the last one. Make that happen: cut the file inside its last record (a cloud of ~100 KB).
  std::filesystem::resize_file(partial, std::filesystem::file_size(partial) - 1000);

  std::string output;
  int exit_code = -1;
  const auto [replayed_clouds, replayed_odometry] = replayLog(dir, partial, &output, &exit_code);
  EXPECT_EQ(exit_code, 0) << output;
  EXPECT_NE(output.find("interrupted"), std::string::npos) << output;
  EXPECT_EQ(jsonNumber(readFile(dir.file("replay.json")), "logs_truncated"), 1) << output;
  // Everything but the cut cloud, unchanged.
  ASSERT_EQ(replayed_clouds.size(), 9U) << output;
  ASSERT_EQ(replayed_odometry.size(), 10U) << output;
  for (std::size_t i = 0; i < replayed_clouds.size(); ++i) {
    EXPECT_EQ(replayed_clouds[i], clouds[i]) << "cloud " << i << " differs";
  }
}

TEST(Record, CorruptLogsAndUndecodableMessagesGetClearErrors) {
  TempDir dir;
  // A log with one good odometry message and one "cloud" whose bytes are not a PointCloud2.
  const std::string log = dir.file("mixed.rmlog");
  {
    auto writer = std::move(record::RecordLogWriter::create(log)).value();
    const auto odom =
        writer->addTopic("rt/odom", "nav_msgs::msg::dds_::Odometry_",
                         record::LogReliability::kBestEffort, record::LogDurability::kVolatile);
    const auto points =
        writer->addTopic("rt/points", "sensor_msgs::msg::dds_::PointCloud2_",
                         record::LogReliability::kBestEffort, record::LogDurability::kVolatile);
    const auto other =
        writer->addTopic("rt/chatter", "std_msgs::msg::dds_::String_",
                         record::LogReliability::kReliable, record::LogDurability::kVolatile);
    std::vector<std::byte> garbage(64, std::byte{0x7F});
    garbage[0] = std::byte{0};
    garbage[1] = std::byte{1};  // CDR little endian, then nonsense lengths
    const std::int64_t now = platform::monotonicNowNs();
    ASSERT_TRUE(writer->write(points.value(), 0, now, 0, garbage).has_value());
    ASSERT_TRUE(writer->write(other.value(), 0, now + 1000, 0, garbage).has_value());
    (void)odom;
    ASSERT_TRUE(writer->close().has_value());
  }
  const RunResult mixed = runRaymap({"replay", log, "--domain", std::to_string(uniqueDomain()),
                                     "--wait", "0", "--stats-json", "-"});
  EXPECT_EQ(mixed.exit_code, 0) << describe(mixed);
  EXPECT_NE(mixed.err.find("rt/chatter has type std_msgs::msg::dds_::String_"), std::string::npos)
      << describe(mixed);
  EXPECT_NE(mixed.err.find("is not a valid sensor_msgs::msg::dds_::PointCloud2_"),
            std::string::npos)
      << describe(mixed);
  EXPECT_EQ(jsonNumber(mixed.out, "log_messages_undecodable"), 1) << describe(mixed);

  // A flipped byte inside a record: the checksum names the file and the record.
  std::string bytes = readFile(log);
  bytes[bytes.size() - 40] = static_cast<char>(bytes[bytes.size() - 40] ^ 0x5A);
  const std::string corrupt = dir.file("corrupt.rmlog");
  std::ofstream(corrupt, std::ios::binary) << bytes;
  const RunResult bad =
      runRaymap({"replay", corrupt, "--domain", std::to_string(uniqueDomain()), "--wait", "0"});
  EXPECT_EQ(bad.exit_code, 1) << describe(bad);
  EXPECT_NE(bad.err.find(corrupt), std::string::npos) << describe(bad);
  EXPECT_NE(bad.err.find("record"), std::string::npos) << describe(bad);

  // Not a log and not a PLY.
  const std::string text = dir.file("notes.txt");
  std::ofstream(text) << "hello\n";
  const RunResult neither = runRaymap({"replay", text, "--wait", "0"});
  EXPECT_EQ(neither.exit_code, 1) << describe(neither);
  EXPECT_NE(neither.err.find(text), std::string::npos) << describe(neither);
}

}  // namespace
}  // namespace raymap::test
