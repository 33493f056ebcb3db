// SPDX-License-Identifier: BSD-3-Clause
// LidarPlayback: the real-time schedule of a simulated driver.
#include "src/driver/lidar_playback.hpp"

#include <algorithm>
#include <cmath>

#include "src/core/eigen_conversions.hpp"

namespace raymap::driver {

LidarPlayback::LidarPlayback(const SimulatedLidar& lidar, DriverPublisher& publisher,
                             PlaybackOptions options)
    : lidar_(lidar), publisher_(publisher), options_(options) {
  const std::size_t n = lidar_.moving() ? 1 : static_cast<std::size_t>(options_.distinct_scans);
  scans_cache_.resize(n);
  rings_cache_.resize(n);
  if (!lidar_.moving()) {
    for (std::size_t k = 0; k < n; ++k) {
      lidar_.scan(k, scans_cache_[k], rings_cache_[k]);
      corruptTimes(scans_cache_[k]);
    }
  }
  scan_period_ = std::llround(1e9 / options_.scan_rate_hz);
  odometry_period_ = std::llround(1e9 / options_.odometry_rate_hz);
}

void LidarPlayback::corruptTimes(std::vector<msgs::ScanPoint>& scan) const {
  const std::size_t n = std::min<std::size_t>(options_.bad_time_points, scan.size());
  for (std::size_t i = 0; i < n; ++i) {
    scan[i].time_s = 4.294967295f;  // t = 0xFFFFFFFF ns once written back as nanoseconds
  }
}

void LidarPlayback::start(std::int64_t monotonic_ns, std::int64_t wall_ns) {
  t0_ = monotonic_ns;
  stamp0_ = wall_ns;
  next_scan_ = t0_ + scan_period_;
  next_odometry_ = t0_;
}

std::int64_t LidarPlayback::publishDue(std::int64_t now) {
  // Odometry first: a scan's poses are out before the scan, as with a live localisation stack.
  while (next_odometry_ <= now) {
    const double t = static_cast<double>(next_odometry_ - t0_) * 1e-9;
    io::Pose base = lidar_.poseAt(t);
    base.position -= base.orientation * toEigen(options_.sensor_in_base);
    if (options_.pose_as_tf) {
      publisher_.publishTf(stamp0_ + (next_odometry_ - t0_), base, options_.world_frame,
                           options_.base_frame);
    } else {
      publisher_.publishOdometry(stamp0_ + (next_odometry_ - t0_), base, options_.world_frame,
                                 options_.base_frame);
    }
    next_odometry_ += odometry_period_;
  }
  if (next_scan_ <= now) {
    // Scan k sweeps [k T, (k + 1) T) and goes out when complete; its stamp is its start.
    const std::uint64_t k = scans_;
    const std::size_t slot = lidar_.moving() ? 0 : k % scans_cache_.size();
    if (lidar_.moving()) {
      lidar_.scan(k, scans_cache_[0], rings_cache_[0]);
      corruptTimes(scans_cache_[0]);
    }
    const std::int64_t start = static_cast<std::int64_t>(k) * scan_period_;
    publisher_.publishCloud(scans_cache_[slot], rings_cache_[slot], stamp0_ + start,
                            options_.frame);
    ++scans_;
    points_ += scans_cache_[slot].size();
    next_scan_ += scan_period_;
    if (next_scan_ <= now) {
      next_scan_ = now + scan_period_;  // fell behind (slow scene): do not burst
    }
  }
  return std::min(next_scan_, next_odometry_);
}

}  // namespace raymap::driver
