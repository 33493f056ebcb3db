// SPDX-License-Identifier: BSD-3-Clause
// Recorded data published over DDS as a lidar driver and a localisation stack would, from ray
// files (PLY), raymap record logs and rosbag2 bags: the engine of `raymap replay`, usable from any
// program that wants to feed a live mapper (raymapd, a ROS 2 node) from a recording.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "raymap/error.hpp"

#include "src/bag/bag_reader.hpp"
#include "src/dds/cdr_writer.hpp"
#include "src/dds/entities.hpp"
#include "src/driver/ros_endpoints.hpp"
#include "src/io/ray_source.hpp"
#include "src/record/record_log.hpp"
#include "src/replay/recorded_scans.hpp"
#include "src/replay/replay_clock.hpp"

namespace raymap::replay {

/// Between the end of one input (or pass) and the start of the next, in replay time, when the
/// input's scan spacing is unknown (one scan) or logs: keeps stamps strictly increasing and reads
/// as a short pause of the sensor. Seconds. Ray files with several scans continue one scan
/// spacing after their last scan started instead.
inline constexpr double kGapBetweenInputsSeconds = 0.1;

struct ReplayStats;

/// @brief Where a replay is, for a progress display. Valid during the callback only.
struct ReplayProgress {
  const ReplayStats& stats;     ///< what was published so far
  std::string_view input;       ///< the input being played (empty when finished)
  double input_fraction = 0.0;  ///< how far into it, 0 to 1
  double elapsed_s = 0.0;       ///< wall-clock seconds since publishing started
  double max_late_ms = 0.0;     ///< the furthest the replay fell behind the recording so far
  bool finished = false;        ///< the last call, after every pass
};

/// @brief How to replay (the options of `raymap replay`, documented in docs/cli.md; messages
/// name them as `replay.<field>`).
struct ReplayOptions {
  std::vector<std::string> inputs;
  double rate = 1.0;        ///< data seconds per second; 0 = as fast as the subscriber keeps up
  bool loop = false;        ///< start over after the last input, until stopped
  double start_s = 0.0;     ///< skip this much of each input's data
  double duration_s = 0.0;  ///< then play this much of it (0 = to the end)
  std::uint32_t domain = 0;
  // Ray files: what is published, and how.
  io::RaySourceOptions source;
  std::string cloud_topic = "rt/points";
  std::string odometry_topic = "rt/odom";
  bool pose_odometry = true;  ///< nav_msgs/Odometry on odometry_topic
  bool pose_tf = false;       ///< tf2_msgs/TFMessage world -> base on rt/tf
  bool tf_static = true;      ///< base -> sensor frame, identity, latched on rt/tf_static
  std::string frame = "lidar";
  std::string world_frame = "odom";
  std::string base_frame = "base_link";
  double pose_period_s = 0.01;  ///< odometry about every 10 ms (100 Hz), like a state estimator
  // Start and flow control.
  double wait_s = 10.0;  ///< wait this long for a subscriber of the first published topic
  std::string diagnostics_topic = "rt/diagnostics";  ///< --rate max: raymapd's progress
  std::uint32_t max_ahead = 2;  ///< --rate max: scans published but not yet processed
  bool skip_damaged = false;    ///< bags: play what a damaged bag holds (BagReadOptions)
  /// Logs and bags: also publish what a mapping service publishes (diagnostic_msgs and
  /// grid_map_msgs topics). Off: a recording's /diagnostics would carry the recorded service's
  /// statuses beside the live one's (and --rate max would pace on them).
  bool include_outputs = false;
  /// Called on run()'s thread after each published cloud, pose batch or log message, and once
  /// more with `finished` at the end: a display throttles itself. Optional.
  std::function<void(const ReplayProgress&)> on_progress;
  /// Called once on run()'s thread when the replay starts to wait (up to wait_s) for a
  /// subscriber of `topic`. Optional.
  std::function<void(const std::string& topic)> on_waiting;
};

/// @brief What a replay did (the --stats-json keys, docs/cli.md).
struct ReplayStats {
  std::uint64_t passes = 0;       ///< complete passes over all inputs
  std::uint64_t scans = 0;        ///< point clouds published (ray files and logs)
  std::uint64_t points = 0;       ///< points in them (ray files)
  std::uint64_t poses = 0;        ///< odometry / TF pose samples published (ray files)
  std::uint64_t messages = 0;     ///< messages published from logs (clouds included)
  std::uint64_t undecodable = 0;  ///< log messages that were not their topic's type (skipped)
  std::uint64_t origin_conflicts = 0;
  std::uint64_t truncated_logs = 0;
  std::uint64_t feedback_timeouts = 0;  ///< --rate max: no progress report for 2 s
  double data_seconds = 0.0;            ///< recorded time played
  double wall_seconds = 0.0;
  double max_late_ms = 0.0;
  /// The stamp of replay time zero (ns since the epoch): a ray file's first scan is stamped
  /// with it (after --start), so a subscriber can tell which scans a stamp covers.
  std::int64_t stamp_zero_ns = 0;
  std::vector<std::string> warnings;
};

/// @brief One replay: the DDS endpoints, the clock and the statistics. Not thread-safe: create
/// and run it on one thread. Not real-time: it reads files and allocates as it plays.
class ReplaySession {
 public:
  static Result<std::unique_ptr<ReplaySession>> create(const ReplayOptions& options,
                                                       platform::ShutdownSignals signals);
  /// @brief Plays every input once per pass, passes until done (or forever with --loop).
  Result<ReplayStats> run();

 private:
  explicit ReplaySession(const ReplayOptions& options, platform::ShutdownSignals signals);
  Result<void> playRayFile(const std::string& path);
  /// A ray file's scan `driver_scan_` with its pose knots, each when it is due. False: stopped.
  bool publishDriverScan(std::int64_t stamp_of_zero, double& played_until_s);
  /// Where the next input starts after a ray file whose last scan started at `last_scan_start_s`
  /// with `scan_spacing_s` between scans (either unknown: a short gap after its last cloud).
  void advancePastRayFile(std::optional<double> last_scan_start_s,
                          std::optional<double> scan_spacing_s, double played_until_s);
  Result<void> playLog(const std::string& path);
  /// A rosbag2 bag (replay_bag.cpp): every message of a type raymap knows, on its topic
  /// (/x -> rt/x) with the QoS the bag recorded, at its recorded spacing (log time).
  Result<void> playBag(const std::string& path);
  enum class Sent : std::uint8_t { kSent, kRefused, kStopped };
  /// The writers of a log's or a bag's topics, by topic index (nullptr: not played), which of
  /// them carry scans (clouds or depth images: paced when unpaced), and the first such topic.
  struct TopicWriters {
    std::vector<dds::CdrWriter*> writers;
    std::vector<bool> scans;
    std::vector<bool> warned;  // a message of the topic was refused and said so
    dds::CdrWriter* first_scan = nullptr;
    std::string first_scan_topic;
    void add(std::size_t index, dds::CdrWriter* writer, bool scan, const std::string& topic);
    dds::CdrWriter* at(std::size_t index) const noexcept {
      return index < writers.size() ? writers[index] : nullptr;
    }
  };
  /// A log's writers, one per recorded topic with its recorded QoS.
  Result<TopicWriters> logTopicWriters(const std::string& path,
                                       const std::vector<record::LogTopic>& topics);
  /// A bag's writers, with the QoS of its offered_qos_profiles.
  Result<TopicWriters> bagTopicWriters(const std::string& path, const bag::BagReader& reader);
  /// Waits for a subscriber of the first scan topic (none: no wait). False: stopped.
  bool waitForScanSubscriber(const TopicWriters& topics);
  /// Sends message `number` of topic `index` (on `topic`, of `type`) at `t` seconds after its
  /// input's first message; a refused message is reported once per topic, naming `path`.
  Sent playRecorded(TopicWriters& topics, std::size_t index, double t,
                    std::span<const std::byte> cdr, double& played_until_s, const std::string& path,
                    std::uint64_t number, const std::string& topic, const std::string& type);
  /// Sends one recorded message at `t` seconds after its input's first message (paced by the
  /// clock; --rate max waits for room first for clouds) and counts it.
  Sent sendRecorded(dds::CdrWriter& writer, bool cloud, double t, std::span<const std::byte> cdr,
                    double& played_until_s);
  /// Whether a topic of `type` is a mapping service's output that is not replayed (without
  /// include_outputs); says so in the warnings, naming `path` and `topic`.
  bool leavesOutServiceOutput(const std::string& path, const std::string& topic,
                              const std::string& type);
  Result<dds::CdrWriter*> logWriter(const std::string& topic, const std::string& type,
                                    bool reliable, bool transient_local);
  /// Waits (once per session, up to --wait) for a subscriber: data sent before discovery
  /// completes is lost on best-effort topics.
  bool waitForSubscriber(const std::function<std::uint32_t()>& matched, const std::string& topic);
  /// --rate max: blocks until the subscriber has processed all but max_ahead clouds.
  bool waitForRoom();
  void reportProgress(double input_fraction, const std::string& input, bool finished = false);

  ReplayOptions options_;
  ReplayClock clock_;
  std::optional<dds::Participant> participant_;
  std::unique_ptr<driver::DriverPublisher> driver_;
  std::unique_ptr<driver::DiagnosticsListener> feedback_;
  std::map<std::string, dds::CdrWriter> log_writers_;
  ReplayStats stats_;
  double pass_offset_s_ = 0.0;  ///< replay time at which the current input starts
  bool waited_for_subscriber_ = false;
  /// --rate max: the subscriber's processed-cloud count minus our clouds, at the first report.
  std::optional<double> processed_baseline_;
  RecordedScan scan_;
  DriverScan driver_scan_;
};

}  // namespace raymap::replay
