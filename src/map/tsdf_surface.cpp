// SPDX-License-Identifier: BSD-3-Clause
// TSDF zero crossings.
#include "src/map/tsdf_surface.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

#include "raymap/assert.hpp"

namespace raymap {

std::vector<TsdfSurfacePoint> tsdfZeroCrossings(const VoxelMap& map, float min_weight) {
  RAYMAP_EXPECTS(map.tsdfLayer() >= 0);
  const RegionStore& store = map.store();
  RegionCursor cursor(map);  // a tiered map's regions stream through its pool
  const std::int32_t n = map.geometry().region_voxels;
  const auto tau =
      static_cast<float>(map.config().tsdf.truncationMetres(map.geometry().resolution));
  const auto usable = [&](const rm_tsdf_voxel& v) { return tsdfVoxelUsable(v, min_weight); };
  std::vector<TsdfSurfacePoint> points;
  while (cursor.next()) {
    const Vec3i region = cursor.region();
    const std::uint32_t slot = cursor.slot();
    const rm_tsdf_voxel* tsdf = store.layerData<rm_tsdf_voxel>(slot, map.tsdfLayer());
    std::uint32_t index = 0;
    for (std::int32_t z = 0; z < n; ++z) {
      for (std::int32_t y = 0; y < n; ++y) {
        for (std::int32_t x = 0; x < n; ++x, ++index) {
          const rm_tsdf_voxel a = tsdf[index];
          if (!usable(a) || std::fabs(a.distance) >= tau) {
            continue;  // no crossing from a saturated voxel is measured
          }
          const Vec3i voxel{region.x * n + x, region.y * n + y, region.z * n + z};
          const std::int32_t local[3] = {x, y, z};
          const std::uint32_t stride[3] = {1u, static_cast<std::uint32_t>(n),
                                           static_cast<std::uint32_t>(n * n)};
          for (int axis = 0; axis < 3; ++axis) {
            Vec3i next = voxel;
            next[axis] += 1;
            // Inside the region the neighbour is one stride on; across its face, a lookup.
            const rm_tsdf_voxel b =
                local[axis] + 1 < n ? tsdf[index + stride[axis]] : map.tsdf(next);
            if (!usable(b) || !tsdfMeasuredCrossing(a.distance, b.distance, tau)) {
              continue;
            }
            const double f = static_cast<double>(a.distance) /
                             (static_cast<double>(a.distance) - static_cast<double>(b.distance));
            const Vec3d ca = map.voxelCentre(voxel);
            const Vec3d cb = map.voxelCentre(next);
            TsdfSurfacePoint point;
            point.p_world = ca + (cb - ca) * f;
            point.weight = std::min(a.weight, b.weight);
            Vec3d normal{};
            normal[axis] = a.distance >= 0.0f ? -1.0 : 1.0;
            point.normal = normal;
            points.push_back(point);
          }
        }
      }
    }
  }
  return points;
}

TsdfSummary summariseTsdf(const VoxelMap& map) {
  TsdfSummary summary;
  if (map.tsdfLayer() < 0) {
    return summary;
  }
  const auto max_weight = static_cast<float>(map.config().tsdf.max_weight);
  (void)map.forEachRegionInCoordOrder([&](Vec3i, std::uint32_t slot) {
    const auto* tsdf = map.store().layerData<rm_tsdf_voxel>(slot, map.tsdfLayer());
    for (std::uint32_t i = 0; i < map.store().voxelsPerRegion(); ++i) {
      if (tsdf[i].weight > 0.0f) {
        ++summary.updated;
        summary.behind += tsdf[i].distance < 0.0f ? 1u : 0u;
        summary.saturated += tsdf[i].weight >= max_weight ? 1u : 0u;
      }
    }
  });
  return summary;
}

}  // namespace raymap
