// SPDX-License-Identifier: BSD-3-Clause
// Ray casting through a scene and its vertical columns: each solid is the set of points along a
// ray between an entry and an exit distance, found analytically.
#include "src/sim/scene.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace raymap::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// The part of a ray inside a solid: distances [enter, exit] along it (may start behind the
/// origin); empty when enter > exit.
struct Span {
  double enter = -kInf;
  double exit = kInf;

  bool empty() const noexcept { return enter > exit; }
};

constexpr Span kEmpty{kInf, -kInf};

/// A half-space n . p <= c.
struct HalfSpace {
  Vec3d n;
  double c = 0.0;
};

/// Narrows `span` to the half-space (Cyrus-Beck clipping).
Span clip(Span span, const HalfSpace& h, Vec3d o, Vec3d d) noexcept {
  const double denom = h.n.dot(d);
  const double num = h.c - h.n.dot(o);
  if (denom == 0.0) {
    return num < 0.0 ? kEmpty : span;  // parallel: all outside or all inside
  }
  const double t = num / denom;
  if (denom < 0.0) {
    span.enter = std::max(span.enter, t);
  } else {
    span.exit = std::min(span.exit, t);
  }
  return span;
}

/// Slab test of an axis-aligned box.
Span boxSpan(const Box& box, Vec3d o, Vec3d d) noexcept {
  Span span;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) {
      if (o[a] < box.min[a] || o[a] > box.max[a]) {
        return kEmpty;
      }
      continue;
    }
    double t0 = (box.min[a] - o[a]) / d[a];
    double t1 = (box.max[a] - o[a]) / d[a];
    if (t0 > t1) {
      std::swap(t0, t1);
    }
    span.enter = std::max(span.enter, t0);
    span.exit = std::min(span.exit, t1);
    if (span.empty()) {
      return kEmpty;
    }
  }
  return span;
}

/// The sloped top of a ramp as a half-space with n.z = 1, so the top's height at (x, y) is
/// c - n.x x - n.y y.
HalfSpace rampTop(const Ramp& ramp) noexcept {
  const Vec3d& lo = ramp.min;
  const Vec3d& hi = ramp.max;
  const double rise = hi.z - lo.z;
  switch (ramp.axis) {
    case RampAxis::kPlusX: {
      const double s = rise / (hi.x - lo.x);
      return {{-s, 0.0, 1.0}, lo.z - s * lo.x};
    }
    case RampAxis::kMinusX: {
      const double s = rise / (hi.x - lo.x);
      return {{s, 0.0, 1.0}, lo.z + s * hi.x};
    }
    case RampAxis::kPlusY: {
      const double s = rise / (hi.y - lo.y);
      return {{0.0, -s, 1.0}, lo.z - s * lo.y};
    }
    case RampAxis::kMinusY: {
      const double s = rise / (hi.y - lo.y);
      return {{0.0, s, 1.0}, lo.z + s * hi.y};
    }
  }
  return {{0.0, 0.0, 1.0}, hi.z};
}

double rampTopAt(const Ramp& ramp, double x, double y) noexcept {
  const HalfSpace top = rampTop(ramp);
  return std::clamp(top.c - top.n.x * x - top.n.y * y, ramp.min.z, ramp.max.z);
}

Span rampSpan(const Ramp& ramp, Vec3d o, Vec3d d) noexcept {
  const Span span = boxSpan(Box{ramp.min, ramp.max}, o, d);
  return span.empty() ? span : clip(span, rampTop(ramp), o, d);
}

Span poleSpan(const Cylinder& pole, Vec3d o, Vec3d d) noexcept {
  const double dx = o.x - pole.x;
  const double dy = o.y - pole.y;
  const double r2 = pole.radius * pole.radius;
  const double a = d.x * d.x + d.y * d.y;
  Span span;
  if (a == 0.0) {
    if (dx * dx + dy * dy > r2) {
      return kEmpty;
    }
  } else {
    const double b = dx * d.x + dy * d.y;
    const double disc = b * b - a * (dx * dx + dy * dy - r2);
    if (disc < 0.0) {
      return kEmpty;
    }
    const double root = std::sqrt(disc);
    span = {(-b - root) / a, (-b + root) / a};
  }
  span = clip(span, {{0.0, 0.0, -1.0}, -pole.z_min}, o, d);
  return clip(span, {{0.0, 0.0, 1.0}, pole.z_max}, o, d);
}

/// Distance to the first solid point of a span: 0 when the origin is inside.
double entry(Span span) noexcept {
  if (span.empty() || span.exit < 0.0) {
    return kInf;
  }
  return std::max(span.enter, 0.0);
}

/// The ditch whose open rectangle contains (x, y), or null.
const Ditch* ditchAt(const Scene& scene, double x, double y) noexcept {
  for (const Ditch& ditch : scene.ditches) {
    if (x > ditch.x_min && x < ditch.x_max && y > ditch.y_min && y < ditch.y_max) {
      return &ditch;
    }
  }
  return nullptr;
}

/// A ray in the hollow of `ditch` (from its origin, or after entering through the opening): the
/// distance to the bottom or a wall, or +inf when it leaves through the opening (and then, rising,
/// never meets the ground again).
double hitInsideDitch(const Ditch& ditch, double ground, Vec3d o, Vec3d d) noexcept {
  double t_wall = kInf;
  const double lo[2] = {ditch.x_min, ditch.y_min};
  const double hi[2] = {ditch.x_max, ditch.y_max};
  for (int a = 0; a < 2; ++a) {
    if (d[a] > 0.0) {
      t_wall = std::min(t_wall, (hi[a] - o[a]) / d[a]);
    } else if (d[a] < 0.0) {
      t_wall = std::min(t_wall, (lo[a] - o[a]) / d[a]);
    }
  }
  if (d.z > 0.0) {
    return (ground - o.z) / d.z < t_wall ? kInf : t_wall;
  }
  if (d.z < 0.0) {
    return std::min(t_wall, (ground - ditch.depth - o.z) / d.z);
  }
  return t_wall;
}

/// The ground half-space with its ditches.
double hitGround(const Scene& scene, Vec3d o, Vec3d d) noexcept {
  if (!scene.has_ground) {
    return kInf;
  }
  const double ground = scene.ground_height;
  if (const Ditch* ditch = ditchAt(scene, o.x, o.y)) {
    if (o.z <= ground - ditch->depth) {
      return 0.0;
    }
    if (o.z < ground) {
      return hitInsideDitch(*ditch, ground, o, d);
    }
  } else if (o.z <= ground) {
    return 0.0;
  }
  if (d.z >= 0.0) {
    return kInf;
  }
  const double t = (ground - o.z) / d.z;
  const Vec3d p = o + d * t;
  const Ditch* ditch = ditchAt(scene, p.x, p.y);
  return ditch == nullptr ? t : hitInsideDitch(*ditch, ground, o, d);
}

}  // namespace

double castRay(const Scene& scene, Vec3d origin, Vec3d dir) noexcept {
  double range = hitGround(scene, origin, dir);
  for (const Box& box : scene.boxes) {
    range = std::min(range, entry(boxSpan(box, origin, dir)));
  }
  for (const Ramp& ramp : scene.ramps) {
    range = std::min(range, entry(rampSpan(ramp, origin, dir)));
  }
  for (const Cylinder& pole : scene.poles) {
    range = std::min(range, entry(poleSpan(pole, origin, dir)));
  }
  return range;
}

std::vector<std::pair<double, double>> solidIntervals(const Scene& scene, double x, double y) {
  std::vector<std::pair<double, double>> intervals;
  if (scene.has_ground) {
    const Ditch* ditch = ditchAt(scene, x, y);
    intervals.emplace_back(-kInf, scene.ground_height - (ditch != nullptr ? ditch->depth : 0.0));
  }
  for (const Box& box : scene.boxes) {
    if (x >= box.min.x && x <= box.max.x && y >= box.min.y && y <= box.max.y) {
      intervals.emplace_back(box.min.z, box.max.z);
    }
  }
  for (const Ramp& ramp : scene.ramps) {
    if (x >= ramp.min.x && x <= ramp.max.x && y >= ramp.min.y && y <= ramp.max.y) {
      const double top = rampTopAt(ramp, x, y);
      if (top > ramp.min.z) {  // the low edge has no thickness
        intervals.emplace_back(ramp.min.z, top);
      }
    }
  }
  for (const Cylinder& pole : scene.poles) {
    const double dx = x - pole.x;
    const double dy = y - pole.y;
    if (dx * dx + dy * dy <= pole.radius * pole.radius) {
      intervals.emplace_back(pole.z_min, pole.z_max);
    }
  }
  std::sort(intervals.begin(), intervals.end());
  std::vector<std::pair<double, double>> merged;
  for (const auto& interval : intervals) {
    if (!merged.empty() && interval.first <= merged.back().second) {
      merged.back().second = std::max(merged.back().second, interval.second);
    } else {
      merged.push_back(interval);
    }
  }
  return merged;
}

std::optional<TrueSurface> trueSurface(const Scene& scene, double x, double y, double reference_z,
                                       double min_clearance) {
  const std::vector<std::pair<double, double>> intervals = solidIntervals(scene, x, y);
  std::optional<TrueSurface> best;
  for (std::size_t i = 0; i < intervals.size(); ++i) {
    const double top = intervals[i].second;
    const double gap = i + 1 < intervals.size() ? intervals[i + 1].first - top : kInf;
    if (gap < min_clearance) {
      continue;
    }
    // Bottom-up with a strict comparison: of two equally near tops the lower stays.
    if (!best || std::abs(top - reference_z) < std::abs(best->height - reference_z)) {
      best = TrueSurface{top, gap};
    }
  }
  return best;
}

std::optional<Box> objectBounds(const Scene& scene) {
  std::optional<Box> bounds;
  const auto add = [&bounds](Vec3d lo, Vec3d hi) {
    if (!bounds) {
      bounds = Box{lo, hi};
      return;
    }
    for (int a = 0; a < 3; ++a) {
      bounds->min[a] = std::min(bounds->min[a], lo[a]);
      bounds->max[a] = std::max(bounds->max[a], hi[a]);
    }
  };
  for (const Box& box : scene.boxes) {
    add(box.min, box.max);
  }
  for (const Ramp& ramp : scene.ramps) {
    add(ramp.min, ramp.max);
  }
  for (const Cylinder& pole : scene.poles) {
    add({pole.x - pole.radius, pole.y - pole.radius, pole.z_min},
        {pole.x + pole.radius, pole.y + pole.radius, pole.z_max});
  }
  for (const Ditch& ditch : scene.ditches) {
    add({ditch.x_min, ditch.y_min, scene.ground_height - ditch.depth},
        {ditch.x_max, ditch.y_max, scene.ground_height});
  }
  return bounds;
}

}  // namespace raymap::sim
