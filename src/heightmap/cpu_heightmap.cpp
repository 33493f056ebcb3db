// SPDX-License-Identifier: BSD-3-Clause
// The CPU height-map generator: the kernel header's work-items run in a loop, in the order a
// device runs them (flood fill ring by ring).
#include <algorithm>
#include <vector>

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
  out.has_normals = g.has_normals;
  out.resizeLayers();
}

namespace {

class CpuHeightmapGenerator final : public HeightmapGenerator {
 public:
  const char* name() const noexcept override { return "cpu"; }

  void reserveHostScratch(const VoxelMap& map, std::size_t regions) override {
    const auto n = static_cast<std::size_t>(map.geometry().region_voxels);
    const auto words = static_cast<std::size_t>(rm_hm_mask_words(static_cast<rm_i32>(n)));
    masks_.reserve(std::max<std::size_t>(regions, 1) * n * n * words);
    occupied_.reserve(n * n);
    observed_.reserve(n * n);
  }

  Expected<void, Error> generate(const VoxelMap& map, const HeightmapPlan& plan,
                                 HeightMap& out) override {
    prepareOutput(plan, out);
    const RegionStore& store = map.store();
    const rm_heightmap_params& p = plan.params;
    buildMasks(map, plan);
    // Layer-major pool: slot 0's layer start is the whole layer, indexed by slot.
    const rm_voxel_mean* mean = nullptr;
    if (map.meanLayer() >= 0 && store.capacity() > 0) {
      mean = store.layerData<const rm_voxel_mean>(0, map.meanLayer());
    }
    const rm_ndt_voxel* ndt = nullptr;
    if (map.ndtLayer() >= 0 && store.capacity() > 0) {
      ndt = store.layerData<const rm_ndt_voxel>(0, map.ndtLayer());
    }
    const rm_hm_sources sources{plan.region_table.data(), plan.region_slots.data(), masks_.data(),
                                mean, ndt};
    const rm_hm_layers layers{out.elevation.data(),      out.clearance.data(), out.kind.data(),
                              out.observed_count.data(), out.reference.data(), out.normal_x.data(),
                              out.normal_y.data(),       out.normal_z.data()};
    if ((p.flags & RM_HM_FLAG_FILL) != 0) {
      const rm_i32 rings = rm_hm_ring_count(p);
      for (rm_i32 k = 0; k < rings; ++k) {
        const rm_u32 items = rm_hm_ring_size(k);
        for (rm_u32 g = 0; g < items; ++g) {
          rm_hm_fill_item(p, sources, layers, k, g);
        }
      }
    } else {
      const auto items = static_cast<rm_u32>(out.cellCount());
      for (rm_u32 g = 0; g < items; ++g) {
        rm_hm_planar_item(p, sources, layers, g);
      }
    }
    return {};
  }

 private:
  /// The column masks of every region under the box (kernels/common/heightmap.h), from the voxels
  /// the search can read (the grid's columns, one voxel below the box to its top; other bits stay
  /// clear and are never read). Row by row, so the occupancy layer is read in memory order and
  /// the loop vectorises (a device reads it column by column, which its neighbouring work-items
  /// make contiguous); rm_hm_observed_bit() / rm_hm_occupied_bit() are the shared rule.
  void buildMasks(const VoxelMap& map, const HeightmapPlan& plan) {
    const rm_heightmap_params& p = plan.params;
    const float threshold = p.occupied_threshold;
    const rm_i32 n = p.region_voxels;
    const auto plane = static_cast<std::size_t>(n) * static_cast<std::size_t>(n);
    const auto words = static_cast<std::size_t>(rm_hm_mask_words(n));
    masks_.resize(std::max<std::size_t>(plan.region_slots.size(), 1) * plane * words);
    occupied_.resize(plane);
    observed_.resize(plane);
    // The voxels the search reads: the grid's columns, from one voxel below the box to its top.
    const Vec3i box_min{p.voxel_x0 - p.cells_x + 1, p.voxel_y0 - p.cells_y + 1, p.box_z_min - 1};
    const Vec3i box_max{p.voxel_x0, p.voxel_y0, p.box_z_max};
    std::size_t t = 0;
    for (rm_i32 tz = 0; tz < p.regions_z; ++tz) {
      for (rm_i32 ty = 0; ty < p.regions_y; ++ty) {
        for (rm_i32 tx = 0; tx < p.regions_x; ++tx, ++t) {
          const std::uint32_t r = plan.region_table[t];
          if (r == RM_HM_NO_REGION) {
            continue;
          }
          // This region's part of the box, in region-local voxels.
          const Vec3i origin{(p.region_x0 + tx) * n, (p.region_y0 + ty) * n,
                             (p.region_z0 + tz) * n};
          Vec3i lo;
          Vec3i hi;
          for (int a = 0; a < 3; ++a) {
            lo[a] = std::max(box_min[a] - origin[a], 0);
            hi[a] = std::min(box_max[a] - origin[a], n - 1);
          }
          const float* voxels =
              map.store().layerData<const float>(plan.region_slots[r], map.occupancyLayer());
          rm_hm_mask* out = masks_.data() + std::size_t{r} * plane * words;
          for (std::size_t w = 0; w < words; ++w) {
            std::fill(occupied_.begin(), occupied_.end(), 0u);
            std::fill(observed_.begin(), observed_.end(), 0u);
            const rm_i32 z0 = std::max(lo.z, static_cast<rm_i32>(w * 32));
            const rm_i32 z1 = std::min(hi.z, static_cast<rm_i32>(w * 32 + 31));
            for (rm_i32 z = z0; z <= z1; ++z) {
              const rm_u32 b = static_cast<rm_u32>(z) % 32u;
              for (rm_i32 y = lo.y; y <= hi.y; ++y) {
                const auto row = static_cast<std::size_t>(y * n);
                const float* values = voxels + static_cast<std::size_t>(z) * plane + row;
                std::uint32_t* occupied = occupied_.data() + row;
                std::uint32_t* observed = observed_.data() + row;
                for (rm_i32 x = lo.x; x <= hi.x; ++x) {
                  observed[x] |= rm_hm_observed_bit(values[x]) << b;
                  occupied[x] |= rm_hm_occupied_bit(values[x], threshold) << b;
                }
              }
            }
            for (std::size_t c = 0; c < plane; ++c) {
              out[c * words + w] = rm_hm_mask{occupied_[c], observed_[c]};
            }
          }
        }
      }
    }
  }

  std::vector<std::uint32_t> occupied_;  // one mask word of every column of a region (scratch)
  std::vector<std::uint32_t> observed_;
  std::vector<rm_hm_mask> masks_;
};

}  // namespace

std::unique_ptr<HeightmapGenerator> makeCpuHeightmapGenerator() {
  return std::make_unique<CpuHeightmapGenerator>();
}

}  // namespace raymap::heightmap
