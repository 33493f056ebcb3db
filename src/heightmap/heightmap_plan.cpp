// SPDX-License-Identifier: BSD-3-Clause
#include "src/heightmap/heightmap_plan.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace raymap::heightmap {
namespace {

std::string metres(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

/// The box of stored regions, metres: {min corner, max corner}; for rolling maps the window.
std::pair<Vec3d, Vec3d> mapBounds(const VoxelMap& map) {
  if (map.config().policy == StorePolicy::kRolling) {
    return map.windowBounds();
  }
  constexpr std::int32_t kBig = std::numeric_limits<std::int32_t>::max();
  Vec3i lo{kBig, kBig, kBig};
  Vec3i hi{-kBig, -kBig, -kBig};
  for (const Vec3i r : map.regionCoordsInOrder()) {  // every tier of a tiered map
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], r[a]);
      hi[a] = std::max(hi[a], r[a]);
    }
  }
  if (lo.x > hi.x) {
    return {Vec3d{}, Vec3d{}};
  }
  const double e = map.geometry().regionExtent();
  return {Vec3d{lo.x * e, lo.y * e, lo.z * e},
          Vec3d{(hi.x + 1) * e, (hi.y + 1) * e, (hi.z + 1) * e}};
}

}  // namespace

std::size_t maxPlanRegions(const VoxelMap& map, double size_m) noexcept {
  const double res = map.geometry().resolution;
  const double n = map.geometry().region_voxels;
  // planHeightmap(): the grid is size/res cells (rounded), the box z from centre - half - 1 to
  // centre + half voxels; a span of v voxels touches at most ceil(v / n) + 1 regions.
  const double cells = std::ceil(size_m / res) + 1.0;
  const double z_voxels = 2.0 * std::ceil(0.5 * size_m / res) + 2.0;
  const double xy = std::ceil(cells / n) + 1.0;
  const double z = std::ceil(z_voxels / n) + 1.0;
  return static_cast<std::size_t>(xy * xy * z);
}

void reservePlan(HeightmapPlan& plan, std::size_t regions) {
  plan.region_table.reserve(regions);
  plan.region_slots.reserve(regions);
}

namespace {

/// A box the map can hold: within a rolling window, and its centre inside the map's bounds.
Expected<void, Error> checkBoxInMap(const VoxelMap& map, const HeightmapOptions& o) {
  if (map.config().policy == StorePolicy::kRolling) {
    const auto [lo, hi] = map.windowBounds();
    const double window = std::min(hi.x - lo.x, hi.y - lo.y);
    if (o.size > window + 1e-9) {
      return fail(ErrorCode::kInvalidArgument, "heightmap.size: " + metres(o.size) +
                                                   ": larger than the rolling window (" +
                                                   metres(window) + " m)");
    }
  }
  const auto [lo, hi] = mapBounds(map);
  for (int a = 0; a < 3; ++a) {
    if (!(o.centre[a] >= lo[a] && o.centre[a] < hi[a])) {
      return fail(ErrorCode::kInvalidArgument,
                  "heightmap.centre: " + metres(o.centre.x) + "," + metres(o.centre.y) + "," +
                      metres(o.centre.z) + ": outside the map (x " + metres(lo.x) + ".." +
                      metres(hi.x) + ", y " + metres(lo.y) + ".." + metres(hi.y) + ", z " +
                      metres(lo.z) + ".." + metres(hi.z) + " m)");
    }
  }
  return {};
}

double floorDepthOf(const HeightmapOptions& o) { return o.floor_depth.value_or(0.5 * o.size); }
double ceilingHeightOf(const HeightmapOptions& o) {
  return o.ceiling_height.value_or(0.5 * o.size);
}

/// The options' values, each by its key: finite, in range, and a box the map can hold.
Expected<void, Error> checkOptions(const VoxelMap& map, const HeightmapOptions& o) {
  const double res = map.geometry().resolution;
  if (!std::isfinite(o.centre.x) || !std::isfinite(o.centre.y) || !std::isfinite(o.centre.z)) {
    return fail(ErrorCode::kInvalidArgument,
                "heightmap.centre: must be three finite numbers (metres)");
  }
  if (!(o.size >= res) || !std::isfinite(o.size)) {
    return fail(ErrorCode::kInvalidArgument, "heightmap.size: " + metres(o.size) +
                                                 ": must be a finite size of at least the map "
                                                 "resolution (" +
                                                 metres(res) + " m)");
  }
  if (!(o.min_clearance >= 0.0) || !std::isfinite(o.min_clearance)) {
    return fail(ErrorCode::kInvalidArgument,
                "heightmap.min_clearance: " + metres(o.min_clearance) + ": must be >= 0 metres");
  }
  const double floor_depth = floorDepthOf(o);
  const double ceiling_height = ceilingHeightOf(o);
  if (!(floor_depth >= 0.0) || !std::isfinite(floor_depth)) {
    return fail(ErrorCode::kInvalidArgument,
                "heightmap.floor_depth: " + metres(floor_depth) + ": must be >= 0");
  }
  if (!(ceiling_height >= 0.0) || !std::isfinite(ceiling_height)) {
    return fail(ErrorCode::kInvalidArgument,
                "heightmap.ceiling_height: " + metres(ceiling_height) + ": must be >= 0");
  }
  const long cells_long = std::lround(o.size / res);
  if (cells_long > kMaxCellsPerSide) {
    return fail(ErrorCode::kInvalidArgument, "heightmap.size: " + metres(o.size) + ": " +
                                                 std::to_string(cells_long) +
                                                 " cells per side at " + metres(res) +
                                                 " m; at most " + std::to_string(kMaxCellsPerSide));
  }
  return checkBoxInMap(map, o);
}

/// The grid's voxel box: cells x cells columns, the centre's column at the middle (rounded
/// toward +x), and the height range searched.
struct GridBox {
  int cells = 1;
  Vec3i centre_voxel;
  std::int32_t x_min = 0, y_min = 0, x_max = 0, y_max = 0, z_min = 0, z_max = 0;
};

GridBox gridBox(const VoxelMap& map, const HeightmapOptions& o) {
  const double res = map.geometry().resolution;
  GridBox box;
  box.cells = static_cast<int>(std::max(1L, std::lround(o.size / res)));
  box.centre_voxel = map.voxelOf(o.centre);
  box.x_min = box.centre_voxel.x - box.cells / 2;
  box.y_min = box.centre_voxel.y - box.cells / 2;
  box.x_max = box.x_min + box.cells - 1;
  box.y_max = box.y_min + box.cells - 1;
  const auto half_cells = static_cast<std::int32_t>(std::lround(0.5 * o.size / res));
  box.z_min = box.centre_voxel.z - half_cells;
  box.z_max = box.centre_voxel.z + half_cells;
  return box;
}

/// The kernel's parameters for the box (kernels/common/heightmap.h).
rm_heightmap_params kernelParams(const VoxelMap& map, const HeightmapOptions& o,
                                 const GridBox& box) {
  const double res = map.geometry().resolution;
  rm_heightmap_params p{};
  p.cells_x = box.cells;
  p.cells_y = box.cells;
  p.voxel_x0 = box.x_max;
  p.voxel_y0 = box.y_max;
  p.region_voxels = map.geometry().region_voxels;
  p.region_shift = -1;
  for (int shift = 0; shift < 31; ++shift) {
    if ((1 << shift) == p.region_voxels) {
      p.region_shift = shift;
    }
  }
  const Vec3i region_lo = map.regionOfVoxel({box.x_min, box.y_min, box.z_min - 1});
  const Vec3i region_hi = map.regionOfVoxel({box.x_max, box.y_max, box.z_max});
  p.region_x0 = region_lo.x;
  p.region_y0 = region_lo.y;
  p.region_z0 = region_lo.z;
  p.regions_x = region_hi.x - region_lo.x + 1;
  p.regions_y = region_hi.y - region_lo.y + 1;
  p.regions_z = region_hi.z - region_lo.z + 1;
  p.box_z_min = box.z_min;
  p.box_z_max = box.z_max;
  p.seed_i = box.x_max - box.centre_voxel.x;
  p.seed_j = box.y_max - box.centre_voxel.y;
  p.flags = (o.virtual_surfaces ? RM_HM_FLAG_VIRTUAL : 0) |
            (map.meanLayer() >= 0 ? RM_HM_FLAG_SAMPLES : 0) |
            (o.use_voxel_mean && map.meanLayer() >= 0 ? RM_HM_FLAG_MEAN : 0) |
            (o.mode == HeightmapMode::kFill ? RM_HM_FLAG_FILL : 0) |
            (map.ndtLayer() >= 0 ? RM_HM_FLAG_NORMALS : 0);
  p.resolution = static_cast<float>(res);
  p.inverse_resolution = static_cast<float>(1.0 / res);
  p.reference_z = static_cast<float>(o.centre.z);
  p.floor_depth = static_cast<float>(floorDepthOf(o));
  p.ceiling_height = static_cast<float>(ceilingHeightOf(o));
  p.min_clearance = static_cast<float>(o.min_clearance);
  p.occupied_threshold = map.occupancy().threshold;
  p.normal_min_samples = map.config().ndt.sample_threshold;
  return p;
}

/// The region table over the box: each region's index into region_slots, or RM_HM_NO_REGION.
Expected<void, Error> tableRegions(const VoxelMap& map, const HeightmapOptions& o,
                                   HeightmapPlan& plan) {
  const rm_heightmap_params& p = plan.params;
  const auto table_size = static_cast<std::size_t>(p.regions_x) *
                          static_cast<std::size_t>(p.regions_y) *
                          static_cast<std::size_t>(p.regions_z);
  plan.region_table.resize(table_size);
  plan.region_slots.clear();
  // A tiered map brings the box's cold regions into its pool; all of them are used in this epoch,
  // so none is evicted while the plan is built, nor before the next epoch but one.
  map.beginEpoch();
  std::size_t t = 0;
  for (std::int32_t z = 0; z < p.regions_z; ++z) {
    for (std::int32_t y = 0; y < p.regions_y; ++y) {
      for (std::int32_t x = 0; x < p.regions_x; ++x) {
        const Vec3i region{p.region_x0 + x, p.region_y0 + y, p.region_z0 + z};
        auto resident = map.residentSlot(region);
        if (!resident) {
          if (resident.error() == StoreError::kFull) {
            return fail(ErrorCode::kCapacity,
                        "heightmap.size: " + metres(o.size) +
                            ": the box covers more regions than the " +
                            std::to_string(map.store().capacity()) +
                            " the map's memory budget holds at once (map.max_memory)");
          }
          return Unexpected(map.tierError(resident.error()));
        }
        const std::uint32_t slot = *resident;
        if (slot == RegionStore::kNoSlot) {
          plan.region_table[t++] = RM_HM_NO_REGION;
        } else {
          plan.region_table[t++] = static_cast<std::uint32_t>(plan.region_slots.size());
          plan.region_slots.push_back(slot);
        }
      }
    }
  }
  return {};
}

}  // namespace

Expected<void, Error> planHeightmap(const VoxelMap& map, const HeightmapOptions& o,
                                    HeightmapPlan& plan) {
  if (map.occupancyLayer() < 0) {
    return fail(ErrorCode::kUnsupported,
                "the map has no occupancy layer: a height map needs occupied and free voxels");
  }
  if (auto ok = checkOptions(map, o); !ok) {
    return ok;
  }
  const GridBox box = gridBox(map, o);
  plan.params = kernelParams(map, o, box);
  if (auto ok = tableRegions(map, o, plan); !ok) {
    return ok;
  }
  const double res = map.geometry().resolution;
  HeightMap& g = plan.grid;
  g.resolution = res;
  g.cells_x = box.cells;
  g.cells_y = box.cells;
  g.centre_x = (box.x_min + 0.5 * box.cells) * res;
  g.centre_y = (box.y_min + 0.5 * box.cells) * res;
  g.reference_z = o.centre.z;
  g.mode = o.mode;
  g.has_normals = map.ndtLayer() >= 0;
  return {};
}

}  // namespace raymap::heightmap
