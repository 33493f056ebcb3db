// SPDX-License-Identifier: BSD-3-Clause
// What a height map is asked for (centre, size, mode, limits) and the plan every generator (CPU,
// OpenCL, CUDA) executes: the kernel parameters and the table of map regions under the box.
#pragma once
#include <cstdint>
#include <optional>
#include <vector>

#include "raymap/error.hpp"

#include "kernels/common/heightmap.h"
#include "src/core/vec3.hpp"
#include "src/heightmap/height_map.hpp"
#include "src/map/voxel_map.hpp"

namespace raymap::heightmap {

/// @brief A height-map request. World frame, metres. Aggregate with defaults; checked by
/// planHeightmap().
struct HeightmapOptions {
  static constexpr double kDefaultSize = 20.0;
  static constexpr double kDefaultMinClearance = 0.5;
  /// x, y: the column the map is centred on (the robot); z: the reference height the surface is
  /// searched around (planar) or the flood fill starts from (usually the robot's ground height).
  Vec3d centre{};
  /// Side of the square map, metres. The searched box is the cube of this side centred on
  /// `centre`: columns look for surfaces and clearance inside it.
  double size = kDefaultSize;
  HeightmapMode mode = HeightmapMode::kPlanar;
  /// Free height a surface needs above it to count as ground (unobserved space counts as free).
  double min_clearance = kDefaultMinClearance;
  /// Metres below / above a column's reference searched for surfaces; nullopt: size / 2.
  std::optional<double> floor_depth;
  std::optional<double> ceiling_height;
  bool virtual_surfaces = false;  ///< report virtual surfaces (negative obstacles)
  bool use_voxel_mean = true;     ///< surface height from the voxel mean when the map has it
};

/// Largest grid side accepted, cells (a 0.1 m map: 819.2 m).
inline constexpr int kMaxCellsPerSide = 8192;

/// @brief The executable form of a request: kernel parameters, the region table (for every region
/// under the box, x fastest: its index r into `region_slots`, or RM_HM_NO_REGION where the map
/// holds none), the pool slot of each present region, and the output grid's geometry. Reusable:
/// planHeightmap() keeps the vectors' capacity.
struct HeightmapPlan {
  rm_heightmap_params params{};
  std::vector<std::uint32_t> region_table;
  std::vector<std::uint32_t> region_slots;
  HeightMap grid;  ///< geometry only (layers empty)
};

/// @brief The most regions a box of `size_m` (the map's height map size, metres) can lie over
/// in `map`, wherever it is centred: what a caller that must not allocate per cycle reserves.
std::size_t maxPlanRegions(const VoxelMap& map, double size_m) noexcept;

/// @brief Reserves `plan`'s tables for `regions` regions (start-up; planHeightmap() then
/// allocates nothing for boxes over at most that many).
void reservePlan(HeightmapPlan& plan, std::size_t regions);

/// @brief Checks a request against a map and plans it. Errors name the option and the reason: a
/// map without an occupancy layer, a centre outside the map (global maps: outside the stored
/// regions; rolling maps: outside the window), a size above the rolling window or
/// kMaxCellsPerSide, negative limits. @rt allocates: only when the table or grid grows.
Expected<void, Error> planHeightmap(const VoxelMap& map, const HeightmapOptions& options,
                                    HeightmapPlan& plan);

}  // namespace raymap::heightmap
