// SPDX-License-Identifier: BSD-3-Clause
// Integrator: pose bookkeeping, deskewing and batching (see the header's design note).
#include "src/pipeline/integrator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include "platform/clock.hpp"
#include "src/core/eigen_conversions.hpp"
#include "src/pipeline/deskew.hpp"
#include "src/pipeline/load_shedding.hpp"

namespace raymap::pipeline {
namespace {

constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::max();
/// A scan with time for fewer points than this before its deadline is cut short there (or shed
/// whole when none of it went in yet): a smaller batch would cost more in overhead than it adds.
constexpr std::uint64_t kMinVisits = 256;
/// The ray budget keeps the integrator's work under this share of its time (the rest absorbs
/// the variation in scan size and in the machine's other load).
constexpr double kBudgetLoad = 0.85;
/// The stride goes up when the pressure passes kBudgetRaise, and down when one step finer would
/// still keep it below kBudgetLower: in between it stays (no oscillation at the edge).
constexpr double kBudgetRaise = 0.95;
constexpr double kBudgetLower = 0.9;

}  // namespace

Integrator::Integrator(VoxelMap& map, Backend& backend, platform::PiMutex& map_mutex,
                       ScanMailbox& mailbox, PoseQueue& poses, ArrivalQueue& integrated,
                       LatestPosition& latest, const IntegratorSettings& settings,
                       std::vector<SensorSettings> sensors, PipelineStats& stats)
    : map_(map),
      map_mutex_(map_mutex),
      mailbox_(mailbox),
      pose_queue_(poses),
      integrated_(integrated),
      latest_(latest),
      settings_(settings),
      sensors_(std::move(sensors)),
      stats_(stats),
      history_(settings.pose_history),
      per_scan_(map.semantics() == Semantics::kPerScan),
      // Per-scan semantics integrate one scan per backend call, so a batch holds a whole scan.
      batcher_(
          map, backend,
          per_scan_ ? std::max(settings.batch_rays, mailbox.maxPoints()) : settings.batch_rays) {
  preparers_.reserve(sensors_.size());
  for (const SensorSettings& sensor : sensors_) {
    preparers_.emplace_back(map_, sensor.filter);
  }
  rays_ = batcher_.staging();  // the one batch of rays: the batcher's, filled here
  for (const SensorSettings& sensor : sensors_) {
    sensor_on_device_.push_back(backend.preparesOnDevice(sensor.filter));
  }
  if (std::find(sensor_on_device_.begin(), sensor_on_device_.end(), true) !=
      sensor_on_device_.end()) {
    points_.resize(batcher_.capacity());
    pose_samples_.resize(RM_DESKEW_MAX_POSE_SAMPLES);
    segments_.reserve(RM_DESKEW_MAX_SEGMENTS);
    segment_scans_.reserve(RM_DESKEW_MAX_SEGMENTS);
  }
  completed_.resize(std::size_t{mailbox_.capacity()} + 1);
  completed_sensor_.resize(completed_.size());
}

void Integrator::drainPoses() noexcept {
  PoseUpdate update;
  while (pose_queue_.pop(update)) {
    if (update.kind == PoseUpdate::kSensorExtrinsic) {
      if (update.sensor < sensors_.size()) {
        sensors_[update.sensor].extrinsic = update.pose;
        deskewer_.reset();  // the cached sensor pose used the old extrinsic
      }
      continue;
    }
    (void)startsOver(update);
    if (history_.push(update.stamp_ns, update.pose)) {
      latest_.store(update.stamp_ns, toVec3(update.pose.position));
    } else {
      stats_.poses_out_of_order.add();
    }
  }
}

bool Integrator::startsOver(const PoseUpdate& update) noexcept {
  const io::Pose* newest = history_.newestPose();
  if (newest == nullptr) {
    return false;
  }
  const std::int64_t back = history_.newestStamp() - update.stamp_ns;
  const double jump = (update.pose.position - newest->position).norm();
  const bool reset = back > settings_.time_reset_ns;
  const bool jumped = !reset && settings_.max_pose_jump_m > 0.0 &&
                      update.stamp_ns > history_.newestStamp() && jump > settings_.max_pose_jump_m;
  if (!reset && !jumped) {
    return false;
  }
  if (reset) {
    stats_.pose_time_resets.add();
    stats_.last_time_reset_ms.store(back / 1000000, std::memory_order_relaxed);
  } else {
    stats_.pose_jumps.add();
    stats_.last_pose_jump_mm.store(std::llround(jump * 1000.0), std::memory_order_relaxed);
  }
  // Scans already converted were deskewed with the poses before: they go in as they are. What
  // is left of a scan being converted finds no pose across the break and is left out.
  if (jumped && settings_.clear_on_jump) {
    if (batch_size_ > 0 || completed_count_ > 0) {
      integrateBatch(settings_.clock_ns());
    }
    std::lock_guard<platform::PiMutex> lock(map_mutex_);
    map_.clearWindow();
    stats_.window_clears.add();
  }
  history_.clear();
  deskewer_.reset();
  return true;
}

bool Integrator::beginSegment() noexcept {
  if (segments_.size() == RM_DESKEW_MAX_SEGMENTS) {
    return false;
  }
  const std::size_t poses =
      history_.copyCovering(scan_start_ns_, scan_end_ns_,
                            std::span<rm_pose_sample>(pose_samples_).subspan(pose_samples_used_));
  if (poses == 0) {
    return false;
  }
  segments_.push_back(rm_deskew_segment{io::toRmPose(sensors_[scan_->sensor].extrinsic),
                                        static_cast<rm_u32>(pose_samples_used_),
                                        static_cast<rm_u32>(poses)});
  segment_scans_.push_back(scan_->sequence);
  pose_samples_used_ += poses;
  return true;
}

template <class Convert>
bool Integrator::visitScan(std::uint32_t capacity, std::uint64_t max_visits,
                           Convert&& convert) noexcept {
  const std::span<const msgs::ScanPoint> points = scan_->points();
  const SensorSettings& sensor = sensors_[scan_->sensor];
  std::uint32_t index = 0;
  while (batch_size_ < capacity && max_visits > 0 && order_.next(&index)) {
    --max_visits;
    const msgs::ScanPoint& p = points[index];
    if ((p.flags & msgs::kPointNoReturn) != 0u) {
      stats_.points_no_return.add();  // no direction: nothing to clear along
      continue;
    }
    if (!usableTime(p.time_s, sensor.max_time_offset_s)) {
      continue;  // counted (points_bad_time) when the scan was taken
    }
    batch_size_ += convert(p) ? 1u : 0u;
  }
  return order_.done();
}

bool Integrator::convertScanToPoints(std::uint64_t max_visits) noexcept {
  const auto segment = static_cast<rm_u32>(segments_.size() - 1);
  // The times PointDeskewer would find a pose for with the history as it is now (the scan's
  // were covered when it was taken; a small history may have let the oldest go since).
  const std::int64_t oldest = history_.oldestStamp();
  const std::int64_t latest = history_.newestStamp() + settings_.pose_hold_ns;
  const std::int64_t stamp = scan_->header.stamp_ns;
  return visitScan(
      static_cast<std::uint32_t>(points_.size()), max_visits, [&](const msgs::ScanPoint& p) {
        const std::int64_t t = pointTimeNs(stamp, p.time_s);
        if (t < oldest || t > latest) {
          return false;  // unreachable, as for PointDeskewer
        }
        const std::uint32_t flags =
            (p.flags & msgs::kPointFreeOnly) != 0u ? RM_RAW_RAY_NO_RETURN : 0u;
        points_[batch_size_] = rm_scan_point{p.x, p.y, p.z, p.intensity, flags, segment, t};
        return true;
      });
}

bool Integrator::convertScan(std::uint64_t max_visits) noexcept {
  // Each conversion step looks its poses up afresh: a pose that came since the last step counts
  // from here on, for the host's deskewing as for the device's (which gets the poses of each
  // step in a segment of its own).
  deskewer_.reset();
  if (batch_size_ == 0) {
    points_mode_ = sensor_on_device_[batch_sensor_];
    pose_samples_used_ = 0;
    segments_.clear();
    segment_scans_.clear();
  }
  if (points_mode_) {
    if (beginSegment()) {
      return convertScanToPoints(max_visits);
    }
    if (batch_size_ > 0) {
      return false;  // the batch's tables are full: it goes in first
    }
    points_mode_ = false;  // more poses than a batch's table holds: rays, deskewed here
  }
  const SensorSettings& sensor = sensors_[scan_->sensor];
  return visitScan(
      static_cast<std::uint32_t>(rays_.size()), max_visits, [&](const msgs::ScanPoint& p) {
        // false is unreachable: the scan's first and last times were checked
        return deskewer_.toRay(p, scan_->header.stamp_ns, history_, settings_.pose_hold_ns,
                               sensor.extrinsic, scan_->sequence, rays_[batch_size_]);
      });
}

std::int64_t Integrator::batchDue(std::int64_t now_ns) const noexcept {
  // A scan with a deadline does not wait for company.
  return batch_due_ns_ != kNever ? now_ns : batch_first_ns_ + settings_.batch_deadline_ns;
}

std::uint64_t Integrator::visitsBefore(std::int64_t deadline) const noexcept {
  if (deadline == kNever) {
    return std::numeric_limits<std::uint64_t>::max();
  }
  // The batch's rays still to integrate, then each new point at what a point of a whole scan
  // has cost lately (deskewing, integration and waits).
  const double left = static_cast<double>(deadline - settings_.clock_ns()) -
                      static_cast<double>(batch_size_) * ns_per_ray_;
  if (left <= 0.0) {
    return 0;
  }
  return static_cast<std::uint64_t>(left / std::max(ns_per_ray_, scan_ns_per_point_));
}

void Integrator::integrateBatch(std::int64_t now_ns) noexcept {
  if (batch_size_ == 0 && completed_count_ == 0) {
    return;
  }
  RayPreparer& preparer = preparers_[batch_sensor_];
  const RayCounters rays_before = preparer.counters();
  const BatcherCounters batcher_before = batcher_.counters();
  const std::int64_t batch_started = settings_.clock_ns();
  const DeskewTables tables{
      std::span<const rm_pose_sample>(pose_samples_.data(), pose_samples_used_), segments_,
      segment_scans_};
  const std::size_t total = batch_size_;
  std::size_t done = 0;
  std::unique_lock<platform::PiMutex> lock(map_mutex_, std::defer_lock);
  do {
    lock.lock();
    const std::int64_t hold_started = settings_.clock_ns();
    std::int64_t now = hold_started;
    // Slices until the hold budget is spent (one slice at least; the whole scan per-scan).
    do {
      std::size_t slice = total - done;
      if (!per_scan_) {
        const double fit = static_cast<double>(settings_.max_lock_hold_ns) / ns_per_ray_;
        slice = std::min(slice, static_cast<std::size_t>(std::clamp(fit, 256.0, 1048576.0)));
      }
      const std::int64_t slice_started = now;
      // The slice goes in whole before the lock is given up: what the batch keeps is flushed.
      // Failures are counted by the batcher (integrate_errors below).
      if (points_mode_) {
        (void)batcher_.integratePoints(
            preparer, std::span<const rm_scan_point>(points_.data() + done, slice), tables);
      } else {
        (void)batcher_.integrateStaged(preparer, done, slice);
      }
      done += slice;
      now = settings_.clock_ns();
      if (slice > 0) {
        const double measured =
            static_cast<double>(now - slice_started) / static_cast<double>(slice);
        // A slice stalled by preemption counts, but at most four times the estimate: one stall
        // must not inflate the latency bound's predictions.
        ns_per_ray_ = 0.75 * ns_per_ray_ + 0.25 * std::clamp(measured, 1.0, 4.0 * ns_per_ray_);
      }
    } while (done < total && now - hold_started < settings_.max_lock_hold_ns);
    stats_.map_lock_hold_us.record(static_cast<std::uint64_t>((now - hold_started) / 1000));
    if (done < total) {
      lock.unlock();  // a waiting publisher gets the map here (the PI mutex hands it over)
    }
  } while (done < total);
  // Still locked: the last slice's hold.
  if (scan_stamp_pending_ != 0) {
    stats_.newest_scan_stamp_ns.store(scan_stamp_pending_, std::memory_order_relaxed);
  }
  stats_.integrate_batch_us.record(
      static_cast<std::uint64_t>((settings_.clock_ns() - batch_started) / 1000));
  // Arrivals go out while the map is locked: the publisher reads how many are queued under the
  // same lock, so it counts exactly the scans its map contains.
  for (std::uint32_t i = 0; i < completed_count_; ++i) {
    integrated_.push(completed_[i]);  // full: the latency sample is lost, nothing else
  }
  lock.unlock();
  const BatcherCounters& batcher_now = batcher_.counters();
  stats_.batches.add(batcher_now.batches - batcher_before.batches);
  stats_.integrate_errors.add(batcher_now.batches_failed - batcher_before.batches_failed);
  const std::uint64_t rays_in = batcher_now.rays_integrated - batcher_before.rays_integrated;
  stats_.rays_integrated.add(rays_in);
  countRejections(rays_before, preparer.counters());
  countCompletedScans(rays_in);
  completed_count_ = 0;
  batch_size_ = 0;
  scan_stamp_pending_ = 0;
  batch_due_ns_ = kNever;
  (void)now_ns;
}

void Integrator::countCompletedScans(std::uint64_t rays_in) noexcept {
  // Scans that put nothing in the map (every ray rejected: a min range beyond every return, a
  // wrong extrinsic) are not integrated: counted apart, and the map goes stale (health). A scan
  // larger than a batch went in over several: their rays count for the batch that finishes it.
  rays_since_scan_end_ += rays_in;
  if (completed_count_ == 0) {
    return;
  }
  if (rays_since_scan_end_ == 0) {
    stats_.scans_empty.add(completed_count_);
    return;
  }
  rays_since_scan_end_ = 0;
  stats_.scans_integrated.add(completed_count_);
  for (std::uint32_t i = 0; i < completed_count_; ++i) {
    if (completed_sensor_[i] < stats_.sensors.size()) {
      stats_.sensors[completed_sensor_[i]].scans_integrated.add();
    }
  }
  stats_.last_scan_integrated_ns.store(settings_.clock_ns(), std::memory_order_relaxed);
}

void Integrator::countRejections(const RayCounters& before, const RayCounters& now) noexcept {
  stats_.rays_rejected.add(now.rejected() - before.rejected());
  stats_.rays_invalid.add(now.rays_invalid - before.rays_invalid);
  stats_.rays_too_short.add(now.rays_too_short - before.rays_too_short);
  stats_.rays_out_of_bounds.add(now.rays_out_of_bounds - before.rays_out_of_bounds);
  stats_.rays_outside_window.add(now.rays_outside_window - before.rays_outside_window);
}

std::int64_t Integrator::step(std::int64_t now_ns) noexcept {
  busy_since_ns_ = now_ns;
  const std::int64_t wake = step_(now_ns);
  accountLoad(settings_.clock_ns());
  return wake;
}

void Integrator::accountLoad(std::int64_t now_ns) noexcept {
  // The load: busy time over about a second. Overloaded from 90 % until it falls below 70 %.
  // Called between scans too: under overload one step() can last as long as the input does.
  load_busy_ns_ += now_ns - busy_since_ns_;
  busy_since_ns_ = now_ns;
  if (load_window_start_ns_ == 0) {
    load_window_start_ns_ = now_ns;
    load_busy_ns_ = 0;
    return;
  }
  const std::int64_t window = now_ns - load_window_start_ns_;
  if (window < 1000000000) {
    return;
  }
  const double load = static_cast<double>(load_busy_ns_) / static_cast<double>(window);
  overloaded_ = overloaded_ ? load > 0.7 : load > 0.9;
  stats_.integrator_load_percent.store(static_cast<std::int32_t>(std::lround(load * 100.0)),
                                       std::memory_order_relaxed);
  updateRayBudget(load);
  load_window_start_ns_ = now_ns;
  load_busy_ns_ = 0;
}

void Integrator::updateRayBudget(double load) noexcept {
  // The pressure: the load the integrator would have had at this stride had it taken every
  // scan offered (those dropped on overflow and those shed whole included). The stride follows
  // it to keep the load near kBudgetLoad, thinning every scan alike rather than letting whole
  // scans be dropped; it comes down again once the pressure is clearly lower (hysteresis).
  const std::uint64_t dropped = mailbox_.droppedOldest();
  const double per_scan = window_scans_taken_ > 0
                              ? window_points_taken_ / static_cast<double>(window_scans_taken_)
                              : 0.0;
  const double offered =
      window_points_taken_ + static_cast<double>(dropped - window_dropped_before_) * per_scan;
  window_points_taken_ = 0.0;
  window_scans_taken_ = 0;
  window_dropped_before_ = dropped;
  const double accepted = window_points_accepted_;
  window_points_accepted_ = 0.0;
  if (settings_.max_latency_ns <= 0 || settings_.max_stride <= 1 || offered <= 0.0) {
    budget_stride_ = 1;
  } else {
    const double pressure = accepted > 0.0 ? load * offered / accepted : 1.0;
    const double wanted = static_cast<double>(budget_stride_) * pressure / kBudgetLoad;
    if (pressure > kBudgetRaise) {
      budget_stride_ = static_cast<std::uint32_t>(
          std::min(std::ceil(wanted), static_cast<double>(settings_.max_stride)));
    } else if (budget_stride_ > 1 && pressure * static_cast<double>(budget_stride_) /
                                             static_cast<double>(budget_stride_ - 1) <
                                         kBudgetLower) {
      // One step finer would still stay below kBudgetLower.
      budget_stride_ = static_cast<std::uint32_t>(std::max(std::ceil(wanted), 1.0));
    }
  }
  stats_.subsample_stride.store(static_cast<std::int32_t>(budget_stride_),
                                std::memory_order_relaxed);
}

bool Integrator::takeScan() noexcept {
  scan_ = mailbox_.take();
  if (scan_ == nullptr) {
    return false;
  }
  drainPoses();  // what ingest queued before this scan (an extrinsic from its first cloud)
  scan_first_wait_ns_ = 0;
  window_points_taken_ += static_cast<double>(scan_->header.points);
  ++window_scans_taken_;
  deskewer_.reset();  // the cached pose belongs to the previous scan's sensor
  // The poses must cover the scan's usable point times; a point with a corrupt time is left
  // out (convertScan skips it), not allowed to stretch the scan.
  const ScanTimes times =
      scanTimes(scan_->points(), scan_->header.stamp_ns, sensors_[scan_->sensor].max_time_offset_s);
  if (times.bad_time > 0) {
    stats_.points_bad_time.add(times.bad_time);
  }
  scan_start_ns_ = times.start_ns;
  scan_end_ns_ = times.end_ns;
  return true;
}

void Integrator::dropScan(Counter& reason) noexcept {
  reason.add();
  mailbox_.release(scan_);
  scan_ = nullptr;
}

Integrator::PoseCheck Integrator::checkPoses(std::int64_t now_ns, std::int64_t* wake_ns) noexcept {
  io::Pose unused;
  const PoseLookup end = history_.lookup(scan_end_ns_, settings_.pose_hold_ns, &unused);
  const PoseLookup start = history_.lookup(scan_start_ns_, settings_.pose_hold_ns, &unused);
  if (start == PoseLookup::kTooOld || end == PoseLookup::kTooOld) {
    dropScan(stats_.scans_no_pose);
    return PoseCheck::kDropped;
  }
  if (end == PoseLookup::kOk && start == PoseLookup::kOk) {
    return PoseCheck::kCovered;
  }
  if (scan_first_wait_ns_ == 0) {
    scan_first_wait_ns_ = now_ns;
  }
  const std::int64_t give_up = scan_first_wait_ns_ + settings_.pose_wait_ns;
  if (now_ns >= give_up) {
    dropScan(stats_.scans_no_pose);
    return PoseCheck::kDropped;
  }
  *wake_ns = give_up;  // new poses wake the thread earlier
  // Earlier scans already in the batch do not wait for this one's poses.
  if (batch_size_ > 0 || completed_count_ > 0) {
    const std::int64_t due = batchDue(now_ns);
    if (now_ns >= due) {
      integrateBatch(now_ns);
    } else {
      *wake_ns = std::min(give_up, due);
    }
  }
  return PoseCheck::kWaiting;
}

bool Integrator::planIntake(std::int64_t now_ns, std::int64_t* deadline,
                            std::uint32_t* stride) noexcept {
  const double scan_rays =
      static_cast<double>(scan_->header.points) - static_cast<double>(scan_->header.no_return);
  PublishSchedule schedule;
  schedule.next_publish_ns = stats_.next_publish_ns.load(std::memory_order_relaxed);
  schedule.period_ns = settings_.publish_period_ns;
  // The margin of one lock hold: the last slice may overrun the plan by about that much.
  schedule.lead_ns =
      stats_.publish_lead_us.load(std::memory_order_relaxed) * 1000 + settings_.max_lock_hold_ns;
  // A scan that waited for its poses counts from when they came (about now): waiting for the
  // pose source is not a backlog of the backend's.
  const std::int64_t ready = scan_first_wait_ns_ != 0 ? now_ns : scan_->arrival_ns;
  const ShedDecision decision =
      planScan(now_ns, ready, static_cast<double>(batch_size_), scan_rays,
               std::max(ns_per_ray_, scan_ns_per_point_), schedule, settings_.max_latency_ns,
               settings_.max_stride, overloaded_ || budget_stride_ > 1 || settings_.shed_always);
  if (decision.drop && scans_shed_in_a_row_ < 2) {
    ++scans_shed_in_a_row_;
    dropScan(stats_.scans_shed);
    return false;
  }
  // After two scans shed whole, the third goes in at the largest stride whatever the
  // prediction says: the map keeps moving, and the time per ray is measured again (a
  // prediction inflated by one stalled slice must not shed everything for ever). Its deadline
  // still holds.
  scans_shed_in_a_row_ = 0;
  *stride = decision.drop ? std::max(settings_.max_stride, 1u)
                          : std::max(decision.stride, budget_stride_);
  *deadline = kNever;
  // The deadline holds whatever the load (only whole scans are shed with queues.shed: drop).
  if (settings_.max_stride > 1) {
    const std::int64_t generation =
        latestGenerationWithin(ready, schedule, settings_.max_latency_ns);
    *deadline = generation != 0 ? generation : kNever;
  }
  return true;
}

bool Integrator::convertBefore(std::int64_t now_ns, std::int64_t deadline) noexcept {
  for (;;) {
    const std::uint64_t own = visitsBefore(deadline);
    if (own < kMinVisits) {
      return true;  // out of time: what went in so far is spread over the scan
    }
    // Rays of earlier scans in the batch go in before their own deadline.
    const std::uint64_t for_batch = visitsBefore(batch_due_ns_);
    if (for_batch < kMinVisits && batch_size_ > 0) {
      integrateBatch(now_ns);
      batch_sensor_ = scan_->sensor;
      batch_first_ns_ = scan_->arrival_ns;
      continue;
    }
    if (convertScan(std::min(own, for_batch))) {
      return false;
    }
    if (per_scan_ && batch_size_ < rays_.size()) {
      return true;  // one backend call per scan: no time to convert the rest
    }
    integrateBatch(now_ns);  // full, or as much as fits before a deadline
    batch_sensor_ = scan_->sensor;
    batch_first_ns_ = scan_->arrival_ns;
  }
}

void Integrator::finishScan(std::int64_t now_ns, std::int64_t deadline, bool cut_short,
                            std::int64_t scan_started) noexcept {
  const std::uint64_t visited = order_.visited();
  const std::uint64_t left_out = order_.notVisited();
  const std::int64_t arrival = scan_->arrival_ns;
  const std::int64_t stamp = scan_->header.stamp_ns;
  const std::uint32_t points = scan_->header.points;
  const std::uint32_t sensor_index = scan_->sensor;
  mailbox_.release(scan_);
  scan_ = nullptr;
  if (cut_short && visited == 0) {
    stats_.scans_shed.add();  // its deadline passed before any of it could go in
    return;
  }
  if (left_out > 0) {
    stats_.points_shed.add(left_out);
  }
  if (cut_short) {
    stats_.scans_cut_short.add();
  }
  window_points_accepted_ += static_cast<double>(points);
  completed_sensor_[completed_count_] = sensor_index;
  completed_[completed_count_++] = arrival;
  scan_stamp_pending_ = std::max(scan_stamp_pending_, stamp);
  batch_due_ns_ = std::min(batch_due_ns_, deadline);
  if (per_scan_ || cut_short || completed_count_ == completed_.size() ||
      batch_size_ == rays_.size() || visitsBefore(batch_due_ns_) < kMinVisits) {
    integrateBatch(now_ns);
  }
  if (visited >= 1024) {
    // What a point of a scan really costs, conversion (deskewing) and waits included: the
    // latency bound predicts with this (integration alone under-predicts by the conversion).
    const double sample =
        static_cast<double>(settings_.clock_ns() - scan_started) / static_cast<double>(visited);
    scan_ns_per_point_ =
        scan_ns_per_point_ == 0.0
            ? sample
            : 0.75 * scan_ns_per_point_ + 0.25 * std::min(sample, 4.0 * scan_ns_per_point_);
  }
}

std::int64_t Integrator::step_(std::int64_t now_ns) noexcept {
  for (;;) {
    accountLoad(settings_.clock_ns());
    // Poses that came while the last scan went in: a scan taken after a long one must not wait
    // for poses that are already queued.
    drainPoses();
    if (scan_ == nullptr && !takeScan()) {
      break;
    }
    // Poses must cover the scan before any of it is converted.
    std::int64_t wake_ns = kNever;
    const PoseCheck poses = checkPoses(now_ns, &wake_ns);
    if (poses == PoseCheck::kDropped) {
      continue;
    }
    if (poses == PoseCheck::kWaiting) {
      return wake_ns;
    }
    // The latency bound: take the scan whole, subsampled, or not at all, and by when its rays
    // must be in the map. (A scan gets here once: from here on it is converted in this pass.)
    std::int64_t deadline = kNever;
    std::uint32_t stride = 1;
    if (!planIntake(now_ns, &deadline, &stride)) {
      continue;
    }
    order_.reset(scan_->header.points, stride);
    if (batch_size_ > 0 && batch_sensor_ != scan_->sensor) {
      integrateBatch(now_ns);  // a batch has one sensor's range limits
    }
    if (batch_size_ == 0) {
      batch_sensor_ = scan_->sensor;
      batch_first_ns_ = scan_->arrival_ns;
    }
    const std::int64_t scan_started = settings_.clock_ns();
    const bool cut_short = convertBefore(now_ns, deadline);
    finishScan(now_ns, deadline, cut_short, scan_started);
  }
  if (batch_size_ > 0 || completed_count_ > 0) {
    const std::int64_t due = batchDue(now_ns);
    if (now_ns >= due) {
      integrateBatch(now_ns);
    } else {
      return due;
    }
  }
  return kNever;
}

void Integrator::flush(std::int64_t now_ns) noexcept { integrateBatch(now_ns); }

}  // namespace raymap::pipeline
