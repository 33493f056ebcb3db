// SPDX-License-Identifier: BSD-3-Clause
// Turns the pipeline's counters and histograms into a diagnostic_msgs/DiagnosticArray, a systemd
// status line and log lines about what changed, once per diagnostics period.
#pragma once

#include <cstdint>
#include <string>

#include "src/dds/diagnostics_message.hpp"
#include "src/pipeline/pipeline_stats.hpp"
#include "src/pipeline/pose_update.hpp"
#include "src/pipeline/scan_mailbox.hpp"

namespace raymap::service {

struct RealtimeReport;

/// @brief The diagnostics thread's state: the previous snapshot (rates and interval percentiles
/// are differences between two snapshots) and the preallocated message.
/// Thread-safety: one thread (diagnostics). Reads the counters other threads write.
/// @rt not a real-time thread; still allocates nothing after construction (fixed buffers).
class DiagnosticsReporter {
 public:
  DiagnosticsReporter(const pipeline::PipelineStats& stats, const pipeline::ScanMailbox& mailbox,
                      const pipeline::PoseQueue& poses, std::string backend, std::string device,
                      double publish_rate_hz);

  /// @brief Takes a snapshot at `now_ns` (monotonic) and fills the message and status line.
  void update(std::int64_t now_ns, const RealtimeReport& realtime) noexcept;
  /// @brief The DiagnosticArray of the last update(), stamped `stamp_ns` (wall clock).
  const void* message(std::int64_t stamp_ns) noexcept;
  /// @brief One line for `systemctl status` (STATUS=).
  const char* statusLine() const noexcept { return status_line_; }
  /// @brief Logs new drops, malformed input and late cycles since the previous update.
  void logChanges() noexcept;

 private:
  struct Totals {
    std::uint64_t clouds = 0, malformed = 0, too_large = 0, unknown_frame = 0, overflow = 0;
    std::uint64_t scans = 0, no_pose = 0, rays = 0, rejected = 0, no_return = 0;
    std::uint64_t maps = 0, late = 0, hm_errors = 0, integrate_errors = 0;
    std::uint64_t poses = 0, poses_malformed = 0, poses_dropped = 0;
  };
  Totals read() const noexcept;

  const pipeline::PipelineStats& stats_;
  const pipeline::ScanMailbox& mailbox_;
  const pipeline::PoseQueue& poses_;
  std::string backend_;
  std::string device_;
  double publish_rate_hz_;
  dds::DiagnosticsMessage message_;
  pipeline::DurationHistogram::Snapshot latency_prev_, period_prev_, generate_prev_;
  pipeline::DurationHistogram::Snapshot latency_now_, period_now_, generate_now_;
  Totals previous_{};
  Totals current_{};
  std::int64_t previous_ns_ = 0;
  std::int64_t now_ns_ = 0;
  char status_line_[256] = {};
  const RealtimeReport* realtime_ = nullptr;
};

}  // namespace raymap::service
