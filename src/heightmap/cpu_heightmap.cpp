// SPDX-License-Identifier: BSD-3-Clause
// The CPU height-map generator: the kernel header's work-items run in a loop, in the order a
// device runs them (flood fill ring by ring).
#include "kernels/common/heightmap.h"
#include "src/heightmap/heightmap_generator.hpp"

namespace raymap::heightmap {

void prepareOutput(const HeightmapPlan& plan, HeightMap& out) {
  const HeightMap& g = plan.grid;
  out.resolution = g.resolution;
  out.cells_x = g.cells_x;
  out.cells_y = g.cells_y;
  out.centre_x = g.centre_x;
  out.centre_y = g.centre_y;
  out.reference_z = g.reference_z;
  out.mode = g.mode;
  out.resizeLayers();
}

namespace {

class CpuHeightmapGenerator final : public HeightmapGenerator {
 public:
  const char* name() const noexcept override { return "cpu"; }

  Expected<void, Error> generate(const VoxelMap& map, const HeightmapPlan& plan,
                                 HeightMap& out) override {
    prepareOutput(plan, out);
    const RegionStore& store = map.store();
    // Layer-major pool: slot 0's layer start is the whole layer, indexed by slot.
    const auto* occupancy =
        store.capacity() > 0 ? store.layerData<const float>(0, map.occupancyLayer()) : nullptr;
    const rm_voxel_mean* mean = nullptr;
    if (map.meanLayer() >= 0 && store.capacity() > 0) {
      mean = store.layerData<const rm_voxel_mean>(0, map.meanLayer());
    }
    const rm_heightmap_params& p = plan.params;
    rm_hm_layers layers{out.elevation.data(), out.clearance.data(), out.kind.data(),
                        out.observed_count.data(), out.reference.data()};
    const std::uint32_t* table = plan.region_table.data();
    if ((p.flags & RM_HM_FLAG_FILL) != 0) {
      const rm_i32 rings = rm_hm_ring_count(p);
      for (rm_i32 k = 0; k < rings; ++k) {
        const rm_u32 items = rm_hm_ring_size(k);
        for (rm_u32 g = 0; g < items; ++g) {
          rm_hm_fill_item(p, table, occupancy, mean, layers, k, g);
        }
      }
    } else {
      const auto items = static_cast<rm_u32>(out.cellCount());
      for (rm_u32 g = 0; g < items; ++g) {
        rm_hm_planar_item(p, table, occupancy, mean, layers, g);
      }
    }
    return {};
  }
};

}  // namespace

std::unique_ptr<HeightmapGenerator> makeCpuHeightmapGenerator() {
  return std::make_unique<CpuHeightmapGenerator>();
}

}  // namespace raymap::heightmap
