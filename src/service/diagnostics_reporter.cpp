// SPDX-License-Identifier: BSD-3-Clause
// DiagnosticsReporter: three statuses (pipeline, height map, real time) with stable keys, levels
// decided over a sliding window (see the header).
#include "src/service/diagnostics_reporter.hpp"

#include <algorithm>
#include <atomic>
#include <cinttypes>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>

#include "platform/allocation_scope.hpp"
#include "src/msgs/point_cloud.hpp"
#include "src/service/log.hpp"
#include "src/service/service.hpp"

namespace raymap::service {
namespace {

constexpr double kMinWindowS = 1.0;  // rates and drops over at least this long

/// Appends printf output to the NUL-terminated `out` (truncating, never overflowing).
void appendf(char* out, std::size_t size, const char* format, ...)
    __attribute__((format(printf, 3, 4)));
void appendf(char* out, std::size_t size, const char* format, ...) {
  const std::size_t used = std::strlen(out);
  if (used + 1 >= size) {
    return;
  }
  va_list args;
  va_start(args, format);
  std::vsnprintf(out + used, size - used, format, args);
  va_end(args);
}

const char* levelName(std::uint8_t level) {
  return level == msgs::kDiagnosticError ? "ERROR" : level == msgs::kDiagnosticWarn ? "WARN" : "OK";
}

}  // namespace

DiagnosticsReporter::DiagnosticsReporter(const pipeline::PipelineStats& stats,
                                         const pipeline::ScanMailbox& mailbox,
                                         const pipeline::PoseQueue& poses,
                                         ReporterSettings settings, std::int64_t started_ns)
    : stats_(stats),
      mailbox_(mailbox),
      poses_(poses),
      settings_(std::move(settings)),
      pipeline_name_(settings_.name + ": pipeline"),
      heightmap_name_(settings_.name + ": height map"),
      realtime_name_(settings_.name + ": real time"),
      security_name_(settings_.name + ": security"),
      started_ns_(started_ns),
      // Up to 96 values a status: the pipeline's has 75 with a depth camera configured.
      message_(4 + static_cast<int>(settings_.sensors.size()), 96),
      has_depth_(std::any_of(settings_.sensors.begin(), settings_.sensors.end(),
                             [](const ReporterSettings::Sensor& sensor) {
                               return !sensor.camera_info_topic.empty();
                             })) {
  const double window_s = std::max(kMinWindowS, 1.0 / settings_.report_rate_hz);
  window_ns_ = static_cast<std::int64_t>(std::llround(window_s * 1e9));
  // Enough samples that one of them is a whole window older than the newest.
  ring_.resize(static_cast<std::size_t>(std::ceil(window_s * settings_.report_rate_hz)) + 2);
  // The first sample is the start: what was dropped before the first report (raymapd stopped
  // or starved right after it started, its socket overflowing meanwhile) is then that report's
  // news, not part of a base it is never compared against.
  take(ring_[0], started_ns_);  // filled_ starts at 1: this sample
}

DiagnosticsReporter::Totals DiagnosticsReporter::read() const noexcept {
  Totals t;
  t.clouds = stats_.clouds_received.get();
  t.malformed = stats_.clouds_malformed.get();
  t.too_large = stats_.clouds_too_large.get();
  t.socket_drops = stats_.socket_drops.get();
  t.wrong_frame = stats_.clouds_unknown_frame.get();
  t.overflow = mailbox_.droppedOldest();
  t.overflow_undecoded = mailbox_.droppedUndecoded();
  t.scans = stats_.scans_integrated.get();
  t.no_pose = stats_.scans_no_pose.get();
  t.rays = stats_.rays_integrated.get();
  t.rejected = stats_.rays_rejected.get();
  t.no_return = stats_.points_no_return.get();
  t.bad_time = stats_.points_bad_time.get();
  t.scans_empty = stats_.scans_empty.get();
  t.invalid = stats_.rays_invalid.get();
  t.too_short = stats_.rays_too_short.get();
  t.out_of_bounds = stats_.rays_out_of_bounds.get();
  t.outside_window = stats_.rays_outside_window.get();
  t.too_near = stats_.points_too_near.get();
  t.time_resets = stats_.pose_time_resets.get();
  t.pose_jumps = stats_.pose_jumps.get();
  t.window_clears = stats_.window_clears.get();
  t.scans_shed = stats_.scans_shed.get();
  t.scans_cut_short = stats_.scans_cut_short.get();
  t.points_shed = stats_.points_shed.get();
  t.maps = stats_.maps_published.get();
  t.withheld = stats_.maps_withheld.get();
  t.late = stats_.cycles_late.get();
  t.hm_errors = stats_.heightmap_errors.get();
  t.integrate_errors = stats_.integrate_errors.get();
  t.poses = stats_.poses_received.get();
  t.poses_malformed = stats_.poses_malformed.get();
  t.poses_dropped = stats_.poses_dropped.get();
  for (std::size_t i = 0; i < msgs::kCloudErrorCount; ++i) {
    t.rejected_by[i] = stats_.clouds_rejected_by[i].get();
  }
  for (std::size_t i = 0; i < msgs::kDepthImageErrorCount; ++i) {
    t.image_rejected_by[i] = stats_.images_rejected_by[i].get();
  }
  for (std::size_t i = 0; i < msgs::kCameraInfoErrorCount; ++i) {
    t.camera_info_rejected_by[i] = stats_.camera_info_rejected_by[i].get();
  }
  for (std::size_t i = 0; i < settings_.sensors.size() && i < t.sensor.size(); ++i) {
    const pipeline::SensorCounters& in = stats_.sensors[i];
    Totals::PerSensor& out = t.sensor[i];
    out.received = in.received.get();
    out.accepted = in.accepted.get();
    out.rate_limited = in.rate_limited.get();
    out.rejected = in.rejected.get();
    out.no_camera_info = in.no_camera_info.get();
    out.camera_info = in.camera_info.get();
    out.camera_info_bad = in.camera_info_bad.get();
    out.scans = in.scans_integrated.get();
    out.missing = in.missing.get();
    t.missing += out.missing;
  }
  return t;
}

const DiagnosticsReporter::Sample& DiagnosticsReporter::windowBase() const noexcept {
  const Sample& now = ring_[head_];
  const std::size_t n = ring_.size();
  for (std::size_t back = 1; back < filled_; ++back) {
    const Sample& s = ring_[(head_ + n - back) % n];
    if (now.ns - s.ns >= window_ns_) {
      return s;
    }
  }
  return ring_[(head_ + n - (filled_ - 1)) % n];  // the oldest (at first the start)
}

void DiagnosticsReporter::take(Sample& s, std::int64_t ns) const noexcept {
  s.ns = ns;
  s.totals = read();
  stats_.latency_us.snapshot(&s.latency);
  stats_.period_error_us.snapshot(&s.period);
  stats_.generate_us.snapshot(&s.generate);
  stats_.map_lock_hold_us.snapshot(&s.hold);
  stats_.map_lock_wait_us.snapshot(&s.wait);
  stats_.heightmap_lock_hold_us.snapshot(&s.cycle_hold);
  stats_.sync_copy_bytes.snapshot(&s.sync_bytes);
  stats_.heightmap_copy_bytes.snapshot(&s.heightmap_bytes);
  stats_.heightmap_transfer_bytes.snapshot(&s.transfer_bytes);
}

void DiagnosticsReporter::update(std::int64_t now_ns, const RealtimeReport& realtime,
                                 std::uint32_t other_map_publishers,
                                 const InputPublishers* inputs) noexcept {
  realtime_ = &realtime;
  inputs_ = inputs;
  head_ = (head_ + 1) % ring_.size();
  filled_ = std::min(filled_ + 1, ring_.size());
  Sample& s = ring_[head_];
  take(s, now_ns);
  base_ = &windowBase();
  decide(other_map_publishers);
  const double dt = static_cast<double>(s.ns - base_->ns) * 1e-9;
  const double map_rate =
      dt > 0.0 ? static_cast<double>(s.totals.maps - base_->totals.maps) / dt : 0.0;
  std::snprintf(status_line_, sizeof(status_line_),
                "%s %s: %.1f maps/s, %" PRIu64 " scans, %" PRIu64
                " dropped, latency p99 %.0f ms; %s; %s",
                settings_.backend.c_str(), levelName(pipeline_level_), map_rate, s.totals.scans,
                s.totals.overflow + s.totals.no_pose + s.totals.malformed + s.totals.too_large +
                    s.totals.wrong_frame + s.totals.missing,
                s.latency.quantileUs(0.99) / 1000.0, realtime.summary.c_str(),
                settings_.secure                     ? "security on"
                : settings_.security_warning.empty() ? "security off"
                                                     : "security OFF (Permissive)");
}

void DiagnosticsReporter::describeFrameDrops(const Totals& c, const Totals& b,
                                             const char*& sep) noexcept {
  char* out = drop_reasons_;
  const std::size_t size = sizeof(drop_reasons_);
  if (c.wrong_frame > b.wrong_frame) {
    const bool seen = stats_.wrong_frame_seen.load(std::memory_order_acquire);
    const std::uint32_t sensor = stats_.wrong_frame_sensor;
    if (seen && sensor < settings_.sensor_frames.size()) {
      appendf(out, size, "%s%" PRIu64 " clouds in frame '%s', not sensors[%u].frame '%s'", sep,
              c.wrong_frame - b.wrong_frame, stats_.wrong_frame, sensor,
              settings_.sensor_frames[sensor].c_str());
    } else {
      appendf(out, size, "%s%" PRIu64 " %s", sep, c.wrong_frame - b.wrong_frame,
              "clouds in a frame no sensor is configured for");
    }
    sep = "; ";
  }
  if (c.malformed > b.malformed) {
    appendf(out, size, "%s%" PRIu64 " malformed %s (", sep, c.malformed - b.malformed,
            has_depth_ ? "clouds or depth images" : "clouds");
    const char* inner = "";
    for (std::size_t i = 0; i < msgs::kCloudErrorCount; ++i) {
      if (i != static_cast<std::size_t>(msgs::CloudError::kTooManyPoints) &&
          c.rejected_by[i] > b.rejected_by[i]) {
        appendf(out, size, "%s%s %" PRIu64, inner, msgs::toString(static_cast<msgs::CloudError>(i)),
                c.rejected_by[i] - b.rejected_by[i]);
        inner = ", ";
      }
    }
    for (std::size_t i = 0; i < msgs::kDepthImageErrorCount; ++i) {
      if (i != static_cast<std::size_t>(msgs::DepthImageError::kTooManyPoints) &&
          c.image_rejected_by[i] > b.image_rejected_by[i]) {
        appendf(out, size, "%simage %s %" PRIu64, inner,
                msgs::toString(static_cast<msgs::DepthImageError>(i)),
                c.image_rejected_by[i] - b.image_rejected_by[i]);
        inner = ", ";
      }
    }
    appendf(out, size, ")");
    sep = "; ";
  }
}

void DiagnosticsReporter::describeCameraDrops(const Totals& c, const Totals& b,
                                              const char*& sep) noexcept {
  char* out = drop_reasons_;
  const std::size_t size = sizeof(drop_reasons_);
  for (std::size_t i = 0; i < settings_.sensors.size() && i < c.sensor.size(); ++i) {
    const Totals::PerSensor& cs = c.sensor[i];
    const Totals::PerSensor& bs = b.sensor[i];
    if (cs.no_camera_info > bs.no_camera_info) {
      appendf(out, size,
              "%s%" PRIu64 " depth images of sensors[%zu] without a CameraInfo (from %s)", sep,
              cs.no_camera_info - bs.no_camera_info, i,
              settings_.sensors[i].camera_info_topic.c_str());
      sep = "; ";
    }
    if (cs.camera_info_bad > bs.camera_info_bad) {
      appendf(out, size, "%s%" PRIu64 " CameraInfo refused for sensors[%zu] (all cameras: ", sep,
              cs.camera_info_bad - bs.camera_info_bad, i);
      const char* inner = "";
      for (std::size_t r = 0; r < msgs::kCameraInfoErrorCount; ++r) {
        if (c.camera_info_rejected_by[r] > b.camera_info_rejected_by[r]) {
          appendf(out, size, "%s%s", inner, msgs::toString(static_cast<msgs::CameraInfoError>(r)));
          inner = ", ";
        }
      }
      appendf(out, size, ")");
      sep = "; ";
    }
  }
}

void DiagnosticsReporter::describePoseResets(const Totals& c, const Totals& b,
                                             const char*& sep) noexcept {
  char* out = drop_reasons_;
  const std::size_t size = sizeof(drop_reasons_);
  if (c.time_resets > b.time_resets) {
    appendf(out, size,
            "%sthe pose clock went back %.1f s (%" PRIu64
            "x: a bag played in a loop, a simulation reset?): the pose history started over",
            sep,
            static_cast<double>(stats_.last_time_reset_ms.load(std::memory_order_relaxed)) * 1e-3,
            c.time_resets - b.time_resets);
    sep = "; ";
  }
  if (c.pose_jumps > b.pose_jumps) {
    appendf(out, size,
            "%sthe pose jumped %.2f m (%" PRIu64
            "x, more than pose.max_jump_m: relocalisation, an odometry reset?): the pose history "
            "started over%s",
            sep,
            static_cast<double>(stats_.last_pose_jump_mm.load(std::memory_order_relaxed)) * 1e-3,
            c.pose_jumps - b.pose_jumps,
            c.window_clears > b.window_clears ? ", the rolling window was cleared"
                                              : ", the map was kept");
    sep = "; ";
  }
}

void DiagnosticsReporter::describeDrops() noexcept {
  const Totals& c = ring_[head_].totals;
  const Totals& b = base_->totals;
  char* out = drop_reasons_;
  const std::size_t size = sizeof(drop_reasons_);
  out[0] = '\0';
  const char* sep = "";
  const auto reason = [&](std::uint64_t now, std::uint64_t before, const char* what) {
    if (now > before) {
      appendf(out, size, "%s%" PRIu64 " %s", sep, now - before, what);
      sep = "; ";
    }
  };
  describeFrameDrops(c, b, sep);
  describeCameraDrops(c, b, sep);
  reason(c.missing, b.missing,
         "clouds missing by the gaps in their stamps (lost on the way or never sent)");
  reason(c.socket_drops, b.socket_drops,
         "datagrams dropped by raymapd's full socket receive buffers (clouds lost in fragments: "
         "dds.receive_buffer_mb, net.core.rmem_max)");
  reason(c.too_large, b.too_large, "clouds larger than max_points");
  reason(c.no_pose, b.no_pose, "scans without a pose in time");
  reason(c.overflow, b.overflow, "scans dropped, oldest first (input faster than the integrator)");
  reason(c.bad_time, b.bad_time, "points with a per-point time out of range");
  reason(c.scans_shed, b.scans_shed,
         "scans shed (no map within queues.max_latency_s could hold them)");
  reason(c.scans_cut_short, b.scans_cut_short,
         "scans cut short at their deadline (queues.max_latency_s)");
  reason(c.points_shed, b.points_shed, "points shed by subsampling (latency bound)");
  reason(c.poses_dropped, b.poses_dropped, "poses dropped (pose queue full)");
  describePoseResets(c, b, sep);
}

DiagnosticsReporter::RaysInWindow DiagnosticsReporter::raysInWindow() const noexcept {
  const Totals& c = ring_[head_].totals;
  const Totals& b = base_->totals;
  const std::uint64_t integrated = c.rays - b.rays;
  return {integrated, integrated + (c.rejected - b.rejected) + (c.too_near - b.too_near)};
}

std::uint8_t DiagnosticsReporter::describeIntegration(char* out, std::size_t size) const noexcept {
  const Totals& c = ring_[head_].totals;
  const Totals& b = base_->totals;
  out[0] = '\0';
  const auto [integrated, offered] = raysInWindow();
  if (offered == 0 || static_cast<double>(integrated) >=
                          settings_.min_integrated_fraction * static_cast<double>(offered)) {
    return msgs::kDiagnosticOk;
  }
  const double dt = static_cast<double>(ring_[head_].ns - base_->ns) * 1e-9;
  appendf(out, size, "integrating %" PRIu64 " of %" PRIu64 " rays (%.0f %%) in %.1f s:", integrated,
          offered, 100.0 * static_cast<double>(integrated) / static_cast<double>(offered), dt);
  const char* sep = " ";
  const auto reason = [&](std::uint64_t now, std::uint64_t before, const char* what) {
    if (now > before) {
      appendf(out, size, "%s%" PRIu64 " %s", sep, now - before, what);
      sep = ", ";
    }
  };
  reason(c.too_short, b.too_short, "shorter than the sensor's min_range");
  reason(c.too_near, b.too_near, "depth blocks nearer than the sensor's min_range");
  reason(c.out_of_bounds, b.out_of_bounds, "beyond the map's bounds or max_ray_length");
  reason(c.outside_window, b.outside_window, "outside the rolling window");
  reason(c.invalid, b.invalid, "with coordinates that are not finite");
  return integrated == 0 ? msgs::kDiagnosticError : msgs::kDiagnosticWarn;
}

bool DiagnosticsReporter::describePublishers(char* out, std::size_t size,
                                             bool* extra_sensor) const noexcept {
  out[0] = '\0';
  *extra_sensor = false;
  if (inputs_ == nullptr) {
    return false;
  }
  const char* sep = "";
  for (std::size_t i = 0; i < settings_.sensors.size() && i < pipeline::kMaxSensors; ++i) {
    if (inputs_->clouds[i] > 1) {
      appendf(out, size,
              "%s%u publishers of %s (sensors[%zu].topic): each one's %s go into the map", sep,
              inputs_->clouds[i], settings_.sensors[i].topic.c_str(), i,
              settings_.sensors[i].camera_info_topic.empty() ? "clouds" : "images");
      sep = "; ";
      *extra_sensor = true;
    }
    if (inputs_->camera_info[i] > 1) {
      appendf(out, size, "%s%u publishers of %s (sensors[%zu].camera_info_topic)", sep,
              inputs_->camera_info[i], settings_.sensors[i].camera_info_topic.c_str(), i);
      sep = "; ";
      *extra_sensor = true;
    }
  }
  const bool two_poses = inputs_->odometry > 1;
  if (two_poses) {
    appendf(out, size, "%s%u publishers of %s (%s): two pose sources for one robot", sep,
            inputs_->odometry, inputs_->odometry_topic.c_str(), inputs_->pose_key.c_str());
  }
  if (out[0] != '\0' && inputs_->who != nullptr && inputs_->who[0] != '\0') {
    appendf(out, size, " [%s]", inputs_->who);
  }
  return two_poses;
}

void DiagnosticsReporter::describeStaleness(const Sample& now, std::int64_t last) noexcept {
  const Totals& c = now.totals;
  const Totals& b = base_->totals;
  char* m = pipeline_message_;
  const std::size_t size = sizeof(pipeline_message_);
  if (waiting_first_) {
    appendf(m, size,
            "%swaiting for the first %s, %.1f s since start (ERROR after %.0f s: "
            "health.startup_grace_s)",
            m[0] == '\0' ? "" : "; ", has_depth_ ? "point cloud or depth image" : "point cloud",
            seconds_since_scan_, settings_.startup_grace_s);
  } else if (stale_) {
    appendf(m, size, "%sno scan integrated %s %.1f s", m[0] == '\0' ? "" : "; ",
            last != 0 ? "for" : "since start,", seconds_since_scan_);
    // Whether input still arrives is decided by time, not by the window's counts: a window
    // that still holds the last clouds before the input stopped would report them arriving.
    const double dt = static_cast<double>(now.ns - base_->ns) * 1e-9;
    const std::int64_t last_cloud = stats_.last_cloud_received_ns.load(std::memory_order_relaxed);
    if (c.clouds == 0 || last_cloud <= (last != 0 ? last : started_ns_)) {
      appendf(m, size, " (no %s arrives%s)",
              has_depth_ ? "point cloud or depth image" : "point cloud",
              c.clouds == 0 ? " at all" : " any more");
    } else if (dt > 0.0 && c.clouds > b.clouds) {
      appendf(m, size, " (%.1f clouds/s arrive)", static_cast<double>(c.clouds - b.clouds) / dt);
    } else {
      appendf(m, size, " (the last cloud arrived %.1f s ago)",
              static_cast<double>(now.ns - last_cloud) * 1e-9);
    }
  }
}

void DiagnosticsReporter::decideHeightmap(const Sample& now) noexcept {
  const Totals& c = now.totals;
  const Totals& b = base_->totals;
  heightmap_message_[0] = '\0';
  if (waiting_first_) {
    heightmap_level_ = msgs::kDiagnosticWarn;
    appendf(heightmap_message_, sizeof(heightmap_message_), "no map yet: waiting for the first %s",
            has_depth_ ? "cloud or image" : "cloud");
  } else if (stale_) {
    heightmap_level_ = msgs::kDiagnosticError;
    appendf(heightmap_message_, sizeof(heightmap_message_),
            "withheld: the map is stale (no scan integrated for %.1f s)", seconds_since_scan_);
  } else if (c.withheld > b.withheld) {
    heightmap_level_ = msgs::kDiagnosticError;
    appendf(heightmap_message_, sizeof(heightmap_message_),
            "%" PRIu64 " maps withheld in the last %.1f s: the map was stale",
            c.withheld - b.withheld, static_cast<double>(now.ns - base_->ns) * 1e-9);
  } else if (c.late > b.late || c.hm_errors > b.hm_errors) {
    heightmap_level_ = msgs::kDiagnosticWarn;
    appendf(heightmap_message_, sizeof(heightmap_message_),
            "%" PRIu64 " late and %" PRIu64 " failed cycles", c.late - b.late,
            c.hm_errors - b.hm_errors);
  } else {
    heightmap_level_ = msgs::kDiagnosticOk;
    appendf(heightmap_message_, sizeof(heightmap_message_), "ok");
  }
}

void DiagnosticsReporter::decide(std::uint32_t other_map_publishers) noexcept {
  const Sample& now = ring_[head_];
  const Totals& c = now.totals;
  const Totals& b = base_->totals;
  other_publishers_ = other_map_publishers;
  const std::int64_t last = stats_.last_scan_integrated_ns.load(std::memory_order_relaxed);
  const std::int64_t since = now.ns - (last != 0 ? last : started_ns_);
  seconds_since_scan_ = static_cast<double>(since) * 1e-9;
  stale_ = since > static_cast<std::int64_t>(std::llround(settings_.stale_after_s * 1e9));
  // Before the first cloud a service started ahead of its sensors (as systemd starts it) is
  // waiting, not failing, for startup_grace_s.
  waiting_first_ = stale_ && last == 0 && c.clouds == 0 &&
                   now.ns - started_ns_ <=
                       static_cast<std::int64_t>(std::llround(settings_.startup_grace_s * 1e9));
  const bool failing = c.integrate_errors > b.integrate_errors;
  backend_failing_ = failing;
  describeDrops();
  const bool dropping = drop_reasons_[0] != '\0';

  pipeline_message_[0] = '\0';
  char* m = pipeline_message_;
  const std::size_t size = sizeof(pipeline_message_);
  if (other_publishers_ > 0) {
    appendf(m, size, "%u other publisher%s of %s on this domain (another raymapd?)",
            other_publishers_, other_publishers_ == 1 ? "" : "s", settings_.grid_map_topic.c_str());
  }
  describeStaleness(now, last);
  if (failing) {
    appendf(m, size, "%s%" PRIu64 " backend failures", m[0] == '\0' ? "" : "; ",
            c.integrate_errors - b.integrate_errors);
  }
  char integration[320];
  const std::uint8_t integration_level = describeIntegration(integration, sizeof(integration));
  if (integration_level != msgs::kDiagnosticOk) {
    appendf(m, size, "%s%s", m[0] == '\0' ? "" : "; ", integration);
  }
  char publishers[384];
  bool extra_sensor = false;
  const bool two_poses = describePublishers(publishers, sizeof(publishers), &extra_sensor);
  if (publishers[0] != '\0') {
    appendf(m, size, "%s%s", m[0] == '\0' ? "" : "; ", publishers);
  }
  const bool error = other_publishers_ > 0 || (stale_ && !waiting_first_) || failing ||
                     integration_level == msgs::kDiagnosticError || two_poses;
  const bool warn =
      dropping || waiting_first_ || integration_level != msgs::kDiagnosticOk || extra_sensor;
  if (dropping) {
    appendf(m, size, "%sdropping input: %s", m[0] == '\0' ? "" : "; ", drop_reasons_);
  }
  pipeline_level_ = error  ? msgs::kDiagnosticError
                    : warn ? msgs::kDiagnosticWarn
                           : msgs::kDiagnosticOk;
  if (m[0] == '\0') {
    appendf(m, size, "ok");
  }

  decideHeightmap(now);
}

// The message, one status at a time. `w` is the rate window: the newest sample and the one a
// window before it.

struct DiagnosticsReporter::Window {
  const Sample& now;
  const Sample& base;
  double dt;  ///< seconds between them
  double rate(std::uint64_t a, std::uint64_t b) const noexcept {
    return dt > 0.0 ? static_cast<double>(a - b) / dt : 0.0;
  }
};

const void* DiagnosticsReporter::message(std::int64_t stamp_ns) noexcept {
  const Window w{ring_[head_], *base_, static_cast<double>(ring_[head_].ns - base_->ns) * 1e-9};
  const char* hw = settings_.hardware_id.c_str();
  message_.begin(stamp_ns);
  // Pipeline: input, queues, drops, integration.
  const int s = message_.addStatus(pipeline_level_, pipeline_name_.c_str(), pipeline_message_, hw);
  addInputValues(s, w);
  addIntegrationValues(s, w);
  addQueueValues(s, w);
  addHeightmapStatus(w, hw);
  const Totals& c = w.now.totals;
  for (std::size_t i = 0; i < settings_.sensors.size() && i < c.sensor.size(); ++i) {
    addSensorStatus(i, w.dt);
  }
  addRealtimeAndSecurityStatuses(hw);
  return message_.sample();
}

void DiagnosticsReporter::addInputValues(int s, const Window& w) noexcept {
  const Totals& c = w.now.totals;
  const Totals& p = w.base.totals;
  message_.addValue(s, "backend", "%s", settings_.backend.c_str());
  message_.addValue(s, "device", "%s",
                    settings_.device.empty() ? "host CPU" : settings_.device.c_str());
  message_.addValue(s, "clouds_received", "%" PRIu64, c.clouds);
  message_.addValue(s, "cloud_rate_hz", "%.2f", w.rate(c.clouds, p.clouds));
  message_.addValue(s, "clouds_missing", "%" PRIu64, c.missing);
  message_.addValue(s, "socket_datagrams_dropped", "%" PRIu64, c.socket_drops);
  message_.addValue(s, "socket_receive_buffer_bytes", "%" PRIu64, settings_.receive_buffer_bytes);
  message_.addValue(s, "socket_receive_buffer_wanted_bytes", "%" PRIu64,
                    settings_.receive_buffer_wanted_bytes);
  message_.addValue(s, "clouds_dropped_overflow", "%" PRIu64, c.overflow);
  message_.addValue(s, "clouds_dropped_before_decode", "%" PRIu64, c.overflow_undecoded);
  message_.addValue(s, "clouds_malformed", "%" PRIu64, c.malformed);
  message_.addValue(s, "clouds_too_large", "%" PRIu64, c.too_large);
  message_.addValue(s, "clouds_wrong_frame", "%" PRIu64, c.wrong_frame);
  {
    std::uint64_t rate_limited = 0;
    std::uint64_t no_camera_info = 0;
    for (std::size_t i = 0; i < settings_.sensors.size() && i < c.sensor.size(); ++i) {
      rate_limited += c.sensor[i].rate_limited;
      no_camera_info += c.sensor[i].no_camera_info;
    }
    message_.addValue(s, "clouds_rate_limited", "%" PRIu64, rate_limited);
    message_.addValue(s, "images_without_camera_info", "%" PRIu64, no_camera_info);
  }
  for (std::size_t i = 0; i < msgs::kCloudErrorCount; ++i) {
    if (i == static_cast<std::size_t>(msgs::CloudError::kTooManyPoints)) {
      continue;  // clouds_too_large
    }
    char key[64];
    std::snprintf(key, sizeof(key), "clouds_malformed_%s",
                  msgs::toString(static_cast<msgs::CloudError>(i)));
    message_.addValue(s, key, "%" PRIu64, c.rejected_by[i]);
  }
  if (has_depth_) {
    for (std::size_t i = 0; i < msgs::kDepthImageErrorCount; ++i) {
      if (i == static_cast<std::size_t>(msgs::DepthImageError::kTooManyPoints)) {
        continue;  // clouds_too_large
      }
      char key[64];
      std::snprintf(key, sizeof(key), "images_malformed_%s",
                    msgs::toString(static_cast<msgs::DepthImageError>(i)));
      message_.addValue(s, key, "%" PRIu64, c.image_rejected_by[i]);
    }
    for (std::size_t i = 0; i < msgs::kCameraInfoErrorCount; ++i) {
      char key[64];
      std::snprintf(key, sizeof(key), "camera_info_rejected_%s",
                    msgs::toString(static_cast<msgs::CameraInfoError>(i)));
      message_.addValue(s, key, "%" PRIu64, c.camera_info_rejected_by[i]);
    }
    message_.addValue(s, "points_too_near", "%" PRIu64, c.too_near);
  }
}

void DiagnosticsReporter::addIntegrationValues(int s, const Window& w) noexcept {
  const Totals& c = w.now.totals;
  const Totals& p = w.base.totals;
  message_.addValue(s, "scans_integrated", "%" PRIu64, c.scans);
  message_.addValue(s, "scan_rate_hz", "%.2f", w.rate(c.scans, p.scans));
  message_.addValue(s, "seconds_since_last_scan", "%.2f", seconds_since_scan_);
  message_.addValue(s, "scans_dropped_no_pose", "%" PRIu64, c.no_pose);
  message_.addValue(s, "rays_integrated", "%" PRIu64, c.rays);
  message_.addValue(s, "ray_rate_per_s", "%.0f", w.rate(c.rays, p.rays));
  message_.addValue(s, "rays_rejected", "%" PRIu64, c.rejected);
  message_.addValue(s, "rays_rejected_too_short", "%" PRIu64, c.too_short);
  message_.addValue(s, "rays_rejected_out_of_bounds", "%" PRIu64, c.out_of_bounds);
  message_.addValue(s, "rays_rejected_outside_window", "%" PRIu64, c.outside_window);
  message_.addValue(s, "rays_rejected_invalid", "%" PRIu64, c.invalid);
  {
    // Over the window; 1 when nothing was offered (nothing lost).
    const auto [integrated, offered] = raysInWindow();
    message_.addValue(
        s, "rays_integrated_fraction", "%.3f",
        offered == 0 ? 1.0 : static_cast<double>(integrated) / static_cast<double>(offered));
  }
  message_.addValue(s, "scans_empty", "%" PRIu64, c.scans_empty);
  message_.addValue(s, "points_no_return", "%" PRIu64, c.no_return);
  message_.addValue(s, "points_bad_time", "%" PRIu64, c.bad_time);
  message_.addValue(s, "scans_shed", "%" PRIu64, c.scans_shed);
  message_.addValue(s, "scans_cut_short", "%" PRIu64, c.scans_cut_short);
  message_.addValue(s, "points_shed", "%" PRIu64, c.points_shed);
  if (const platform::RealtimeAllocationCounter counter = platform::realtimeAllocationCounter()) {
    // Only in raymapd_counted (tools/soak.sh): heap allocations the real-time loops made.
    message_.addValue(s, "realtime_allocations", "%" PRIu64, counter());
  }
}

void DiagnosticsReporter::addQueueValues(int s, const Window& w) noexcept {
  const Totals& c = w.now.totals;
  message_.addValue(s, "integrator_load_percent", "%d",
                    stats_.integrator_load_percent.load(std::memory_order_relaxed));
  message_.addValue(s, "subsample_stride", "%d",
                    stats_.subsample_stride.load(std::memory_order_relaxed));
  message_.addValue(s, "tf_ignored", "%" PRIu64, stats_.tf_ignored.get());
  message_.addValue(s, "tf_unresolved", "%" PRIu64, stats_.tf_unresolved.get());
  message_.addValue(s, "tf_static_edges", "%u",
                    stats_.tf_static_edges.load(std::memory_order_relaxed));
  message_.addValue(s, "extrinsics_from_tf", "%u",
                    stats_.extrinsics_from_tf.load(std::memory_order_relaxed));
  message_.addValue(s, "integrate_errors", "%" PRIu64, c.integrate_errors);
  message_.addValue(s, "scan_queue_depth", "%u",
                    mailbox_.waiting() + (pending_ != nullptr ? pending_->size() : 0u));
  message_.addValue(s, "scan_queue_capacity", "%u", mailbox_.capacity() - 1);
  message_.addValue(s, "pose_queue_depth", "%zu", poses_.read_available());
  message_.addValue(s, "poses_received", "%" PRIu64, c.poses);
  message_.addValue(s, "poses_malformed", "%" PRIu64, c.poses_malformed);
  message_.addValue(s, "poses_dropped", "%" PRIu64, c.poses_dropped);
  message_.addValue(s, "pose_time_resets", "%" PRIu64, c.time_resets);
  message_.addValue(s, "pose_jumps", "%" PRIu64, c.pose_jumps);
  message_.addValue(s, "window_clears", "%" PRIu64, c.window_clears);
  message_.addValue(s, "other_map_publishers", "%u", other_publishers_);
  message_.addValue(s, "pose_publishers", "%u", inputs_ != nullptr ? inputs_->odometry : 0u);
  message_.addValue(s, "rate_window_s", "%.2f", w.dt);
}

void DiagnosticsReporter::addHeightmapStatus(const Window& w, const char* hw) noexcept {
  const Sample& now = w.now;
  const Sample& base = w.base;
  const Totals& c = now.totals;
  const Totals& p = base.totals;
  // Height map: rate, timing, latency (percentiles over the same window).
  const pipeline::DurationHistogram::Snapshot latency = now.latency.since(base.latency);
  const pipeline::DurationHistogram::Snapshot period = now.period.since(base.period);
  const pipeline::DurationHistogram::Snapshot generate = now.generate.since(base.generate);
  const int h =
      message_.addStatus(heightmap_level_, heightmap_name_.c_str(), heightmap_message_, hw);
  message_.addValue(h, "maps_published", "%" PRIu64, c.maps);
  message_.addValue(h, "maps_withheld_stale", "%" PRIu64, c.withheld);
  message_.addValue(h, "costmaps_published", "%" PRIu64, stats_.costmaps_published.get());
  message_.addValue(h, "publish_rate_hz", "%.3f", w.rate(c.maps, p.maps));
  message_.addValue(h, "nominal_rate_hz", "%g", settings_.publish_rate_hz);
  message_.addValue(h, "cycles_late", "%" PRIu64, c.late);
  message_.addValue(h, "heightmap_errors", "%" PRIu64, c.hm_errors);
  // Window values and totals since start.
  message_.addValue(h, "period_error_p50_ms", "%.3f", period.quantileUs(0.5) / 1000.0);
  message_.addValue(h, "period_error_p99_ms", "%.3f", period.quantileUs(0.99) / 1000.0);
  message_.addValue(h, "period_error_max_ms_total", "%.3f",
                    static_cast<double>(now.period.max_us) / 1000.0);
  message_.addValue(h, "latency_p50_ms", "%.1f", latency.quantileUs(0.5) / 1000.0);
  message_.addValue(h, "latency_p99_ms", "%.1f", latency.quantileUs(0.99) / 1000.0);
  message_.addValue(h, "latency_p50_ms_total", "%.1f", now.latency.quantileUs(0.5) / 1000.0);
  message_.addValue(h, "latency_p99_ms_total", "%.1f", now.latency.quantileUs(0.99) / 1000.0);
  message_.addValue(h, "latency_max_ms_total", "%.1f",
                    static_cast<double>(now.latency.max_us) / 1000.0);
  message_.addValue(h, "generate_p99_ms", "%.2f", generate.quantileUs(0.99) / 1000.0);
  const pipeline::DurationHistogram::Snapshot hold = now.hold.since(base.hold);
  const pipeline::DurationHistogram::Snapshot wait = now.wait.since(base.wait);
  message_.addValue(h, "map_lock_hold_p99_ms", "%.2f", hold.quantileUs(0.99) / 1000.0);
  message_.addValue(h, "map_lock_hold_max_ms_total", "%.2f",
                    static_cast<double>(now.hold.max_us) / 1000.0);
  message_.addValue(h, "map_lock_wait_p99_ms", "%.2f", wait.quantileUs(0.99) / 1000.0);
  message_.addValue(h, "map_lock_wait_max_ms_total", "%.2f",
                    static_cast<double>(now.wait.max_us) / 1000.0);
  // What each cycle costs the map lock and the bus (device backends; 0 on the CPU).
  const pipeline::DurationHistogram::Snapshot cycle_hold = now.cycle_hold.since(base.cycle_hold);
  const pipeline::DurationHistogram::Snapshot sync_bytes = now.sync_bytes.since(base.sync_bytes);
  const pipeline::DurationHistogram::Snapshot copy_bytes =
      now.heightmap_bytes.since(base.heightmap_bytes);
  message_.addValue(h, "heightmap_lock_hold_p50_ms", "%.2f", cycle_hold.quantileUs(0.5) / 1000.0);
  message_.addValue(h, "heightmap_lock_hold_p99_ms", "%.2f", cycle_hold.quantileUs(0.99) / 1000.0);
  message_.addValue(h, "sync_copy_bytes_p50", "%.0f", sync_bytes.quantileUs(0.5));
  message_.addValue(h, "sync_copy_bytes_p99", "%.0f", sync_bytes.quantileUs(0.99));
  message_.addValue(h, "heightmap_copy_bytes_p50", "%.0f", copy_bytes.quantileUs(0.5));
  message_.addValue(h, "heightmap_copy_bytes_p99", "%.0f", copy_bytes.quantileUs(0.99));
  message_.addValue(h, "heightmap_transfer_bytes_p99", "%.0f",
                    now.transfer_bytes.since(base.transfer_bytes).quantileUs(0.99));
  message_.addValue(
      h, "publish_lead_ms", "%.1f",
      static_cast<double>(stats_.publish_lead_us.load(std::memory_order_relaxed)) / 1000.0);
}

void DiagnosticsReporter::addRealtimeAndSecurityStatuses(const char* hw) noexcept {
  // Real time.
  const bool degraded = realtime_ != nullptr && realtime_->degraded;
  const int r = message_.addStatus(degraded ? msgs::kDiagnosticWarn : msgs::kDiagnosticOk,
                                   realtime_name_.c_str(),
                                   degraded ? "real-time settings refused" : "ok", hw);
  message_.addValue(r, "scheduling", "%s",
                    realtime_ != nullptr ? realtime_->summary.c_str() : "unknown");
  message_.addValue(r, "memory_locked", "%s",
                    realtime_ != nullptr && realtime_->memory_locked ? "true" : "false");

  // DDS Security: decided at start; WARN while running without what was asked for.
  const bool security_warn = !settings_.security_warning.empty();
  const int sec = message_.addStatus(
      security_warn ? msgs::kDiagnosticWarn : msgs::kDiagnosticOk, security_name_.c_str(),
      security_warn ? settings_.security_warning.c_str() : settings_.security_summary.c_str(), hw);
  message_.addValue(sec, "enabled", "%s", settings_.secure ? "true" : "false");
}

void DiagnosticsReporter::addSensorStatus(std::size_t i, double dt) noexcept {
  const ReporterSettings::Sensor& sensor = settings_.sensors[i];
  const Totals::PerSensor& c = ring_[head_].totals.sensor[i];
  const Totals::PerSensor& b = base_->totals.sensor[i];
  const auto rate = [&](std::uint64_t now, std::uint64_t before) {
    return dt > 0.0 ? static_cast<double>(now - before) / dt : 0.0;
  };
  const bool depth = !sensor.camera_info_topic.empty();
  // Silence is judged once a whole window has passed since start (a late driver is not yet
  // a fault); rejections at once. The pipeline status says what the rejections were.
  const bool whole_window = ring_[head_].ns - started_ns_ >= window_ns_;
  char text[160];
  std::uint8_t level = msgs::kDiagnosticOk;
  if (inputs_ != nullptr && inputs_->clouds[i] > 1) {
    level = msgs::kDiagnosticWarn;
    std::snprintf(text, sizeof(text), "%u publishers of %s (see pipeline)", inputs_->clouds[i],
                  sensor.topic.c_str());
  } else if (c.rejected > b.rejected) {
    level = msgs::kDiagnosticWarn;
    std::snprintf(text, sizeof(text), "%" PRIu64 " of %" PRIu64 " %s rejected (see pipeline)",
                  c.rejected - b.rejected, c.received - b.received,
                  depth ? "depth images" : "clouds");
  } else if (c.missing > b.missing) {
    level = msgs::kDiagnosticWarn;
    std::snprintf(text, sizeof(text),
                  "%" PRIu64 " %s missing by the gaps in their stamps, %" PRIu64 " received",
                  c.missing - b.missing, depth ? "depth images" : "clouds",
                  c.received - b.received);
  } else if (whole_window && c.received == b.received) {
    level = msgs::kDiagnosticWarn;
    std::snprintf(text, sizeof(text), "no %s on %s %s", depth ? "depth image" : "point cloud",
                  sensor.topic.c_str(), c.received == 0 ? "since start" : "any more");
  } else {
    std::snprintf(text, sizeof(text), "ok");
  }
  char name[160];
  std::snprintf(name, sizeof(name), "%s: sensor %s", settings_.name.c_str(), sensor.name.c_str());
  const int s = message_.addStatus(level, name, text, settings_.hardware_id.c_str());
  message_.addValue(s, "kind", "%s", depth ? "depth" : "points");
  message_.addValue(s, "topic", "%s", sensor.topic.c_str());
  message_.addValue(s, "received", "%" PRIu64, c.received);
  message_.addValue(s, "rate_hz", "%.2f", rate(c.received, b.received));
  message_.addValue(s, "accepted", "%" PRIu64, c.accepted);
  message_.addValue(s, "accepted_rate_hz", "%.2f", rate(c.accepted, b.accepted));
  message_.addValue(s, "scans_integrated", "%" PRIu64, c.scans);
  message_.addValue(s, "scan_rate_hz", "%.2f", rate(c.scans, b.scans));
  message_.addValue(s, "rejected", "%" PRIu64, c.rejected);
  message_.addValue(s, "missing", "%" PRIu64, c.missing);
  message_.addValue(s, "publishers", "%u", inputs_ != nullptr ? inputs_->clouds[i] : 0u);
  message_.addValue(s, "rate_limited", "%" PRIu64, c.rate_limited);
  message_.addValue(s, "max_rate_hz", "%g", sensor.max_rate_hz);
  if (depth) {
    message_.addValue(s, "camera_info_topic", "%s", sensor.camera_info_topic.c_str());
    message_.addValue(s, "camera_info_received", "%" PRIu64, c.camera_info);
    message_.addValue(s, "camera_info_rejected", "%" PRIu64, c.camera_info_bad);
    message_.addValue(s, "images_without_camera_info", "%" PRIu64, c.no_camera_info);
  }
}

void DiagnosticsReporter::logChanges() noexcept {
  if (pipeline_level_ != msgs::kDiagnosticOk) {
    logLine(pipeline_level_ == msgs::kDiagnosticError ? LogLevel::kError : LogLevel::kWarning,
            "%s %s: %s", pipeline_name_.c_str(), levelName(pipeline_level_), pipeline_message_);
  }
  if (heightmap_level_ != msgs::kDiagnosticOk && !stale_) {  // stale: said once, above
    logLine(heightmap_level_ == msgs::kDiagnosticError ? LogLevel::kError : LogLevel::kWarning,
            "%s %s: %s", heightmap_name_.c_str(), levelName(heightmap_level_), heightmap_message_);
  }
}

}  // namespace raymap::service
