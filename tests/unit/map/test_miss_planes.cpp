// SPDX-License-Identifier: BSD-3-Clause
// MissPlanes: a worker's per-scan miss bits keyed by region start clear in every batch, stay put
// while the batch asks again and while they grow past the first block, are found by key from
// another thread's point of view, and refuse a region past the store's capacity.
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "src/map/miss_planes.hpp"
#include "src/map/scan_bits.hpp"

namespace raymap::detail {
namespace {

TEST(MissPlanes, APlaneStartsClearInEachBatchAndIsFoundByItsKey) {
  const std::size_t words = ScanBits::voxelWordsFor(32);
  ASSERT_EQ(words, 512u);
  MissPlanes planes(8, words);
  std::uint64_t* a = planes.planeFor(42);
  ASSERT_NE(a, nullptr);
  for (std::size_t i = 0; i < words; ++i) {
    ASSERT_EQ(a[i], 0u);
  }
  ScanBits::mark(a, 5);
  // Asked again: the same plane, bits kept. (Marked through `a`, known not null: GCC's
  // -Wnull-dereference cannot see that planeFor() returns it again.)
  ASSERT_EQ(planes.planeFor(42), a);
  ScanBits::mark(a, 32767);
  EXPECT_EQ(planes.find(42), a);
  EXPECT_EQ(planes.find(42)[0], std::uint64_t{1} << 5u);
  EXPECT_EQ(planes.find(42)[511], std::uint64_t{1} << 63u);
  EXPECT_EQ(planes.find(43), nullptr);

  planes.clear();  // the next batch
  EXPECT_EQ(planes.find(42), nullptr);
  const std::uint64_t* again = planes.planeFor(42);
  ASSERT_NE(again, nullptr);
  EXPECT_EQ(again[0], 0u);
  EXPECT_EQ(again[511], 0u);
}

TEST(MissPlanes, PlanesKeepTheirBitsWhenTheBlockGrows) {
  // Keys whose front-cache entries collide and buckets cluster, and more planes than the first
  // block holds (64): every plane keeps its own bits.
  constexpr std::size_t kRegions = 300;
  MissPlanes planes(kRegions, 8);
  for (std::uint64_t k = 0; k < kRegions; ++k) {
    std::uint64_t* p = planes.planeFor(k << 21u);
    ASSERT_NE(p, nullptr) << k;
    p[k % 8] = k + 1;
  }
  for (std::uint64_t k = 0; k < kRegions; ++k) {
    const std::uint64_t* p = planes.find(k << 21u);
    ASSERT_NE(p, nullptr) << k;
    for (std::size_t i = 0; i < 8; ++i) {
      EXPECT_EQ(p[i], i == k % 8 ? k + 1 : 0u) << k << " word " << i;
    }
    EXPECT_EQ(planes.planeFor(k << 21u), p);
  }
  EXPECT_TRUE(planes.full());
}

TEST(MissPlanes, NoPlaneBeyondTheCapacity) {
  MissPlanes planes(2, 8);
  ASSERT_NE(planes.planeFor(1), nullptr);
  ASSERT_NE(planes.planeFor(2), nullptr);
  EXPECT_TRUE(planes.full());
  EXPECT_NE(planes.planeFor(1), nullptr);  // known keys still answer
  EXPECT_EQ(planes.planeFor(3), nullptr);
  EXPECT_TRUE(planes.full());
  planes.clear();
  EXPECT_FALSE(planes.full());
  EXPECT_NE(planes.planeFor(3), nullptr);
}

}  // namespace
}  // namespace raymap::detail
