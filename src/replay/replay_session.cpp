// SPDX-License-Identifier: BSD-3-Clause
// ReplaySession: passes over the inputs, ray files published as driver scans and poses, flow
// control when unpaced (rate 0: as fast as the subscriber keeps up), progress.
#include "src/replay/replay_session.hpp"

#include <algorithm>

#include "platform/clock.hpp"
#include "src/bag/bag_reader.hpp"
#include "src/core/eigen_conversions.hpp"
#include "src/record/record_log_reader.hpp"
#include "src/security/secure_participant.hpp"

namespace raymap::replay {
namespace {

/// A writer sees its subscriber before that subscriber has matched the writer, and a best-effort
/// reader drops what arrives before. The pause after the writer-side match covers the reader's
/// side, with room for a loaded machine (0.2 s lost the first cloud under ASan in CI, and so did
/// skipping the pause when the match was already there at the first look).
constexpr double kReaderSideMatchSeconds = 1.0;

/// Unpaced: a subscriber that reports no progress for this long is not waited for.
constexpr double kFeedbackTimeoutSeconds = 2.0;

/// The counters of raymapd's "raymapd: pipeline" status that account for every received cloud.
/// (Depth images count as clouds; those above a sensor's max_rate_hz or before its CameraInfo
/// are accounted too, and so are scans the latency bound shed whole and scans that put no ray
/// into the map.)
constexpr const char* kProcessedKeys[] = {
    "raymapd: pipeline/scans_integrated",           "raymapd: pipeline/scans_empty",
    "raymapd: pipeline/scans_dropped_no_pose",      "raymapd: pipeline/clouds_dropped_overflow",
    "raymapd: pipeline/clouds_malformed",           "raymapd: pipeline/clouds_too_large",
    "raymapd: pipeline/clouds_wrong_frame",         "raymapd: pipeline/clouds_rate_limited",
    "raymapd: pipeline/images_without_camera_info", "raymapd: pipeline/scans_shed"};

std::optional<double> processedClouds(const driver::DiagnosticsListener& diagnostics) {
  double sum = 0.0;
  for (const char* key : kProcessedKeys) {
    const auto value = diagnostics.number(key);
    if (!value) {
      return std::nullopt;
    }
    sum += *value;
  }
  return sum;
}

}  // namespace

ReplaySession::ReplaySession(const ReplayOptions& options, platform::ShutdownSignals signals)
    : options_(options), clock_(options.rate, signals) {}

Result<std::unique_ptr<ReplaySession>> ReplaySession::create(const ReplayOptions& options,
                                                             platform::ShutdownSignals signals) {
  std::unique_ptr<ReplaySession> s(new ReplaySession(options, signals));
  auto participant =
      security::openToolParticipant(options.domain, "raymap replay", security::kToolsEnclave);
  if (!participant) {
    return Unexpected(std::move(participant).error());
  }
  s->participant_.emplace(std::move(participant).value());
  // The simulated driver's writers only for ray files: bags and logs get a writer per recorded
  // topic. An idle driver writer on the bag's own cloud or odometry topic is a second publisher
  // to raymapd (two pose sources: ERROR).
  bool any_ray_file = false;
  for (const std::string& input : options.inputs) {
    any_ray_file = any_ray_file || (!record::isRecordLogInput(input) && !bag::isBag(input));
  }
  if (any_ray_file) {
    auto driver = driver::DriverPublisher::create(*s->participant_, options.cloud_topic,
                                                  options.odometry_topic, 1);
    if (!driver) {
      return Unexpected(std::move(driver).error());
    }
    s->driver_ = std::move(driver).value();
  }
  if (options.rate <= 0.0) {
    // raymapd's progress reports are read on the same participant: one DDS identity per process
    // (Cyclone DDS 0.10 checks topics against a process's first participant's permissions, and
    // a process with two secure participants crashed in Cyclone when a secure Fast DDS node
    // joined: docs/security.md).
    auto feedback =
        driver::DiagnosticsListener::create(*s->participant_, options.diagnostics_topic);
    if (!feedback) {
      return Unexpected(std::move(feedback).error());
    }
    s->feedback_ = std::move(feedback).value();
  }
  return s;
}

bool ReplaySession::waitForSubscriber(const std::function<std::uint32_t()>& matched,
                                      const std::string& topic) {
  if (waited_for_subscriber_) {
    return true;
  }
  waited_for_subscriber_ = true;
  const std::int64_t end =
      platform::monotonicNowNs() + static_cast<std::int64_t>(options_.wait_s * 1e9);
  bool waited = false;
  while (matched() == 0 && platform::monotonicNowNs() < end) {
    if (!waited && options_.on_waiting) {
      options_.on_waiting(topic);
    }
    waited = true;
    if (!clock_.sleepFor(0.02)) {
      return false;
    }
  }
  if (matched() == 0) {
    stats_.warnings.push_back("no subscriber of " + topic + " after " +
                              std::to_string(options_.wait_s) + " s: publishing anyway");
  } else if (!clock_.sleepFor(kReaderSideMatchSeconds)) {
    // Also when the subscriber was matched at the first look: that says nothing of how long
    // ago, and the subscriber's side may still be behind (a cloud was lost so under ASan in CI).
    return false;
  }
  if (stats_.scans + stats_.poses + stats_.messages == 0) {
    // Time zero is when publishing starts: the wait does not make the first data late (and
    // then sent in a burst that overflows a subscriber's queue).
    clock_.start();
    stats_.stamp_zero_ns = clock_.stampAt(0.0);
  }
  return true;
}

bool ReplaySession::waitForRoom() {
  if (!feedback_) {
    return true;
  }
  const std::int64_t start = platform::monotonicNowNs();
  std::optional<double>& baseline = processed_baseline_;
  for (;;) {
    feedback_->poll();
    const auto processed = processedClouds(*feedback_);
    if (processed && !baseline) {
      baseline = *processed - static_cast<double>(stats_.scans);
    }
    if (processed &&
        static_cast<double>(stats_.scans) - (*processed - *baseline) < options_.max_ahead) {
      return true;
    }
    if (static_cast<double>(platform::monotonicNowNs() - start) * 1e-9 >
        (baseline ? kFeedbackTimeoutSeconds : options_.wait_s)) {
      ++stats_.feedback_timeouts;
      if (!baseline) {
        stats_.warnings.push_back("replay.rate: max: no progress report on " +
                                  options_.diagnostics_topic +
                                  " (is raymapd running?): publishing unpaced");
        feedback_.reset();
      }
      return true;
    }
    if (!clock_.sleepFor(0.002)) {
      return false;
    }
  }
}

void ReplaySession::reportProgress(double input_fraction, const std::string& input, bool finished) {
  if (options_.on_progress) {
    options_.on_progress(ReplayProgress{stats_, input, input_fraction, clock_.elapsed(),
                                        clock_.maxLateMs(), finished});
  }
}

bool ReplaySession::publishDriverScan(std::int64_t stamp_of_zero, double& played_until_s) {
  driver::DriverPublisher& driver = *driver_;
  const auto replayTime = [&](std::int64_t stamp_ns) {
    return pass_offset_s_ + static_cast<double>(stamp_ns - stamp_of_zero) * 1e-9;
  };
  // Poses first, each when it is due, then the cloud once its sweep is complete.
  for (const PoseKnot& knot : driver_scan_.knots) {
    if (!clock_.waitUntil(replayTime(knot.stamp_ns))) {
      return false;
    }
    io::Pose pose;
    pose.position = toEigen(knot.position);
    if (options_.pose_odometry) {
      driver.publishOdometry(knot.stamp_ns, pose, options_.world_frame.c_str(),
                             options_.base_frame.c_str());
    }
    if (options_.pose_tf) {
      driver.publishTf(knot.stamp_ns, pose, options_.world_frame.c_str(),
                       options_.base_frame.c_str());
    }
    ++stats_.poses;
  }
  if (!waitForRoom()) {
    return false;
  }
  const double cloud_time = replayTime(driver_scan_.knots.back().stamp_ns);
  if (!clock_.waitUntil(cloud_time)) {
    return false;
  }
  driver.reserveCloud(static_cast<std::uint32_t>(driver_scan_.points.size()));
  driver.publishCloud(driver_scan_.points, {}, driver_scan_.stamp_ns, options_.frame.c_str());
  ++stats_.scans;
  stats_.points += driver_scan_.points.size();
  stats_.data_seconds += cloud_time - played_until_s;
  played_until_s = cloud_time;
  return true;
}

void ReplaySession::advancePastRayFile(std::optional<double> last_scan_start_s,
                                       std::optional<double> scan_spacing_s,
                                       double played_until_s) {
  if (last_scan_start_s && scan_spacing_s && *scan_spacing_s > 0.0 &&
      *last_scan_start_s + *scan_spacing_s > played_until_s) {
    pass_offset_s_ = *last_scan_start_s + *scan_spacing_s;
  } else {
    pass_offset_s_ = std::max(pass_offset_s_, played_until_s) + kGapBetweenInputsSeconds;
  }
}

Result<void> ReplaySession::playRayFile(const std::string& path) {
  auto opened = io::openRaySource(path, options_.source);
  if (!opened) {
    return Unexpected(std::move(opened).error());
  }
  ScanReader reader(std::move(opened).value());
  driver::DriverPublisher& driver = *driver_;
  // The clouds' subscriber, and its pose source: scans whose poses were lost in discovery
  // would be dropped.
  const bool tf_only = options_.pose_tf && !options_.pose_odometry;
  if (!waitForSubscriber(
          [&driver, tf_only] {
            return std::min(driver.matchedCloudReaders(),
                            tf_only ? driver.matchedTfReaders() : driver.matchedOdometryReaders());
          },
          options_.cloud_topic)) {
    return {};
  }
  if (options_.tf_static) {
    driver.publishTfStatic(io::Pose{}, options_.base_frame.c_str(), options_.frame.c_str());
  }
  std::optional<double> t_zero;            // the file time where the played window starts
  double played_until_s = pass_offset_s_;  // replay time of the last cloud of this file
  // Replay times of the last scan's start and the spacing of scan starts: the next input (or
  // pass) starts one spacing after the last scan started, so a looped 10 Hz file stays a 10 Hz
  // stream with a constant phase, as a sensor that kept running.
  std::optional<double> last_scan_start_s;
  std::optional<double> scan_spacing_s;
  for (;;) {
    auto more = reader.next(scan_);
    if (!more) {
      return Unexpected(std::move(more).error());
    }
    if (!more.value()) {
      break;
    }
    if (!t_zero) {
      t_zero = scan_.t_first_s + options_.start_s;
    }
    if (scan_.t_first_s < *t_zero) {
      continue;  // before the start
    }
    if (options_.duration_s > 0.0 && scan_.t_first_s >= *t_zero + options_.duration_s) {
      break;
    }
    const std::int64_t stamp_of_zero = clock_.stampAt(pass_offset_s_);
    toDriverScan(scan_, stamp_of_zero, *t_zero, options_.pose_period_s, driver_scan_);
    stats_.origin_conflicts += driver_scan_.origin_conflicts;
    if (!publishDriverScan(stamp_of_zero, played_until_s)) {
      return {};
    }
    const double scan_start =
        pass_offset_s_ + static_cast<double>(driver_scan_.stamp_ns - stamp_of_zero) * 1e-9;
    if (last_scan_start_s) {
      scan_spacing_s = scan_start - *last_scan_start_s;
    }
    last_scan_start_s = scan_start;
    reportProgress(reader.progress(), path);
  }
  advancePastRayFile(last_scan_start_s, scan_spacing_s, played_until_s);
  return {};
}

Result<ReplayStats> ReplaySession::run() {
  clock_.start();
  stats_.stamp_zero_ns = clock_.stampAt(0.0);
  do {
    for (const std::string& input : options_.inputs) {
      auto played = record::isRecordLogInput(input) ? playLog(input)
                    : bag::isBag(input)             ? playBag(input)
                                                    : playRayFile(input);
      if (!played) {
        return Unexpected(std::move(played).error());
      }
      if (clock_.stopped()) {
        break;
      }
    }
    if (!clock_.stopped()) {
      ++stats_.passes;
    }
  } while (options_.loop && !clock_.stopped());
  // Best-effort samples still in flight when the participant goes are lost: a moment for the
  // last cloud to leave. Reliable ones not yet acknowledged (a recorded odometry or transform
  // after the last cloud) would be lost with their writers too: wait for the readers, at most
  // 2 s (a reader that went away is no longer waited for).
  (void)clock_.sleepFor(0.2);
  if (!clock_.stopped() && !participant_->waitForAcknowledgements(2'000'000'000)) {
    stats_.warnings.emplace_back("the last reliable messages were not acknowledged within 2 s");
  }
  stats_.wall_seconds = clock_.elapsed();
  stats_.max_late_ms = clock_.maxLateMs();
  reportProgress(1.0, "", true);
  return stats_;
}

}  // namespace raymap::replay
