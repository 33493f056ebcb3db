// SPDX-License-Identifier: BSD-3-Clause
// OctoMap reference mapper.
#include "tools/bench/octomap_reference.hpp"

#include <chrono>
#include <cmath>

#include <octomap/OcTree.h>

namespace raymap::bench {
namespace {

// OctoMap keys are floor(coordinate / resolution) + 2^15 (octomap::OcTree tree_max_val).
constexpr int kKeyOffset = 32768;

octomap::point3d toPoint(Vec3d p) {
  return octomap::point3d(static_cast<float>(p.x), static_cast<float>(p.y),
                          static_cast<float>(p.z));
}

}  // namespace

struct OctomapReference::Impl {
  explicit Impl(const OctomapOptions& o) : options(o), tree(o.resolution) {
    tree.setProbHit(probability(o.occupancy.hit));
    tree.setProbMiss(probability(o.occupancy.miss));
    tree.setClampingThresMin(probability(o.occupancy.clamp_min));
    tree.setClampingThresMax(probability(o.occupancy.clamp_max));
    tree.setOccupancyThres(probability(o.occupancy.threshold));
  }

  bool accept(const Ray& ray) {
    ++counts.rays_in;
    if (!ray.origin.isFinite() || !ray.sample.isFinite() ||
        (ray.sample - ray.origin).norm() < options.min_range_m) {
      ++counts.rays_rejected;
      return false;
    }
    return true;
  }

  OctomapOptions options;
  octomap::OcTree tree;
  OctomapCounts counts;
};

OctomapReference::OctomapReference(const OctomapOptions& options)
    : impl_(std::make_unique<Impl>(options)) {}

OctomapReference::~OctomapReference() = default;

void OctomapReference::integrate(std::span<const Ray> rays) {
  Impl& m = *impl_;
  const double max_range = m.options.max_range_m > 0.0 ? m.options.max_range_m : -1.0;
  using Clock = std::chrono::steady_clock;
  if (m.options.semantics == Semantics::kPerRay) {
    for (const Ray& ray : rays) {
      if (!m.accept(ray)) {
        continue;
      }
      const auto t = Clock::now();
      if ((ray.flags & kRayNoReturn) != 0u) {
        // Free space only, clipped like insertRay clips.
        octomap::point3d end = toPoint(ray.sample);
        const octomap::point3d origin = toPoint(ray.origin);
        if (max_range > 0.0 && (end - origin).norm() > max_range) {
          end = origin + (end - origin).normalized() * static_cast<float>(max_range);
        }
        octomap::KeyRay keys;
        if (m.tree.computeRayKeys(origin, end, keys)) {
          for (const octomap::OcTreeKey& k : keys) {
            m.tree.updateNode(k, false);
          }
        }
      } else {
        m.tree.insertRay(toPoint(ray.origin), toPoint(ray.sample), max_range);
      }
      m.counts.integrate_seconds += std::chrono::duration<double>(Clock::now() - t).count();
      ++m.counts.rays_integrated;
    }
    return;
  }
  // Per-scan: one insertPointCloud per run of rays sharing an origin. Ray clouds store origins
  // as sample + float offset, so "sharing" allows a millimetre of rounding.
  constexpr double kSameOrigin = 1e-3;  // metres
  std::size_t i = 0;
  while (i < rays.size()) {
    octomap::Pointcloud cloud;
    const Vec3d origin = rays[i].origin;
    std::size_t j = i;
    for (; j < rays.size() && (rays[j].origin - origin).norm() <= kSameOrigin; ++j) {
      if (!m.accept(rays[j])) {
        continue;
      }
      if ((rays[j].flags & kRayNoReturn) != 0u) {
        ++m.counts.rays_skipped_no_return;
        continue;
      }
      cloud.push_back(toPoint(rays[j].sample));
      ++m.counts.rays_integrated;
    }
    const auto t = Clock::now();
    m.tree.insertPointCloud(cloud, toPoint(origin), max_range);
    m.counts.integrate_seconds += std::chrono::duration<double>(Clock::now() - t).count();
    i = j;
  }
}

OctomapCounts OctomapReference::counts() const {
  OctomapCounts c = impl_->counts;
  const octomap::OcTree& tree = impl_->tree;
  const unsigned max_depth = tree.getTreeDepth();
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const unsigned levels = max_depth - it.getDepth();
    const std::uint64_t voxels = std::uint64_t{1} << (3u * levels);
    if (tree.isNodeOccupied(*it)) {
      c.voxels_occupied += voxels;
    } else {
      c.voxels_free += voxels;
    }
  }
  return c;
}

Agreement OctomapReference::compare(const VoxelMap& map) const {
  Agreement a;
  const octomap::OcTree& tree = impl_->tree;
  const unsigned max_depth = tree.getTreeDepth();
  // Every voxel OctoMap observed.
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const int size = 1 << (max_depth - it.getDepth());
    const octomap::OcTreeKey key = it.getIndexKey();
    const VoxelState octo = tree.isNodeOccupied(*it) ? VoxelState::kOccupied : VoxelState::kFree;
    for (int dz = 0; dz < size; ++dz) {
      for (int dy = 0; dy < size; ++dy) {
        for (int dx = 0; dx < size; ++dx) {
          const Vec3i v{key[0] + dx - kKeyOffset, key[1] + dy - kKeyOffset,
                        key[2] + dz - kKeyOffset};
          const VoxelState ours = map.state(v);
          ++a.compared;
          a.same += ours == octo ? 1u : 0u;
          a.only_octomap += ours == VoxelState::kUnobserved ? 1u : 0u;
        }
      }
    }
  }
  // Voxels only raymap observed.
  const int n = map.geometry().region_voxels;
  map.store().forEachRegion([&](std::uint32_t slot, Vec3i region) {
    const float* occ = map.store().layerData<float>(slot, map.occupancyLayer());
    for (int i = 0; i < n * n * n; ++i) {
      if (std::isinf(occ[i])) {
        continue;
      }
      const Vec3i v = map.voxelAt(region, static_cast<std::uint32_t>(i));
      const octomap::OcTreeKey key(static_cast<octomap::key_type>(v.x + kKeyOffset),
                                   static_cast<octomap::key_type>(v.y + kKeyOffset),
                                   static_cast<octomap::key_type>(v.z + kKeyOffset));
      if (tree.search(key) == nullptr) {
        ++a.compared;
        ++a.only_raymap;
      }
    }
  });
  return a;
}

}  // namespace raymap::bench
