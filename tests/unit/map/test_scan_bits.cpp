// SPDX-License-Identifier: BSD-3-Clause
// ScanBits: the CPU's once-per-scan bits are claimed once per batch, start clear in every batch,
// never pass an old batch's bits off as new ones when the map restarts its sequences, and keep
// each slot's bits apart (two workers own two slots).
#include <cstdint>

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace raymap::detail
