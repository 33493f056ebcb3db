// SPDX-License-Identifier: BSD-3-Clause
// A fixed-size log-linear histogram of durations (microseconds) for latency and jitter
// percentiles, written by one real-time thread and read by a reporting thread.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>

namespace raymap::pipeline {

/// @brief Counts of durations in buckets of about 1.6 % relative width (64 sub-buckets per power
/// of two) from 1 µs to 2^36 µs (19 hours); values below 64 µs are exact.
///
/// Design: one writer (record) and any number of readers (snapshot). A snapshot taken during a
/// record may miss that one value, nothing worse: its maximum is never below a value it counted
/// (record() stores the maximum before it counts with release order; snapshot() loads the counts
/// with acquire order, then the maximum). Stress test: DurationHistogramStress.* (arm64 under
/// qemu and ThreadSanitizer in CI).
/// @rt record: wait-free, allocates: no.
class DurationHistogram {
 public:
  static constexpr int kSubBits = 6;
  static constexpr int kSub = 1 << kSubBits;
  static constexpr int kOctaves = 31;  // 2^6 .. 2^36 µs above the exact range
  static constexpr int kBuckets = kSub + kOctaves * kSub;

  /// @brief Plain copy of the counts, for percentiles and differences between two snapshots.
  struct Snapshot {
    std::array<std::uint64_t, kBuckets> counts{};
    std::uint64_t total = 0;
    std::uint64_t max_us = 0;
    /// @brief The value (µs, the bucket's upper edge) at quantile q in [0, 1]; 0 when empty.
    double quantileUs(double q) const noexcept;
    /// @brief Counts recorded since `earlier` (max_us stays this snapshot's overall maximum).
    Snapshot since(const Snapshot& earlier) const noexcept;
  };

  void record(std::uint64_t value_us) noexcept;
  void snapshot(Snapshot* out) const noexcept;

  static int bucketOf(std::uint64_t value_us) noexcept;
  /// @brief Largest value that falls in bucket `b`.
  static std::uint64_t bucketUpper(int b) noexcept;

 private:
  std::array<std::atomic<std::uint64_t>, kBuckets> counts_{};
  std::atomic<std::uint64_t> max_us_{0};
};

}  // namespace raymap::pipeline
