// SPDX-License-Identifier: BSD-3-Clause
#include "tests/heightmap/column_map.hpp"

#include <gtest/gtest.h>

#include "kernels/common/key_math.h"
#include "kernels/common/voxel_mean.h"

namespace raymap::test {

ColumnMap::ColumnMap() {
  MapConfig config;
  config.memory_budget_bytes = std::uint64_t{64} << 20;
  auto created = VoxelMap::create(config);
  EXPECT_TRUE(created) << created.error().message;
  map_ = std::make_unique<VoxelMap>(std::move(*created));
  for (int x = -1; x <= 0; ++x) {
    for (int y = -1; y <= 0; ++y) {
      for (int z = -1; z <= 0; ++z) {
        EXPECT_TRUE(map_->acquireRegion({x, y, z}));
      }
    }
  }
}

void ColumnMap::set(int x, int y, int z, float value, float mean_z, std::uint32_t count) {
  auto slot = map_->acquireRegion(map_->regionOfVoxel({x, y, z}));
  ASSERT_TRUE(slot);
  const rm_u32 index = rm_local_index(rm_local_of_voxel(rm_vec3i_make(x, y, z), 32), 32);
  map_->store().layerData<float>(*slot, map_->occupancyLayer())[index] = value;
  if (mean_z >= 0.0f) {
    auto* mean = map_->store().layerData<rm_voxel_mean>(*slot, map_->meanLayer());
    mean[index].packed = rm_mean_encode(rm_vec3f_make(0.5f, 0.5f, mean_z));
    mean[index].count = count;
  }
}

void ColumnMap::freeRange(int x, int y, int z0, int z1) {
  for (int z = z0; z <= z1; ++z) {
    set(x, y, z, kFree);
  }
}

}  // namespace raymap::test
