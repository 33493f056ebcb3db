// SPDX-License-Identifier: BSD-3-Clause
#include "src/map/decay_summary.hpp"

#include "kernels/common/voxel_mean.h"

namespace raymap {

DecaySummary summariseDecay(const VoxelMap& map) {
  DecaySummary summary;
  if (map.traversalLayer() < 0 || map.meanLayer() < 0) {
    return summary;
  }
  const RegionStore& store = map.store();
  (void)map.forEachRegionInCoordOrder([&](Vec3i, std::uint32_t slot) {
    const float* traversal = store.layerData<float>(slot, map.traversalLayer());
    const auto* means = store.layerData<rm_voxel_mean>(slot, map.meanLayer());
    for (std::uint32_t i = 0; i < store.voxelsPerRegion(); ++i) {
      if (traversal[i] > 0.0f) {
        ++summary.crossed;
        summary.with_samples += means[i].count > 0u ? 1u : 0u;
        summary.metres += static_cast<double>(traversal[i]);
        summary.samples += means[i].count;
      }
    }
  });
  return summary;
}

}  // namespace raymap
