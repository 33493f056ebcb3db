// SPDX-License-Identifier: BSD-3-Clause
// Region store: pool sizing, index behaviour under random inserts and deletes, capacity.
#include <cmath>
#include <map>
#include <random>
#include <tuple>

#include <gtest/gtest.h>

#include "src/map/region_store.hpp"

namespace raymap {
namespace {

RegionStore makeStore(std::uint32_t capacity, std::int32_t n = 8) {
  RegionStore::Config config;
  (void)config.schema.add(LayerKind::kOccupancy);
  (void)config.schema.add(LayerKind::kVoxelMean);
  config.region_voxels = n;
  config.capacity = capacity;
  auto store = RegionStore::create(config);
  EXPECT_TRUE(store.has_value());
  return std::move(store).value();
}

TEST(RegionStore, PoolIsWhatTheConfigurationSays) {
  const RegionStore store = makeStore(10, 32);
  // 32^3 voxels x (4 + 8) bytes x 10 regions, in one block.
  EXPECT_EQ(store.poolBytes(), std::size_t{32 * 32 * 32} * 12u * 10u);
  EXPECT_EQ(store.capacity(), 10u);
  EXPECT_EQ(store.size(), 0u);
}

TEST(RegionStore, NewRegionsStartClear) {
  RegionStore store = makeStore(2);
  auto slot = store.findOrCreate({1, -2, 3});
  ASSERT_TRUE(slot);
  const float* occ = store.layerData<float>(*slot, 0);
  const auto* mean = store.layerData<std::uint32_t>(*slot, 1);
  for (std::uint32_t i = 0; i < store.voxelsPerRegion(); ++i) {
    ASSERT_TRUE(std::isinf(occ[i]) && occ[i] > 0.0f);
    ASSERT_EQ(mean[2 * i], 0u);
    ASSERT_EQ(mean[2 * i + 1], 0u);
  }
  EXPECT_EQ(store.find({1, -2, 3}), *slot);
  EXPECT_EQ(store.coordOf(*slot), (Vec3i{1, -2, 3}));
}

TEST(RegionStore, FullStoreSaysSoAndKeepsItsRegions) {
  RegionStore store = makeStore(3);
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(store.findOrCreate({i, 0, 0}));
  }
  auto full = store.findOrCreate({9, 9, 9});
  ASSERT_FALSE(full);
  EXPECT_EQ(full.error(), StoreError::kFull);
  // Existing regions are still found, and found by findOrCreate without a new slot.
  for (int i = 0; i < 3; ++i) {
    EXPECT_NE(store.find({i, 0, 0}), RegionStore::kNoSlot);
    EXPECT_TRUE(store.findOrCreate({i, 0, 0}));
  }
  EXPECT_EQ(store.find({9, 9, 9}), RegionStore::kNoSlot);
}

TEST(RegionStore, RecycledSlotsStartClearAgain) {
  RegionStore store = makeStore(1);
  auto a = store.findOrCreate({0, 0, 0});
  ASSERT_TRUE(a);
  store.layerData<float>(*a, 0)[17] = 1.5f;
  store.release(*a);
  EXPECT_EQ(store.find({0, 0, 0}), RegionStore::kNoSlot);
  auto b = store.findOrCreate({5, 5, 5});
  ASSERT_TRUE(b);
  EXPECT_EQ(*b, *a);  // the same memory, recycled
  EXPECT_TRUE(std::isinf(store.layerData<float>(*b, 0)[17]));
}

// A device sharing the pool clears a new region itself (findOrCreateUncleared, then a fill that
// skips zero layers on a slot still on zero pages) and writes into it; when that slot is
// released and reused, its zero-valued layers must be cleared again, not trusted to be zero.
TEST(RegionStore, ASlotWrittenWithoutAHostClearIsClearedWhenReused) {
  RegionStore store = makeStore(1);
  bool created = false;
  auto a = store.findOrCreateUncleared({0, 0, 0}, &created);
  ASSERT_TRUE(a && created);
  EXPECT_TRUE(store.onZeroPages(*a));
  store.layerData<std::uint32_t>(*a, 1)[2 * 5 + 1] = 7u;  // a mean count, written "by a device"
  store.release(*a);
  EXPECT_FALSE(store.onZeroPages(*a));
  auto b = store.findOrCreate({1, 1, 1});
  ASSERT_TRUE(b);
  ASSERT_EQ(*b, *a);
  EXPECT_EQ(store.layerData<std::uint32_t>(*b, 1)[2 * 5 + 1], 0u);
}

TEST(RegionStore, OutOfRangeCoordinatesAreRefused) {
  RegionStore store = makeStore(2);
  auto r = store.findOrCreate({RegionStore::kMaxRegionCoord + 1, 0, 0});
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error(), StoreError::kOutOfRange);
  EXPECT_TRUE(store.findOrCreate({-RegionStore::kMaxRegionCoord, RegionStore::kMaxRegionCoord, 0}));
}

TEST(RegionStore, PackedCoordinatesRoundTrip) {
  for (const Vec3i r : {Vec3i{0, 0, 0}, Vec3i{-1, 2, -3},
                        Vec3i{RegionStore::kMaxRegionCoord, -RegionStore::kMaxRegionCoord, 7}}) {
    EXPECT_EQ(RegionStore::unpackCoord(RegionStore::packCoord(r)), r);
  }
}

TEST(RegionStore, IndexAgreesWithAModelUnderRandomChurn) {
  // Inserts and deletes in a small coordinate space, so probe runs collide and backward-shift
  // deletion is exercised; compared after every operation with std::map.
  RegionStore store = makeStore(64, 4);
  std::map<std::tuple<int, int, int>, std::uint32_t> model;
  std::mt19937 rng(5489);
  std::uniform_int_distribution<int> c(-4, 4);
  for (int step = 0; step < 20000; ++step) {
    const Vec3i r{c(rng), c(rng), c(rng)};
    const auto key = std::make_tuple(r.x, r.y, r.z);
    if ((rng() & 1u) != 0u) {
      auto slot = store.findOrCreate(r);
      if (model.count(key) != 0) {
        ASSERT_TRUE(slot);
        ASSERT_EQ(*slot, model[key]);
      } else if (model.size() < 64) {
        ASSERT_TRUE(slot);
        model[key] = *slot;
      } else {
        ASSERT_FALSE(slot);
      }
    } else if (model.count(key) != 0) {
      store.release(model[key]);
      model.erase(key);
    }
    ASSERT_EQ(store.size(), model.size());
    if (step % 97 == 0) {
      for (int x = -4; x <= 4; ++x) {
        for (int y = -4; y <= 4; ++y) {
          for (int z = -4; z <= 4; ++z) {
            const auto it = model.find({x, y, z});
            ASSERT_EQ(store.find({x, y, z}), it == model.end() ? RegionStore::kNoSlot : it->second);
          }
        }
      }
    }
  }
}

}  // namespace
}  // namespace raymap
