// SPDX-License-Identifier: BSD-3-Clause
// touchForWrite: a page first touched with write intent faults once, not twice, and keeps its
// value.
#include <cstddef>
#include <cstdint>

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include "platform/memory.hpp"
#include "platform/write_intent.hpp"

namespace raymap::platform {
namespace {

/// Minor page faults this thread has taken so far (Linux: RUSAGE_THREAD).
long threadMinorFaults() {
  rusage usage{};
  getrusage(RUSAGE_THREAD, &usage);
  return usage.ru_minflt;
}

/// The minor faults of `update` applied once to the first word of each of `pages` fresh pages.
template <class Update>
long faultsOfFirstUpdates(std::byte* first_page, int pages, std::size_t page, Update update) {
  const long before = threadMinorFaults();
  for (int i = 0; i < pages; ++i) {
    update(reinterpret_cast<std::uint32_t*>(first_page + (static_cast<std::size_t>(i) * page)));
  }
  return threadMinorFaults() - before;
}

TEST(WriteIntent, APageReadThenWrittenFaultsOnceWhenFirstTouchedForWrite) {
  // Arrange: three separate stretches of never-touched pages, 4 MiB apart so that none shares
  // a 2 MiB huge page with another where the OS backs anonymous memory with them.
  const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  constexpr int kPages = 64;
  constexpr std::size_t kStretch = 4u << 20;
  auto block = PageBlock::create(3 * kStretch);
  ASSERT_TRUE(block) << block.error().message;
  std::byte* read_first = block->data();
  std::byte* touched_first = block->data() + kStretch;
  std::byte* written_only = block->data() + (2 * kStretch);

  // Act: the read-modify-write of a voxel update (a count read, then written), as is and after
  // touchForWrite; and a plain write for the least a page can cost.
  const auto increment = [](std::uint32_t* word) {
    *static_cast<volatile std::uint32_t*>(word) = *static_cast<volatile std::uint32_t*>(word) + 1;
  };
  const long read_first_faults = faultsOfFirstUpdates(read_first, kPages, page, increment);
  const long touched_faults =
      faultsOfFirstUpdates(touched_first, kPages, page, [&](std::uint32_t* word) {
        touchForWrite(word);
        increment(word);
      });
  const long write_only_faults = faultsOfFirstUpdates(
      written_only, kPages, page,
      [](std::uint32_t* word) { *static_cast<volatile std::uint32_t*>(word) = 1; });

  // Assert: the read maps the shared zero page and the write then faults again to copy it
  // (twice the faults on 4 KiB pages); touched first, a page costs what a plain write costs.
  // A sanitizer's shadow memory may add a few faults of its own to each stretch alike.
  EXPECT_LT(touched_faults, read_first_faults)
      << "minor faults: read first " << read_first_faults << ", touched first " << touched_faults
      << ", written only " << write_only_faults;
  EXPECT_LE(touched_faults, write_only_faults + (kPages / 8));
  for (int i = 0; i < kPages; ++i) {
    const auto offset = static_cast<std::size_t>(i) * page;
    EXPECT_EQ(*reinterpret_cast<std::uint32_t*>(touched_first + offset), 1u) << "page " << i;
  }
}

TEST(WriteIntent, TouchingLeavesTheValuesAsTheyWere) {
  // Arrange: a 4-byte and an 8-byte object with every bit pattern that could carry.
  struct Pair {
    std::uint32_t a;
    std::uint32_t b;
  };
  std::uint32_t words[3] = {0xDEADBEEFu, 0u, 0xFFFFFFFFu};
  Pair pair{0xFFFFFFFFu, 0x80000001u};

  // Act
  for (std::uint32_t& word : words) {
    touchForWrite(&word);
  }
  touchForWrite(&pair);

  // Assert
  EXPECT_EQ(words[0], 0xDEADBEEFu);
  EXPECT_EQ(words[1], 0u);
  EXPECT_EQ(words[2], 0xFFFFFFFFu);
  EXPECT_EQ(pair.a, 0xFFFFFFFFu);
  EXPECT_EQ(pair.b, 0x80000001u);
}

}  // namespace
}  // namespace raymap::platform
