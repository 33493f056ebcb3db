// SPDX-License-Identifier: BSD-3-Clause
// Turns the pipeline's counters and histograms into a diagnostic_msgs/DiagnosticArray, a systemd
// status line and a log line per report while anything is wrong, once per diagnostics period.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "src/dds/diagnostics_message.hpp"
#include "src/pipeline/pipeline_stats.hpp"
#include "src/pipeline/pose_update.hpp"
#include "src/pipeline/scan_mailbox.hpp"
#include "src/service/pending_scans.hpp"

namespace raymap::service {

struct RealtimeReport;

/// @brief What the reporter is told once, at start-up.
struct ReporterSettings {
  std::string name = "raymapd";  ///< status names are "<name>: pipeline", ...
  std::string hardware_id;       ///< diagnostic_msgs hardware_id of every status
  std::string backend;
  std::string device;
  double publish_rate_hz = 5.0;
  double report_rate_hz = 1.0;
  double stale_after_s = 1.0;  ///< no scan integrated for this long: ERROR
  /// Before the first cloud: WARN "waiting for the first cloud" this long after start, then the
  /// staleness ERROR (health.startup_grace_s).
  double startup_grace_s = 10.0;
  /// Rays integrated over rays offered within the window below this: WARN; none of them: ERROR
  /// (health.min_integrated_fraction).
  double min_integrated_fraction = 0.5;
  std::string grid_map_topic;              ///< named when another publisher of it is found
  std::vector<std::string> sensor_frames;  ///< sensors[].frame ("" = any), for the reasons
  /// The DDS sockets' receive buffer asked for (bytes; 0: left to Cyclone) and what the sensors'
  /// clouds want (service::planReceiveBuffer), reported as values.
  std::uint64_t receive_buffer_bytes = 0;
  std::uint64_t receive_buffer_wanted_bytes = 0;
  /// DDS Security as the service started (security::SecurityOutcome): a status "<name>:
  /// security", WARN with `security_warning` when that is set (running without the security
  /// asked for, Permissive; keys about to expire), else OK with `security_summary`; the systemd
  /// status line ends with "security on" or "security OFF".
  bool secure = false;
  std::string security_summary = "DDS Security: off";
  std::string security_warning;
  /// One per configured sensor (same order): a status "<name>: sensor <sensor.name>" each.
  struct Sensor {
    std::string name;
    std::string topic;
    std::string camera_info_topic;  ///< depth cameras; empty for point clouds
    double max_rate_hz = 0.0;
  };
  std::vector<Sensor> sensors;
};

/// @brief Writers of the service's inputs found by discovery (matched publications), read by the
/// diagnostics thread each report. One writer per input is expected; a second publisher of a
/// sensor's topic puts its clouds into the map, a second odometry publisher interleaves two
/// robots' poses.
struct InputPublishers {
  std::array<std::uint32_t, pipeline::kMaxSensors> clouds{};       ///< of sensors[i].topic
  std::array<std::uint32_t, pipeline::kMaxSensors> camera_info{};  ///< of camera_info_topic
  /// Of pose.topic (pose.source odometry), or of base_frame's transform on rt/tf seen within
  /// the last second (pose.source tf: /tf itself has many writers by design).
  std::uint32_t odometry = 0;
  std::string odometry_topic;           ///< what `odometry` counts the writers of (start-up)
  std::string pose_key = "pose.topic";  ///< the configuration key naming it
  /// Who the writers of inputs with more than one are ("" while each has at most one).
  const char* who = "";
};

/// @brief The diagnostics thread's state: a ring of snapshots (rates, drops and percentiles are
/// differences over a window of at least one second, whatever the report rate) and the
/// preallocated message.
///
/// Levels (docs/raymapd.md, Diagnostics):
/// - pipeline ERROR: no scan integrated for stale_after_s while running (also before the first
///   one, once stale_after_s has passed since start and a cloud came or startup_grace_s passed),
///   no ray of those offered within the window integrated, another publisher of the height-map
///   topic on the domain, or backend failures; WARN: waiting for the first cloud (within
///   startup_grace_s), fewer than min_integrated_fraction of the offered rays integrated, any
///   input dropped within the window (missing by the gaps in their stamps, datagrams dropped by
///   a full socket buffer, wrong frame, malformed, too large, no pose, overflow, points with bad
///   times); the message names the reasons with their counts.
/// - height map ERROR while maps are withheld (stale), WARN for late or failed cycles.
/// - real time WARN when requested settings were refused.
/// Thread-safety: one thread (diagnostics). Reads the counters other threads write.
/// @rt not a real-time thread; still allocates nothing after construction (fixed buffers).
class DiagnosticsReporter {
 public:
  /// @param started_ns when the service started (monotonic): the staleness rule's origin.
  DiagnosticsReporter(const pipeline::PipelineStats& stats, const pipeline::ScanMailbox& mailbox,
                      const pipeline::PoseQueue& poses, ReporterSettings settings,
                      std::int64_t started_ns);

  /// @brief Scans the ingest thread holds undecoded: counted in `scan_queue_depth` with the
  /// mailbox's (start-up, before update() runs).
  void countHeldScans(const PendingScans* pending) noexcept { pending_ = pending; }

  /// @brief Takes a snapshot at `now_ns` (monotonic) and decides the levels and messages.
  /// @param other_map_publishers writers of the height-map topic in other participants
  /// @param inputs writers of the inputs (nullptr: not known; each counted as one)
  void update(std::int64_t now_ns, const RealtimeReport& realtime,
              std::uint32_t other_map_publishers, const InputPublishers* inputs = nullptr) noexcept;
  /// @brief The DiagnosticArray of the last update(), stamped `stamp_ns` (wall clock).
  const void* message(std::int64_t stamp_ns) noexcept;
  /// @brief One line for `systemctl status` (STATUS=).
  const char* statusLine() const noexcept { return status_line_; }
  /// @brief Logs one line per status that is not OK, naming the reason.
  void logChanges() noexcept;
  /// @brief The pipeline status's level after the last update (msgs::kDiagnosticOk, ...).
  std::uint8_t pipelineLevel() const noexcept { return pipeline_level_; }
  /// @brief The pipeline status's message after the last update ("ok", or the reasons).
  const char* pipelineMessage() const noexcept { return pipeline_message_; }
  /// @brief Backend failures within the window (the one ERROR a restart can clear).
  bool backendFailing() const noexcept { return backend_failing_; }
  /// @brief The height-map status's level after the last update.
  std::uint8_t heightmapLevel() const noexcept { return heightmap_level_; }

 private:
  struct Totals {
    std::uint64_t clouds = 0, malformed = 0, too_large = 0, wrong_frame = 0, overflow = 0;
    std::uint64_t overflow_undecoded = 0;         // of overflow, dropped before decoding
    std::uint64_t missing = 0, socket_drops = 0;  // lost before they were taken
    std::uint64_t scans = 0, no_pose = 0, rays = 0, rejected = 0, no_return = 0, bad_time = 0;
    std::uint64_t scans_empty = 0, invalid = 0, too_short = 0, out_of_bounds = 0;
    std::uint64_t outside_window = 0, too_near = 0;
    std::uint64_t time_resets = 0, pose_jumps = 0, window_clears = 0;
    std::uint64_t scans_shed = 0, scans_cut_short = 0, points_shed = 0;
    std::uint64_t maps = 0, withheld = 0, late = 0, hm_errors = 0, integrate_errors = 0;
    std::uint64_t poses = 0, poses_malformed = 0, poses_dropped = 0;
    std::array<std::uint64_t, msgs::kCloudErrorCount> rejected_by{};
    std::array<std::uint64_t, msgs::kDepthImageErrorCount> image_rejected_by{};
    std::array<std::uint64_t, msgs::kCameraInfoErrorCount> camera_info_rejected_by{};
    struct PerSensor {
      std::uint64_t received = 0, accepted = 0, rate_limited = 0, rejected = 0;
      std::uint64_t no_camera_info = 0, camera_info = 0, camera_info_bad = 0, scans = 0;
      std::uint64_t missing = 0;
    };
    std::array<PerSensor, pipeline::kMaxSensors> sensor{};
  };
  /// One report's snapshot.
  struct Sample {
    std::int64_t ns = 0;
    Totals totals;
    pipeline::DurationHistogram::Snapshot latency, period, generate, hold, wait;
    pipeline::DurationHistogram::Snapshot cycle_hold, sync_bytes, heightmap_bytes, transfer_bytes;
  };
  Totals read() const noexcept;
  /// Fills `s` with the counters and histograms now, stamped `ns`.
  void take(Sample& s, std::int64_t ns) const noexcept;
  /// The newest sample at least one window older than the current one (else the oldest).
  const Sample& windowBase() const noexcept;
  void decide(std::uint32_t other_map_publishers) noexcept;
  /// decide()'s parts: the pipeline message's waiting or stale part (`last`: when the last scan
  /// went in, 0 if none), and the height map's level and message.
  void describeStaleness(const Sample& now, std::int64_t last) noexcept;
  void decideHeightmap(const Sample& now) noexcept;
  /// Appends the inputs with more than one publisher to `out`. @return whether a pose source
  /// has more than one (ERROR) and, in `extra_sensor`, whether a sensor's topic has (WARN).
  bool describePublishers(char* out, std::size_t size, bool* extra_sensor) const noexcept;
  /// Writes every input dropped within the window, with its count, to drop_reasons_
  /// ("; "-separated; empty when nothing was dropped: that is what "dropping" means).
  void describeDrops() noexcept;
  // describeDrops()'s parts, each appending to drop_reasons_ after `sep` and setting it to "; ".
  void describeFrameDrops(const Totals& c, const Totals& b, const char*& sep) noexcept;
  void describeCameraDrops(const Totals& c, const Totals& b, const char*& sep) noexcept;
  void describePoseResets(const Totals& c, const Totals& b, const char*& sep) noexcept;
  /// Rays integrated within the window, and rays offered: those plus the rejected ones and the
  /// depth blocks nearer than min range (points without a return are not offered).
  struct RaysInWindow {
    std::uint64_t integrated = 0;
    std::uint64_t offered = 0;
  };
  RaysInWindow raysInWindow() const noexcept;
  /// Writes to `out` how many of the rays offered within the window were integrated and why the
  /// others were not. @return the level that says: OK, WARN below min_integrated_fraction,
  /// ERROR for none.
  std::uint8_t describeIntegration(char* out, std::size_t size) const noexcept;
  /// Adds the status of sensor `i` (its counters over the window) to message_.
  struct Window;  // the rate window (diagnostics_reporter.cpp)
  void addInputValues(int status, const Window& w) noexcept;
  void addIntegrationValues(int status, const Window& w) noexcept;
  void addQueueValues(int status, const Window& w) noexcept;
  void addHeightmapStatus(const Window& w, const char* hardware_id) noexcept;
  void addRealtimeAndSecurityStatuses(const char* hardware_id) noexcept;
  void addSensorStatus(std::size_t i, double dt) noexcept;

  const pipeline::PipelineStats& stats_;
  const pipeline::ScanMailbox& mailbox_;
  const PendingScans* pending_ = nullptr;
  const pipeline::PoseQueue& poses_;
  ReporterSettings settings_;
  std::string pipeline_name_, heightmap_name_, realtime_name_, security_name_;
  std::int64_t started_ns_;
  std::int64_t window_ns_;
  dds::DiagnosticsMessage message_;
  bool has_depth_;  ///< a depth camera is configured: its reasons and counters are reported
  std::vector<Sample> ring_;  // fixed size; ring_[head_] is the newest
  std::size_t head_ = 0;
  std::size_t filled_ = 1;  // samples in ring_; the first, the start, taken by the constructor
  const Sample* base_ = nullptr;  // windowBase() of the last update
  const RealtimeReport* realtime_ = nullptr;
  const InputPublishers* inputs_ = nullptr;
  std::uint32_t other_publishers_ = 0;
  double seconds_since_scan_ = 0.0;
  bool stale_ = false;
  bool waiting_first_ = false;  // no cloud yet, within startup_grace_s
  bool backend_failing_ = false;
  std::uint8_t pipeline_level_ = 0;
  std::uint8_t heightmap_level_ = 0;
  char pipeline_message_[1024] = {};
  char drop_reasons_[768] = {};
  char heightmap_message_[128] = {};
  char status_line_[256] = {};
};

}  // namespace raymap::service
