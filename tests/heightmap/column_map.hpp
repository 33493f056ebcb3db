// SPDX-License-Identifier: BSD-3-Clause
// A small hand-built map for height-map tests: voxels set one by one.
#pragma once
#include <cstdint>
#include <memory>

#include "src/map/voxel_map.hpp"

namespace raymap::test {

/// @brief A 0.1 m global map (regions of 32 voxels) with the eight regions around the origin
/// stored, so every test's centre near the origin is inside it; voxels are set directly in the
/// occupancy and mean layers (world frame, global voxel coordinates).
class ColumnMap {
 public:
  static constexpr float kOccupied = 2.0f;  ///< log-odds of an occupied voxel
  static constexpr float kFree = -1.0f;     ///< log-odds of a free voxel

  ColumnMap();
  VoxelMap& map() { return *map_; }

  /// Sets a voxel's log-odds; `mean_z` (voxel units, 0..1) gives it `count` samples.
  void set(int x, int y, int z, float value, float mean_z = -1.0f, std::uint32_t count = 3);
  void occupied(int x, int y, int z, float mean_z = -1.0f) { set(x, y, z, kOccupied, mean_z); }
  /// Free voxels z0..z1 inclusive.
  void freeRange(int x, int y, int z0, int z1);

 private:
  std::unique_ptr<VoxelMap> map_;
};

}  // namespace raymap::test
