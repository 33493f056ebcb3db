// SPDX-License-Identifier: BSD-3-Clause
// FrameWriters: distinct writers of one frame's transform within a window.
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

}  // namespace
}  // namespace raymap::pipeline
