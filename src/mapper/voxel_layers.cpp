// SPDX-License-Identifier: BSD-3-Clause
#include "src/mapper/voxel_layers.hpp"

#include <cmath>

#include "kernels/common/decay.h"
#include "kernels/common/ndt.h"
#include "src/core/eigen_conversions.hpp"

namespace raymap::mapper {

std::optional<NdtVoxelInfo> ndtVoxel(const VoxelMap& map, Vec3i voxel) noexcept {
  if (map.ndtLayer() < 0) {
    return std::nullopt;
  }
  const rm_ndt_voxel v = map.ndt(voxel);
  if (v.count == 0) {
    return std::nullopt;
  }
  // The layer keeps the mean from the voxel's minimum corner and the covariance's square-root
  // factor, both in voxel units (kernels/common/ndt.h).
  const double r = map.geometry().resolution;
  NdtVoxelInfo info;
  info.samples = v.count;
  info.mean = toEigen(map.pointInVoxel(voxel, rm_ndt_mean(&v)));
  float p[6];
  rm_ndt_covariance(v.s, p);  // packed lower triangle by rows: 00, 10, 11, 20, 21, 22
  const int row[6] = {0, 1, 1, 2, 2, 2};
  const int col[6] = {0, 0, 1, 0, 1, 2};
  for (int k = 0; k < 6; ++k) {
    const double value = static_cast<double>(p[k]) * r * r;
    info.covariance(row[k], col[k]) = value;
    info.covariance(col[k], row[k]) = value;
  }
  if (map.hitMissLayer() >= 0) {
    const rm_ndt_hit_miss counts = map.hitMiss(voxel);
    info.hits = counts.hit;
    info.misses = counts.miss;
  }
  if (map.intensityLayer() >= 0) {
    const rm_ndt_intensity intensity = map.intensity(voxel);
    info.intensity_mean = intensity.mean;
    info.intensity_variance = intensity.variance;
  }
  return info;
}

std::optional<TsdfVoxelInfo> tsdfVoxel(const VoxelMap& map, Vec3i voxel) noexcept {
  if (map.tsdfLayer() < 0) {
    return std::nullopt;
  }
  const rm_tsdf_voxel v = map.tsdf(voxel);
  if (!(v.weight > 0.0f)) {
    return std::nullopt;  // never updated
  }
  return TsdfVoxelInfo{v.distance, v.weight};
}

std::optional<DecayVoxelInfo> decayVoxel(const VoxelMap& map, Vec3i voxel) noexcept {
  if (map.traversalLayer() < 0) {
    return std::nullopt;
  }
  DecayVoxelInfo info;
  info.traversal_m = map.traversal(voxel);
  info.samples = map.meanLayer() >= 0 ? map.mean(voxel).count : 0u;
  info.rate_per_m = rm_decay_rate(info.samples, info.traversal_m);
  if (std::isnan(info.rate_per_m)) {
    return std::nullopt;  // no ray entered it
  }
  return info;
}

}  // namespace raymap::mapper
