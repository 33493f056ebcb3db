// SPDX-License-Identifier: BSD-3-Clause
// Integrator: pose bookkeeping, deskewing and batching (see the header's design note).
#include "src/pipeline/integrator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include "platform/clock.hpp"

namespace raymap::pipeline {
namespace {

constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::max();

std::int64_t pointTimeNs(std::int64_t stamp_ns, float time_s) noexcept {
  return stamp_ns + static_cast<std::int64_t>(std::llround(static_cast<double>(time_s) * 1e9));
}

}  // namespace

Integrator::Integrator(VoxelMap& map, Backend& backend, platform::PiMutex& map_mutex,
                       ScanMailbox& mailbox, PoseQueue& poses, ArrivalQueue& integrated,
                       LatestPosition& latest, const IntegratorSettings& settings,
                       std::vector<SensorSettings> sensors, PipelineStats& stats)
    : map_(map),
      backend_(backend),
      map_mutex_(map_mutex),
      mailbox_(mailbox),
      pose_queue_(poses),
      integrated_(integrated),
      latest_(latest),
      settings_(settings),
      sensors_(std::move(sensors)),
      stats_(stats),
      history_(settings.pose_history),
      per_scan_(map.semantics() == Semantics::kPerScan) {
  preparers_.reserve(sensors_.size());
  for (const SensorSettings& sensor : sensors_) {
    preparers_.emplace_back(map_, sensor.filter);
  }
  // Per-scan semantics integrate one scan per backend call, so a batch holds a whole scan.
  const std::uint32_t capacity =
      per_scan_ ? std::max(settings_.batch_rays, mailbox_.maxPoints()) : settings_.batch_rays;
  rays_.resize(capacity);
  prepared_.resize(capacity);
  completed_.resize(std::size_t{mailbox_.capacity()} + 1);
}

void Integrator::drainPoses() noexcept {
  PoseUpdate update;
  while (pose_queue_.pop(update)) {
    if (update.kind == PoseUpdate::kSensorExtrinsic) {
      if (update.sensor < sensors_.size()) {
        sensors_[update.sensor].extrinsic = update.pose;
        last_point_time_ns_ = INT64_MIN;  // the cached sensor pose used the old extrinsic
      }
      continue;
    }
    if (history_.push(update.stamp_ns, update.pose)) {
      latest_.store(update.stamp_ns, update.pose.position);
    } else {
      stats_.poses_out_of_order.add();
    }
  }
}

bool Integrator::convertScan() noexcept {
  const std::span<const dds::ScanPoint> points = scan_->points();
  const SensorSettings& sensor = sensors_[scan_->sensor];
  const auto capacity = static_cast<std::uint32_t>(rays_.size());
  while (scan_cursor_ < points.size() && batch_size_ < capacity) {
    const dds::ScanPoint& p = points[scan_cursor_++];
    if ((p.flags & dds::kPointNoReturn) != 0u) {
      stats_.points_no_return.add();  // no direction: nothing to clear along
      continue;
    }
    const std::int64_t t = pointTimeNs(scan_->header.stamp_ns, p.time_s);
    if (t != last_point_time_ns_) {
      io::Pose base;
      if (history_.lookup(t, settings_.pose_hold_ns, &base) != PoseLookup::kOk) {
        continue;  // unreachable: the scan's first and last times were checked
      }
      last_sensor_pose_ = io::compose(base, sensor.extrinsic);
      last_point_time_ns_ = t;
    }
    Ray& ray = rays_[batch_size_++];
    ray.origin = last_sensor_pose_.position;
    ray.sample = last_sensor_pose_.transform(
        {static_cast<double>(p.x), static_cast<double>(p.y), static_cast<double>(p.z)});
    ray.time_s = static_cast<double>(t) * 1e-9;
    ray.intensity = p.intensity;
    ray.flags = 0;
    ray.scan = scan_->sequence;
  }
  return scan_cursor_ == points.size();
}

void Integrator::integrateBatch(std::int64_t now_ns) noexcept {
  if (batch_size_ == 0 && completed_count_ == 0) {
    return;
  }
  RayPreparer& preparer = preparers_[batch_sensor_];
  const std::uint64_t rejected_before = preparer.counters().rejected();
  {
    std::lock_guard<platform::PiMutex> lock(map_mutex_);
    const std::int64_t started = platform::monotonicNowNs();
    std::span<const Ray> in(rays_.data(), batch_size_);
    while (!in.empty()) {
      const RayPreparer::Progress progress = preparer.prepare(in, prepared_);
      in = in.subspan(progress.consumed);
      if (progress.written > 0) {
        auto result =
            backend_.integrate(std::span<const PreparedRay>(prepared_.data(), progress.written));
        stats_.batches.add();
        if (!result) {
          stats_.integrate_errors.add();
        } else {
          stats_.rays_integrated.add(progress.written);
        }
      }
      if (progress.consumed == 0) {
        break;  // cannot happen without segmentation; never spin
      }
    }
    if (scan_stamp_pending_ != 0) {
      stats_.newest_scan_stamp_ns.store(scan_stamp_pending_, std::memory_order_relaxed);
    }
    const std::int64_t finished = platform::monotonicNowNs();
    stats_.integrate_batch_us.record(static_cast<std::uint64_t>((finished - started) / 1000));
    // Arrivals go out while the map is locked: the publisher reads how many are queued under the
    // same lock, so it counts exactly the scans its map contains.
    for (std::uint32_t i = 0; i < completed_count_; ++i) {
      integrated_.push(completed_[i]);  // full: the latency sample is lost, nothing else
    }
  }
  stats_.rays_rejected.add(preparer.counters().rejected() - rejected_before);
  stats_.scans_integrated.add(completed_count_);
  completed_count_ = 0;
  batch_size_ = 0;
  scan_stamp_pending_ = 0;
  (void)now_ns;
}

std::int64_t Integrator::step(std::int64_t now_ns) noexcept {
  drainPoses();
  for (;;) {
    if (scan_ == nullptr) {
      scan_ = mailbox_.take();
      if (scan_ == nullptr) {
        break;
      }
      scan_cursor_ = 0;
      scan_first_wait_ns_ = 0;
      last_point_time_ns_ = INT64_MIN;  // the cached pose belongs to the previous scan's sensor
      float t_min = 0.0f;
      float t_max = 0.0f;
      for (const dds::ScanPoint& p : scan_->points()) {
        t_min = std::min(t_min, p.time_s);
        t_max = std::max(t_max, p.time_s);
      }
      scan_start_ns_ = pointTimeNs(scan_->header.stamp_ns, t_min);
      scan_end_ns_ = pointTimeNs(scan_->header.stamp_ns, t_max);
    }
    // Poses must cover the scan before any of it is converted.
    io::Pose unused;
    const PoseLookup end = history_.lookup(scan_end_ns_, settings_.pose_hold_ns, &unused);
    const PoseLookup start = history_.lookup(scan_start_ns_, settings_.pose_hold_ns, &unused);
    if (start == PoseLookup::kTooOld || end == PoseLookup::kTooOld) {
      stats_.scans_no_pose.add();
      mailbox_.release(scan_);
      scan_ = nullptr;
      continue;
    }
    if (end != PoseLookup::kOk || start != PoseLookup::kOk) {
      if (scan_first_wait_ns_ == 0) {
        scan_first_wait_ns_ = now_ns;
      }
      const std::int64_t give_up = scan_first_wait_ns_ + settings_.pose_wait_ns;
      if (now_ns < give_up) {
        // Earlier scans already in the batch do not wait for this one's poses.
        if (batch_size_ > 0 || completed_count_ > 0) {
          const std::int64_t due = batch_first_ns_ + settings_.batch_deadline_ns;
          if (now_ns >= due) {
            integrateBatch(now_ns);
          } else {
            return std::min(give_up, due);
          }
        }
        return give_up;  // new poses wake the thread earlier
      }
      stats_.scans_no_pose.add();
      mailbox_.release(scan_);
      scan_ = nullptr;
      continue;
    }
    if (batch_size_ > 0 && batch_sensor_ != scan_->sensor) {
      integrateBatch(now_ns);  // a batch has one sensor's range limits
    }
    if (batch_size_ == 0) {
      batch_sensor_ = scan_->sensor;
      batch_first_ns_ = scan_->arrival_ns;
    }
    while (!convertScan()) {
      integrateBatch(now_ns);
      batch_sensor_ = scan_->sensor;
      batch_first_ns_ = scan_->arrival_ns;
    }
    completed_[completed_count_++] = scan_->arrival_ns;
    scan_stamp_pending_ = std::max(scan_stamp_pending_, scan_->header.stamp_ns);
    mailbox_.release(scan_);
    scan_ = nullptr;
    if (per_scan_ || completed_count_ == completed_.size() || batch_size_ == rays_.size()) {
      integrateBatch(now_ns);
    }
  }
  if (batch_size_ > 0 || completed_count_ > 0) {
    const std::int64_t due = batch_first_ns_ + settings_.batch_deadline_ns;
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
