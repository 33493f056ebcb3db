// SPDX-License-Identifier: BSD-3-Clause
// `raymap replay`'s engine as a library (src/replay): a program that feeds a mapper from a
// recording gets the same session, its progress through callbacks and its warnings by
// configuration key. The CLI tests (test_replay.cpp) follow the published data into raymapd.
#include <array>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "platform/clock.hpp"
#include "platform/signals.hpp"
#include "src/driver/ros_endpoints.hpp"
#include "src/msgs/pose.hpp"
#include "src/record/record_log_reader.hpp"
#include "src/replay/replay_session.hpp"
#include "src/replay/topic_recorder.hpp"
#include "tests/service/service_fixture.hpp"
#include "tests/support/cli_runner.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::test {
namespace {

/// The yard drive: `scans` scans of the simulated 32 x 1024 lidar as a ray-cloud PLY.
std::string yardRays(const TempDir& dir, int scans) {
  std::string path = dir.file("yard.ply");
  const RunResult r = runRaymap({"simulate", std::string(RAYMAP_SCENES_DIR) + "/yard.yaml",
                                 "--rays", path, "--scans", std::to_string(scans), "-q"});
  EXPECT_EQ(r.exit_code, 0) << describe(r);
  return path;
}

/// What the callbacks saw.
struct Seen {
  std::vector<std::string> waited_for;
  std::vector<double> fractions;
  std::vector<std::uint64_t> clouds;
  int finished = 0;
  bool finished_last = false;
};

replay::ReplayOptions optionsFor(const std::string& input, Seen& seen) {
  replay::ReplayOptions options;
  options.inputs = {input};
  options.domain = uniqueDomain();
  options.rate = 50.0;  // 0.5 s of data in about 10 ms
  options.wait_s = 0.05;
  options.on_waiting = [&seen](const std::string& topic) { seen.waited_for.push_back(topic); };
  options.on_progress = [&seen](const replay::ReplayProgress& p) {
    if (p.finished) {
      ++seen.finished;
    } else {
      seen.fractions.push_back(p.input_fraction);
      seen.clouds.push_back(p.stats.scans);
    }
    seen.finished_last = p.finished;
  };
  return options;
}

TEST(ReplayLibrary, ASessionPublishesEveryScanAndReportsItsProgress) {
  TempDir dir;
  const std::string input = yardRays(dir, 5);
  Seen seen;
  const replay::ReplayOptions options = optionsFor(input, seen);
  auto session = replay::ReplaySession::create(options, platform::ShutdownSignals::install());
  ASSERT_TRUE(session.has_value()) << session.error().message;
  const Result<replay::ReplayStats> stats = session.value()->run();
  ASSERT_TRUE(stats.has_value()) << stats.error().message;
  EXPECT_EQ(stats->passes, 1u);
  EXPECT_EQ(stats->scans, 5u);
  EXPECT_EQ(stats->points, 5u * 32u * 1024u);
  EXPECT_GT(stats->poses, 5u);  // poses every 10 ms of data through each scan

  // Nobody subscribed: the session said once that it waited, then published anyway.
  EXPECT_EQ(seen.waited_for, std::vector<std::string>{"rt/points"});
  ASSERT_EQ(stats->warnings.size(), 1u);
  EXPECT_NE(stats->warnings[0].find("no subscriber of rt/points"), std::string::npos)
      << stats->warnings[0];
  // One report per cloud, in order, and the summary last.
  ASSERT_EQ(seen.clouds.size(), 5u);
  for (std::size_t i = 0; i < seen.clouds.size(); ++i) {
    EXPECT_EQ(seen.clouds[i], i + 1);
    EXPECT_GT(seen.fractions[i], 0.0);
    EXPECT_LE(seen.fractions[i], 1.0);
    if (i > 0) {
      EXPECT_GE(seen.fractions[i], seen.fractions[i - 1]);
    }
  }
  EXPECT_EQ(seen.finished, 1);
  EXPECT_TRUE(seen.finished_last);
}

// Unpaced (rate 0) follows raymapd's progress reports; with no raymapd to report, the session
// publishes unpaced and says so naming its option by key, which raymap turns into "--rate max".
TEST(ReplayLibrary, UnpacedWithoutAServiceWarnsByConfigurationKey) {
  TempDir dir;
  const std::string input = yardRays(dir, 2);
  Seen seen;
  replay::ReplayOptions options = optionsFor(input, seen);
  options.rate = 0.0;
  auto session = replay::ReplaySession::create(options, platform::ShutdownSignals::install());
  ASSERT_TRUE(session.has_value()) << session.error().message;
  const Result<replay::ReplayStats> stats = session.value()->run();
  ASSERT_TRUE(stats.has_value()) << stats.error().message;
  EXPECT_EQ(stats->scans, 2u);
  EXPECT_EQ(stats->feedback_timeouts, 1u);
  bool named = false;
  for (const std::string& warning : stats->warnings) {
    named = named || warning.starts_with("replay.rate: max: no progress report on rt/diagnostics");
  }
  EXPECT_TRUE(named) << ::testing::PrintToString(stats->warnings);
}

TEST(ReplayLibrary, AnInputThatIsNoRecordingIsAnErrorNamingIt) {
  TempDir dir;
  const std::string input = dir.file("notes.ply");
  std::ofstream(input) << "this is not a PLY file\n";
  Seen seen;
  auto session =
      replay::ReplaySession::create(optionsFor(input, seen), platform::ShutdownSignals::install());
  ASSERT_TRUE(session.has_value()) << session.error().message;
  const Result<replay::ReplayStats> stats = session.value()->run();
  ASSERT_FALSE(stats.has_value());
  EXPECT_NE(stats.error().message.find(input), std::string::npos) << stats.error().message;
  EXPECT_EQ(seen.clouds.size(), 0u);
}

// `raymap record`'s engine beside a program's own publisher: it finds the requested topic's
// writer, reads it with the writer's QoS (reliable), writes every message's bytes, stops when
// asked, and says which requested topic it never saw.
TEST(ReplayLibrary, ARecorderWritesEveryMessageOfARequestedTopicUntilAskedToStop) {
  TempDir dir;
  const std::uint32_t domain = uniqueDomain();
  replay::RecordOptions options;
  options.output = dir.file("tf.rmlog");
  options.topics = {"rt/nothing", "rt/tf"};
  options.domain = domain;
  std::vector<std::string> notices;
  options.on_notice = [&notices](const std::string& line) { notices.push_back(line); };
  auto recorder = replay::TopicRecorder::create(options);
  ASSERT_TRUE(recorder.has_value()) << recorder.error().message;
  Result<replay::RecordStats> stats = fail(ErrorCode::kUnsupported, "not run");
  std::thread recording(
      [&] { stats = recorder.value()->run(platform::ShutdownSignals::install()); });

  auto participant = dds::Participant::create(domain);
  ASSERT_TRUE(participant.has_value());
  auto publisher = driver::DriverPublisher::create(*participant, "rt/points", "rt/odom", 1);
  ASSERT_TRUE(publisher.has_value()) << publisher.error().message;
  const std::int64_t give_up = platform::monotonicNowNs() + 30'000'000'000;
  while (publisher.value()->matchedTfReaders() == 0 && platform::monotonicNowNs() < give_up) {
    platform::sleepUntilMonotonicNs(platform::monotonicNowNs() + 10'000'000);
  }
  EXPECT_EQ(publisher.value()->matchedTfReaders(), 1u);
  constexpr int kMessages = 20;
  for (int i = 0; i < kMessages; ++i) {
    io::Pose pose;
    pose.position.x() = 0.5 * i;
    publisher.value()->publishTf(1'000'000'000 + i, pose, "odom", "base_link");
  }
  EXPECT_TRUE(participant->waitForAcknowledgements(30'000'000'000));
  recorder.value()->requestStop();
  recording.join();
  ASSERT_TRUE(stats.has_value()) << stats.error().message;

  EXPECT_EQ(stats->messages, static_cast<std::uint64_t>(kMessages));
  ASSERT_EQ(stats->topics.size(), 2u);
  EXPECT_EQ(stats->topics[0].topic, "rt/nothing");
  EXPECT_FALSE(stats->topics[0].seen);
  EXPECT_EQ(stats->topics[1].topic, "rt/tf");
  EXPECT_TRUE(stats->topics[1].seen);
  EXPECT_EQ(stats->topics[1].messages, static_cast<std::uint64_t>(kMessages));
  EXPECT_EQ(notices,
            std::vector<std::string>{"recording rt/tf (tf2_msgs/msg/TFMessage, reliable)"});

  // The log holds the messages in order, each the transform that was sent.
  auto log = record::RecordLogReader::open(options.output);
  ASSERT_TRUE(log.has_value()) << log.error().message;
  int read = 0;
  for (;;) {
    auto message = log.value()->next();
    ASSERT_TRUE(message.has_value()) << message.error().message;
    if (!message.value()) {
      break;
    }
    std::array<msgs::StampedTransform, 1> transform{};
    const auto decoded = msgs::decodeTfMessage(message.value()->cdr, transform);
    ASSERT_TRUE(decoded.has_value());
    EXPECT_EQ(transform[0].stamp_ns, 1'000'000'000 + read);
    EXPECT_EQ(transform[0].tx, 0.5 * read);
    ++read;
  }
  EXPECT_EQ(read, kMessages);
}

}  // namespace
}  // namespace raymap::test
