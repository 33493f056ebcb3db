// SPDX-License-Identifier: BSD-3-Clause
// ScanReader and the conversion of recorded rays into driver-like scans and pose knots.
#include "src/replay/recorded_scans.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "src/core/eigen_conversions.hpp"
#include "src/io/trajectory.hpp"

namespace raymap::replay {
namespace {

constexpr std::size_t kChunkRays = 65536;
constexpr double kSameOrigin = 1e-3;  // metres: closer origins count as one sensor position

std::int64_t stampOf(double t_s, std::int64_t stamp_of_zero_ns, double t_zero_s) {
  return stamp_of_zero_ns + std::llround((t_s - t_zero_s) * 1e9);
}

/// The knots' position at `stamp_ns`: between the bracketing knots as a subscriber deskewing with
/// the odometry interpolates it (io::interpolate, the one definition), held outside.
Vec3d positionAt(const std::vector<PoseKnot>& knots, std::int64_t stamp_ns) {
  if (stamp_ns <= knots.front().stamp_ns) {
    return knots.front().position;
  }
  if (stamp_ns >= knots.back().stamp_ns) {
    return knots.back().position;
  }
  const auto after =
      std::upper_bound(knots.begin(), knots.end(), stamp_ns,
                       [](std::int64_t s, const PoseKnot& k) { return s < k.stamp_ns; });
  const PoseKnot& b = *after;
  const PoseKnot& a = *(after - 1);
  const double f =
      static_cast<double>(stamp_ns - a.stamp_ns) / static_cast<double>(b.stamp_ns - a.stamp_ns);
  const io::Pose at =
      io::interpolate(io::Pose{toEigen(a.position), Eigen::Quaterniond::Identity()},
                      io::Pose{toEigen(b.position), Eigen::Quaterniond::Identity()}, f);
  return toVec3(at.position);
}

}  // namespace

ScanReader::ScanReader(std::unique_ptr<io::RaySource> source)
    : source_(std::move(source)), buffer_(kChunkRays) {}

Result<bool> ScanReader::refill() {
  auto n = source_->read(buffer_);
  if (!n) {
    return Unexpected(std::move(n).error());
  }
  position_ = 0;
  size_ = n.value();
  end_ = size_ == 0;
  return !end_;
}

Result<bool> ScanReader::next(RecordedScan& scan) {
  scan.rays.clear();
  for (;;) {
    if (position_ == size_) {
      if (end_) {
        break;
      }
      auto more = refill();
      if (!more) {
        return Unexpected(std::move(more).error());
      }
      if (!more.value()) {
        break;
      }
    }
    const Ray& ray = buffer_[position_];
    if (!scan.rays.empty() && ray.scan != scan.index) {
      break;  // the next scan starts here; it stays in the buffer
    }
    if (scan.rays.empty()) {
      scan.index = ray.scan;
      scan.t_first_s = ray.time_s;
      scan.t_last_s = ray.time_s;
    }
    scan.t_first_s = std::min(scan.t_first_s, ray.time_s);
    scan.t_last_s = std::max(scan.t_last_s, ray.time_s);
    scan.rays.push_back(ray);
    ++position_;
  }
  return !scan.rays.empty();
}

void toDriverScan(const RecordedScan& scan, std::int64_t stamp_of_zero_ns, double t_zero_s,
                  double knot_period_s, DriverScan& out) {
  out.knots.clear();
  out.points.clear();
  out.origin_conflicts = 0;
  out.stamp_ns = stampOf(scan.t_first_s, stamp_of_zero_ns, t_zero_s);
  if (scan.rays.empty()) {
    return;
  }
  // Knots in time order: the first ray, then a ray at least a knot period after the previous
  // knot, then the last ray.
  std::vector<std::uint32_t> order(scan.rays.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&scan](std::uint32_t a, std::uint32_t b) {
    return scan.rays[a].time_s < scan.rays[b].time_s;
  });
  const auto period_ns = static_cast<std::int64_t>(knot_period_s * 1e9);
  for (std::size_t k = 0; k < order.size(); ++k) {
    const Ray& ray = scan.rays[order[k]];
    const std::int64_t stamp = stampOf(ray.time_s, stamp_of_zero_ns, t_zero_s);
    if (out.knots.empty()) {
      out.knots.push_back({stamp, ray.origin});
      continue;
    }
    PoseKnot& last = out.knots.back();
    if (stamp == last.stamp_ns) {
      if ((ray.origin - last.position).norm() > kSameOrigin) {
        ++out.origin_conflicts;  // one instant, two places: the knot keeps the first
      }
      continue;
    }
    if (stamp - last.stamp_ns >= period_ns || k + 1 == order.size()) {
      out.knots.push_back({stamp, ray.origin});
    }
  }
  if (out.knots.back().stamp_ns != stampOf(scan.t_last_s, stamp_of_zero_ns, t_zero_s)) {
    const Ray& last = scan.rays[order.back()];
    out.knots.push_back({stampOf(last.time_s, stamp_of_zero_ns, t_zero_s), last.origin});
  }

  out.points.reserve(scan.rays.size());
  for (const Ray& ray : scan.rays) {
    const std::int64_t stamp = stampOf(ray.time_s, stamp_of_zero_ns, t_zero_s);
    const Vec3d p = ray.sample - positionAt(out.knots, stamp);
    msgs::ScanPoint point{};
    point.x = static_cast<float>(p.x);
    point.y = static_cast<float>(p.y);
    point.z = static_cast<float>(p.z);
    point.time_s = static_cast<float>(static_cast<double>(stamp - out.stamp_ns) * 1e-9);
    point.intensity = ray.intensity;
    point.flags = (ray.flags & kRayNoReturn) != 0 ? msgs::kPointNoReturn : 0u;
    out.points.push_back(point);
  }
}

}  // namespace raymap::replay
