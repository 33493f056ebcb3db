// SPDX-License-Identifier: BSD-3-Clause
// ScanBits: the CPU's once-per-scan bits are claimed once per batch, start clear in every batch,
// never pass an old batch's bits off as new ones when the map restarts its sequences, and keep
// each slot's bits apart (two workers own two slots); the misses marked on their own plane take
// one miss per voxel at the end of the batch, and none where the scan hit.
#include <array>
#include <cstdint>
#include <set>

#include <gtest/gtest.h>

#include "src/map/cpu_voxel_ops.hpp"
#include "src/map/scan_bits.hpp"

namespace raymap::detail {
namespace {

TEST(ScanBits, AVoxelIsClaimedOncePerBatch) {
  ScanBits bits(4, 32);
  bits.beginBatch(1);
  std::uint64_t* slot = bits.bitsFor(2);
  EXPECT_TRUE(ScanBits::claim(slot, 0));
  EXPECT_FALSE(ScanBits::claim(slot, 0));
  EXPECT_TRUE(ScanBits::claim(slot, 63));
  EXPECT_TRUE(ScanBits::claim(slot, 64));  // the next word
  EXPECT_TRUE(ScanBits::claim(slot, 32 * 32 * 32 - 1));
  EXPECT_FALSE(ScanBits::claim(bits.bitsFor(2), 64));  // asked again in the same batch: kept

  bits.beginBatch(2);
  slot = bits.bitsFor(2);
  EXPECT_TRUE(ScanBits::claim(slot, 0));
  EXPECT_TRUE(ScanBits::claim(slot, 64));
  EXPECT_TRUE(ScanBits::claim(slot, 32 * 32 * 32 - 1));
}

TEST(ScanBits, ARestartedSequenceNeverReusesOldBits) {
  ScanBits bits(2, 8);
  bits.beginBatch(5);
  ASSERT_TRUE(ScanBits::claim(bits.bitsFor(0), 7));
  // The map restarts its sequences (VoxelMap::beginScan after RM_SCAN_SEQUENCE_MAX) and comes
  // back to 5 without slot 0 being used in between: its stamp 5 must not vouch for its bits.
  for (std::uint32_t sequence = 1; sequence <= 5; ++sequence) {
    bits.beginBatch(sequence);
    (void)bits.bitsFor(1);
  }
  EXPECT_TRUE(ScanBits::claim(bits.bitsFor(0), 7));
}

TEST(ScanBits, SlotsKeepTheirBitsOnSeparateCacheLines) {
  ScanBits bits(3, 4);  // 64 voxels: one word, padded to a line
  bits.beginBatch(1);
  std::uint64_t* a = bits.bitsFor(0);
  std::uint64_t* b = bits.bitsFor(1);
  const auto distance = reinterpret_cast<std::uintptr_t>(b) - reinterpret_cast<std::uintptr_t>(a);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(a) % 64u, 0u);
  EXPECT_EQ(distance % 64u, 0u);
  EXPECT_GE(distance, 64u);
  for (std::uint32_t i = 0; i < 64; ++i) {
    ASSERT_TRUE(ScanBits::claim(a, i));
  }
  for (std::uint32_t i = 0; i < 64; ++i) {
    EXPECT_TRUE(ScanBits::claim(b, i)) << "voxel " << i;
  }
}

TEST(ScanBits, MissesAreMarkedOnAPlaneOfTheirOwnAndClearedWithTheHits) {
  ScanBits bits(3, 8);  // 512 voxels: 8 words per plane
  EXPECT_EQ(bits.voxelWords(), 8u);
  bits.beginBatch(1);
  std::uint64_t* hits = bits.bitsFor(1);
  std::uint64_t* misses = bits.missPlane(hits);
  ScanBits::mark(misses, 5);
  ScanBits::mark(misses, 5);
  ScanBits::mark(misses, 511);
  EXPECT_EQ(misses[0], std::uint64_t{1} << 5u);
  EXPECT_EQ(misses[7], std::uint64_t{1} << 63u);
  EXPECT_TRUE(ScanBits::claim(hits, 5)) << "a marked miss is not a hit";
  // Slot 2's planes lie after slot 1's miss plane.
  EXPECT_GE(bits.bitsFor(2), misses + bits.voxelWords());

  std::set<std::uint32_t> used;
  bits.forEachSlotOfBatch([&](std::uint32_t slot) { used.insert(slot); });
  EXPECT_EQ(used, (std::set<std::uint32_t>{1, 2}));

  bits.beginBatch(2);
  used.clear();
  bits.forEachSlotOfBatch([&](std::uint32_t slot) { used.insert(slot); });
  EXPECT_TRUE(used.empty());
  hits = bits.bitsFor(1);
  misses = bits.missPlane(hits);
  for (std::size_t w = 0; w < bits.voxelWords(); ++w) {
    EXPECT_EQ(hits[w], 0u) << "word " << w;
    EXPECT_EQ(misses[w], 0u) << "word " << w;
  }
}

// The per-scan rule with the miss plane: a voxel crossed by any number of the scan's rays takes
// one miss, a voxel the scan hit takes no miss (its hit was applied in the hit pass), and the
// others are not touched.
TEST(ScanBits, EachMarkedVoxelTakesOneMissUnlessTheScanHitIt) {
  constexpr std::int32_t kEdge = 8;
  ScanBits bits(1, kEdge);
  bits.beginBatch(1);
  std::array<float, kEdge * kEdge * kEdge> occupancy{};
  occupancy.fill(RM_OCC_UNOBSERVED);
  occupancy[200] = 1.0f;
  occupancy[300] = 1.0f;
  const rm_occupancy_params params{0.85f, -0.4f, -2.0f, 3.5f, 0.0f};
  RegionLayers layers;
  layers.occupancy = occupancy.data();
  layers.scan_bits = bits.bitsFor(0);
  layers.scan_misses = bits.missPlane(layers.scan_bits);

  applyScanHit(layers, 300, params);   // the hit pass: 1.0 -> 1.85
  for (int ray = 0; ray < 5; ++ray) {  // five rays cross voxels 3, 200 and 300
    PerScanMiss{layers.scan_misses}(3);
    PerScanMiss{layers.scan_misses}(200);
    PerScanMiss{layers.scan_misses}(300);
  }
  PerScanMiss{layers.scan_misses}(511);
  applyScanMisses(layers, bits.voxelWords(), params);

  EXPECT_FLOAT_EQ(occupancy[3], -0.4f);  // unobserved: one miss from 0
  EXPECT_FLOAT_EQ(occupancy[200], 0.6f);
  EXPECT_FLOAT_EQ(occupancy[300], 1.85f);  // hit in this scan: no miss
  EXPECT_FLOAT_EQ(occupancy[511], -0.4f);
  int touched = 0;
  for (const float value : occupancy) {
    touched += value != RM_OCC_UNOBSERVED ? 1 : 0;
  }
  EXPECT_EQ(touched, 4);
}

}  // namespace
}  // namespace raymap::detail
