// SPDX-License-Identifier: BSD-3-Clause
// TransferStaging: the ring that region moves between the host store and a device cache go
// through, freed batch by batch. Host code only; runs without a device.
#include <array>
#include <cstddef>
#include <cstring>
#include <vector>

#include <gtest/gtest.h>

#include "src/device/staging/transfer_staging.hpp"

namespace raymap::gpu {
namespace {

TEST(TransferStaging, DownloadsReachTheHostStoreOnlyWhenTheirBatchRetires) {
  TransferStaging ring(64, 4, std::pmr::get_default_resource());
  std::array<std::byte, 16> host_a{};
  std::array<std::byte, 16> host_b{};
  // A download for batch 1 (host slot 2) and one for batch 2 (host slot 3).
  std::byte* a = ring.reserve(16, 1);
  ASSERT_NE(a, nullptr);
  ring.noteDownload(a, host_a.data(), 16, 2);
  std::memset(a, 0x11, 16);  // the device's copy lands in the ring
  std::byte* b = ring.reserve(16, 2);
  ASSERT_NE(b, nullptr);
  ring.noteDownload(b, host_b.data(), 16, 3);
  std::memset(b, 0x22, 16);
  EXPECT_TRUE(ring.downloadPending(2));
  EXPECT_TRUE(ring.downloadPending(3));
  EXPECT_EQ(host_a[0], std::byte{0});

  ring.complete(1);
  EXPECT_EQ(host_a[15], std::byte{0x11});
  EXPECT_FALSE(ring.downloadPending(2));
  EXPECT_TRUE(ring.downloadPending(3));
  EXPECT_EQ(host_b[0], std::byte{0});

  ring.completeAll();
  EXPECT_EQ(host_b[15], std::byte{0x22});
  EXPECT_FALSE(ring.downloadPending(3));
}

TEST(TransferStaging, AFullRingSaysSoAndWrapsOnceItsOldestBatchRetires) {
  TransferStaging ring(100, 1, std::pmr::get_default_resource());
  std::byte* first = ring.reserve(40, 1);
  std::byte* second = ring.reserve(40, 2);
  ASSERT_NE(first, nullptr);
  ASSERT_NE(second, nullptr);
  EXPECT_EQ(second - first, 40);
  EXPECT_EQ(ring.reserve(40, 2), nullptr);  // 20 bytes left at the end
  EXPECT_NE(ring.reserve(20, 2), nullptr);  // which a smaller copy takes
  ring.complete(1);                         // frees the first 40 bytes
  std::byte* wrapped = ring.reserve(40, 3);
  EXPECT_EQ(wrapped, first);               // the copy wraps to the start, never splits
  EXPECT_EQ(ring.reserve(1, 3), nullptr);  // nothing free between the new tail and batch 2's
  ring.complete(3);
  EXPECT_NE(ring.reserve(100, 4), nullptr);  // all of it, once everything has retired
  EXPECT_EQ(ring.reserve(101, 5), nullptr);  // more than the ring, ever
}

TEST(TransferStaging, UploadsHoldTheirSpaceUntilTheirBatchRetires) {
  TransferStaging ring(64, 1, std::pmr::get_default_resource());
  ASSERT_NE(ring.reserve(64, 7), nullptr);
  EXPECT_EQ(ring.reserve(1, 7), nullptr);
  ring.complete(6);
  EXPECT_EQ(ring.reserve(1, 8), nullptr);  // batch 7 still runs
  ring.complete(7);
  EXPECT_NE(ring.reserve(64, 8), nullptr);
}

TEST(TransferStaging, ARegionWantedBackUploadsFromItsDownloadAndHoldsItsSpace) {
  TransferStaging ring(64, 1, std::pmr::get_default_resource());
  std::array<std::byte, 16> host{};
  std::byte* landing = ring.reserve(16, 1);
  ring.noteDownload(landing, host.data(), 16, 0);
  ASSERT_NE(ring.reserve(16, 2), nullptr);                          // another copy behind it
  EXPECT_EQ(ring.stagedDownload(host.data() + 1, 16, 3), nullptr);  // not this layer
  EXPECT_EQ(ring.stagedDownload(host.data(), 16, 3), landing);
  ring.complete(2);  // the download is now wanted until batch 3: kept, and the copy behind too
  EXPECT_TRUE(ring.downloadPending(0));
  ring.complete(3);
  EXPECT_FALSE(ring.downloadPending(0));
}

}  // namespace
}  // namespace raymap::gpu
