// SPDX-License-Identifier: BSD-3-Clause
// PageArray: room without resident pages, growth that keeps what it is told to keep.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include "platform/page_array.hpp"

namespace raymap::platform {
namespace {

/// Pages of [data, data + bytes) that are resident (mincore), or -1 where it cannot tell.
long residentPages(void* data, std::size_t bytes) {
  const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  std::vector<unsigned char> in_core((bytes + page - 1) / page);
  // mincore wants a page-aligned start: PageArray's block starts on a page.
  if (mincore(data, bytes, in_core.data()) != 0) {
    return -1;
  }
  long resident = 0;
  for (unsigned char c : in_core) {
    resident += (c & 1u) != 0 ? 1 : 0;
  }
  return resident;
}

TEST(PageArray, RoomCostsNoResidentMemoryUntilWritten) {
  // Arrange
  PageArray<std::uint64_t> array;
  constexpr std::size_t kElements = 8u << 20;  // 64 MiB

  // Act
  ASSERT_TRUE(array.reserve(kElements));
  const long before = residentPages(array.data(), kElements * sizeof(std::uint64_t));
  array[0] = 7;
  const long after = residentPages(array.data(), kElements * sizeof(std::uint64_t));

  // Assert: a std::vector of the same size would have written (and made resident) every page.
  ASSERT_GE(before, 0) << "mincore failed";
  EXPECT_GE(array.capacity(), kElements);
  EXPECT_EQ(before, 0);
  EXPECT_GE(after, 1);
  // One 4 KiB page, or one 2 MiB huge page where the OS gives them: never the whole block.
  const auto page = static_cast<long>(sysconf(_SC_PAGESIZE));
  EXPECT_LE(after, (2L << 20) / page);
  EXPECT_EQ(array[0], 7u);
}

TEST(PageArray, GrowingKeepsTheFirstElementsAskedForAndSmallerRequestsChangeNothing) {
  // Arrange
  PageArray<std::uint32_t> array;
  ASSERT_TRUE(array.reserve(1000));
  const std::size_t first_capacity = array.capacity();
  for (std::uint32_t i = 0; i < 1000; ++i) {
    array[i] = 3u * i + 1u;
  }
  const std::uint32_t* first_block = array.data();

  // Act
  const bool smaller = array.reserve(10, 0);  // fits: nothing moves, nothing is lost
  const bool grown = array.reserve(first_capacity * 4, 600);

  // Assert
  EXPECT_TRUE(smaller);
  EXPECT_TRUE(grown);
  EXPECT_GE(array.capacity(), first_capacity * 4);
  EXPECT_NE(array.data(), first_block);
  for (std::uint32_t i = 0; i < 600; ++i) {
    ASSERT_EQ(array[i], 3u * i + 1u) << "element " << i;
  }
  // Past `keep` the new block holds what fresh pages hold: nothing of the old one.
  EXPECT_EQ(array[600], 0u);
}

}  // namespace
}  // namespace raymap::platform
