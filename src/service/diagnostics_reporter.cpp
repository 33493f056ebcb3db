// SPDX-License-Identifier: BSD-3-Clause
// DiagnosticsReporter: three statuses (pipeline, height map, real time) with stable keys.
#include "src/service/diagnostics_reporter.hpp"

#include <cinttypes>
#include <cstdio>

#include "src/dds/point_cloud.hpp"
#include "src/service/log.hpp"
#include "src/service/service.hpp"

namespace raymap::service {

DiagnosticsReporter::DiagnosticsReporter(const pipeline::PipelineStats& stats,
                                         const pipeline::ScanMailbox& mailbox,
                                         const pipeline::PoseQueue& poses, std::string backend,
                                         std::string device, double publish_rate_hz)
    : stats_(stats),
      mailbox_(mailbox),
      poses_(poses),
      backend_(std::move(backend)),
      device_(std::move(device)),
      publish_rate_hz_(publish_rate_hz),
      message_(3, 32) {}

DiagnosticsReporter::Totals DiagnosticsReporter::read() const noexcept {
  Totals t;
  t.clouds = stats_.clouds_received.get();
  t.malformed = stats_.clouds_malformed.get();
  t.too_large = stats_.clouds_too_large.get();
  t.unknown_frame = stats_.clouds_unknown_frame.get();
  t.overflow = mailbox_.droppedOldest();
  t.scans = stats_.scans_integrated.get();
  t.no_pose = stats_.scans_no_pose.get();
  t.rays = stats_.rays_integrated.get();
  t.rejected = stats_.rays_rejected.get();
  t.no_return = stats_.points_no_return.get();
  t.maps = stats_.maps_published.get();
  t.late = stats_.cycles_late.get();
  t.hm_errors = stats_.heightmap_errors.get();
  t.integrate_errors = stats_.integrate_errors.get();
  t.poses = stats_.poses_received.get();
  t.poses_malformed = stats_.poses_malformed.get();
  t.poses_dropped = stats_.poses_dropped.get();
  return t;
}

void DiagnosticsReporter::update(std::int64_t now_ns, const RealtimeReport& realtime) noexcept {
  realtime_ = &realtime;
  previous_ = current_;
  previous_ns_ = now_ns_;
  now_ns_ = now_ns;
  current_ = read();
  latency_prev_ = latency_now_;
  period_prev_ = period_now_;
  generate_prev_ = generate_now_;
  stats_.latency_us.snapshot(&latency_now_);
  stats_.period_error_us.snapshot(&period_now_);
  stats_.generate_us.snapshot(&generate_now_);
  const double dt = previous_ns_ == 0 ? 0.0 : static_cast<double>(now_ns_ - previous_ns_) * 1e-9;
  const double map_rate = dt > 0.0 ? static_cast<double>(current_.maps - previous_.maps) / dt : 0.0;
  std::snprintf(status_line_, sizeof(status_line_),
                "%s: %.1f maps/s, %" PRIu64 " scans, %" PRIu64 " dropped, latency p99 %.0f ms; %s",
                backend_.c_str(), map_rate, current_.scans,
                current_.overflow + current_.no_pose + current_.malformed + current_.too_large,
                latency_now_.quantileUs(0.99) / 1000.0, realtime.summary.c_str());
}

const void* DiagnosticsReporter::message(std::int64_t stamp_ns) noexcept {
  const double dt = previous_ns_ == 0 ? 0.0 : static_cast<double>(now_ns_ - previous_ns_) * 1e-9;
  const auto rate = [&](std::uint64_t now, std::uint64_t before) {
    return dt > 0.0 ? static_cast<double>(now - before) / dt : 0.0;
  };
  const Totals& c = current_;
  const Totals& p = previous_;
  message_.begin(stamp_ns);

  // Pipeline: input, queues, drops, integration.
  const bool dropping = c.overflow > p.overflow || c.no_pose > p.no_pose ||
                        c.malformed > p.malformed || c.too_large > p.too_large ||
                        c.poses_dropped > p.poses_dropped;
  const bool failing = c.integrate_errors > p.integrate_errors;
  const int s = message_.addStatus(failing    ? dds::kDiagnosticError
                                   : dropping ? dds::kDiagnosticWarn
                                              : dds::kDiagnosticOk,
                                   "raymapd: pipeline",
                                   failing    ? "backend errors"
                                   : dropping ? "dropping input"
                                              : "ok",
                                   "raymapd");
  message_.addValue(s, "backend", "%s", backend_.c_str());
  message_.addValue(s, "device", "%s", device_.empty() ? "host CPU" : device_.c_str());
  message_.addValue(s, "clouds_received", "%" PRIu64, c.clouds);
  message_.addValue(s, "cloud_rate_hz", "%.2f", rate(c.clouds, p.clouds));
  message_.addValue(s, "clouds_dropped_overflow", "%" PRIu64, c.overflow);
  message_.addValue(s, "clouds_malformed", "%" PRIu64, c.malformed);
  message_.addValue(s, "clouds_too_large", "%" PRIu64, c.too_large);
  message_.addValue(s, "clouds_wrong_frame", "%" PRIu64, c.unknown_frame);
  const std::uint32_t last_error = stats_.last_cloud_error.load(std::memory_order_relaxed);
  message_.addValue(
      s, "last_cloud_error", "%s",
      last_error == 0 ? "none" : dds::toString(static_cast<dds::CloudError>(last_error - 1)));
  message_.addValue(s, "scans_integrated", "%" PRIu64, c.scans);
  message_.addValue(s, "scans_dropped_no_pose", "%" PRIu64, c.no_pose);
  message_.addValue(s, "rays_integrated", "%" PRIu64, c.rays);
  message_.addValue(s, "ray_rate_per_s", "%.0f", rate(c.rays, p.rays));
  message_.addValue(s, "rays_rejected", "%" PRIu64, c.rejected);
  message_.addValue(s, "points_no_return", "%" PRIu64, c.no_return);
  message_.addValue(s, "integrate_errors", "%" PRIu64, c.integrate_errors);
  message_.addValue(s, "scan_queue_depth", "%u", mailbox_.waiting());
  message_.addValue(s, "scan_queue_capacity", "%u", mailbox_.capacity() - 1);
  message_.addValue(s, "pose_queue_depth", "%zu", poses_.read_available());
  message_.addValue(s, "poses_received", "%" PRIu64, c.poses);
  message_.addValue(s, "poses_malformed", "%" PRIu64, c.poses_malformed);
  message_.addValue(s, "poses_dropped", "%" PRIu64, c.poses_dropped);

  // Height map: rate, timing, latency.
  const pipeline::DurationHistogram::Snapshot latency = latency_now_.since(latency_prev_);
  const pipeline::DurationHistogram::Snapshot period = period_now_.since(period_prev_);
  const pipeline::DurationHistogram::Snapshot generate = generate_now_.since(generate_prev_);
  const bool late = c.late > p.late || c.hm_errors > p.hm_errors;
  const int h =
      message_.addStatus(late ? dds::kDiagnosticWarn : dds::kDiagnosticOk, "raymapd: height map",
                         late ? "late or failed cycles" : "ok", "raymapd");
  message_.addValue(h, "maps_published", "%" PRIu64, c.maps);
  message_.addValue(h, "publish_rate_hz", "%.3f", rate(c.maps, p.maps));
  message_.addValue(h, "nominal_rate_hz", "%g", publish_rate_hz_);
  message_.addValue(h, "cycles_late", "%" PRIu64, c.late);
  message_.addValue(h, "heightmap_errors", "%" PRIu64, c.hm_errors);
  // Interval values (since the previous report) and totals since start.
  message_.addValue(h, "period_error_p50_ms", "%.3f", period.quantileUs(0.5) / 1000.0);
  message_.addValue(h, "period_error_p99_ms", "%.3f", period.quantileUs(0.99) / 1000.0);
  message_.addValue(h, "period_error_max_ms_total", "%.3f",
                    static_cast<double>(period_now_.max_us) / 1000.0);
  message_.addValue(h, "latency_p50_ms", "%.1f", latency.quantileUs(0.5) / 1000.0);
  message_.addValue(h, "latency_p99_ms", "%.1f", latency.quantileUs(0.99) / 1000.0);
  message_.addValue(h, "latency_p50_ms_total", "%.1f", latency_now_.quantileUs(0.5) / 1000.0);
  message_.addValue(h, "latency_p99_ms_total", "%.1f", latency_now_.quantileUs(0.99) / 1000.0);
  message_.addValue(h, "latency_max_ms_total", "%.1f",
                    static_cast<double>(latency_now_.max_us) / 1000.0);
  message_.addValue(h, "generate_p99_ms", "%.2f", generate.quantileUs(0.99) / 1000.0);

  // Real time.
  const bool degraded = realtime_ != nullptr && realtime_->degraded;
  const int r =
      message_.addStatus(degraded ? dds::kDiagnosticWarn : dds::kDiagnosticOk, "raymapd: real time",
                         degraded ? "real-time settings refused" : "ok", "raymapd");
  message_.addValue(r, "scheduling", "%s",
                    realtime_ != nullptr ? realtime_->summary.c_str() : "unknown");
  message_.addValue(r, "memory_locked", "%s",
                    realtime_ != nullptr && realtime_->memory_locked ? "true" : "false");
  return message_.sample();
}

void DiagnosticsReporter::logChanges() noexcept {
  const Totals& c = current_;
  const Totals& p = previous_;
  if (c.overflow > p.overflow) {
    logLine(LogLevel::kWarning,
            "dropped %" PRIu64 " scans (oldest first): input faster than the integrator",
            c.overflow - p.overflow);
  }
  if (c.malformed > p.malformed || c.too_large > p.too_large) {
    const std::uint32_t e = stats_.last_cloud_error.load(std::memory_order_relaxed);
    logLine(LogLevel::kWarning, "rejected %" PRIu64 " point clouds (last: %s)",
            c.malformed - p.malformed + c.too_large - p.too_large,
            e == 0 ? "?" : dds::toString(static_cast<dds::CloudError>(e - 1)));
  }
  if (c.no_pose > p.no_pose) {
    logLine(LogLevel::kWarning, "dropped %" PRIu64 " scans: no pose covered them in time",
            c.no_pose - p.no_pose);
  }
  if (c.late > p.late) {
    logLine(LogLevel::kWarning, "%" PRIu64 " height-map cycles late", c.late - p.late);
  }
  if (c.hm_errors > p.hm_errors || c.integrate_errors > p.integrate_errors) {
    logLine(LogLevel::kError, "%" PRIu64 " height-map and %" PRIu64 " integration failures",
            c.hm_errors - p.hm_errors, c.integrate_errors - p.integrate_errors);
  }
}

}  // namespace raymap::service
