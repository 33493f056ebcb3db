// SPDX-License-Identifier: BSD-3-Clause
// FrameWriters: distinct writers of one frame's transform within a window, and counted while
// they are seen.
#include <atomic>
#include <thread>

#include <gtest/gtest.h>

#include "src/pipeline/frame_writers.hpp"

namespace raymap::pipeline {
namespace {

constexpr std::int64_t kSecond = 1'000'000'000;

TEST(FrameWriters, CountsTheWritersSeenWithinTheWindow) {
  FrameWriters writers;
  EXPECT_EQ(writers.writers(10 * kSecond, kSecond), 0u);
  writers.seen(11, 10 * kSecond);
  writers.seen(11, 10 * kSecond + kSecond / 2);
  EXPECT_EQ(writers.writers(10 * kSecond + kSecond / 2, kSecond), 1u) << "one writer, twice";
  writers.seen(22, 11 * kSecond);
  EXPECT_EQ(writers.writers(11 * kSecond, kSecond), 2u);
  // The first stops; a second later it no longer counts.
  writers.seen(22, 12 * kSecond);
  EXPECT_EQ(writers.writers(12 * kSecond, kSecond), 1u);
}

TEST(FrameWriters, ANewWriterTakesTheSlotOfTheLeastRecentlySeen) {
  FrameWriters writers;
  for (std::uint64_t w = 1; w <= FrameWriters::kSlots; ++w) {
    writers.seen(w, static_cast<std::int64_t>(w) * kSecond);
  }
  writers.seen(99, 100 * kSecond);  // replaces writer 1
  writers.seen(2, 100 * kSecond);
  EXPECT_EQ(writers.writers(100 * kSecond, kSecond), 2u);
}

TEST(FrameWritersStress, ACountTakenWhileWritersAreSeenIsOneTheyCouldGive) {
  // The ingest thread sees three writers in turn, one per millisecond of its clock; the
  // diagnostics thread counts them meanwhile (relaxed: a slot's writer and time may be read from
  // two different updates). Whatever it reads, a count is between 0 and the writers there are,
  // and once the ingest thread stops the count is exact.
  constexpr std::int64_t kUpdates = 200000;
  constexpr std::int64_t kMs = 1'000'000;
  FrameWriters writers;
  std::atomic<std::int64_t> now{0};
  std::atomic<bool> seen_all{false};
  std::thread ingest([&] {
    for (std::int64_t i = 1; i <= kUpdates; ++i) {
      writers.seen(static_cast<std::uint64_t>(1 + i % 3), i * kMs);
      now.store(i * kMs, std::memory_order_relaxed);
    }
    seen_all.store(true, std::memory_order_release);
  });
  std::uint64_t counts = 0;
  std::uint64_t impossible = 0;
  while (!seen_all.load(std::memory_order_acquire)) {
    const std::uint32_t n = writers.writers(now.load(std::memory_order_relaxed), kSecond);
    impossible += n > 3 ? 1 : 0;
    ++counts;
  }
  ingest.join();
  EXPECT_EQ(impossible, 0U) << "of " << counts << " counts";
  EXPECT_EQ(writers.writers(kUpdates * kMs, kSecond), 3U);
  EXPECT_EQ(writers.writers(kUpdates * kMs, kMs), 2U) << "the last two";
}

}  // namespace
}  // namespace raymap::pipeline
