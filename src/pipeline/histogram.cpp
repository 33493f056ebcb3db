// SPDX-License-Identifier: BSD-3-Clause
// DurationHistogram: bucket arithmetic and quantiles.
#include "src/pipeline/histogram.hpp"

#include <bit>

namespace raymap::pipeline {

int DurationHistogram::bucketOf(std::uint64_t value_us) noexcept {
  if (value_us < kSub) {
    return static_cast<int>(value_us);
  }
  const int top = 63 - std::countl_zero(value_us);  // >= kSubBits
  const int octave = top - kSubBits;                // 0 for [64, 128)
  if (octave >= kOctaves) {
    return kBuckets - 1;
  }
  const auto sub = static_cast<int>((value_us >> (top - kSubBits)) & (kSub - 1));
  return kSub + octave * kSub + sub;
}

std::uint64_t DurationHistogram::bucketUpper(int b) noexcept {
  if (b < kSub) {
    return static_cast<std::uint64_t>(b);
  }
  const int octave = (b - kSub) / kSub;
  const int sub = (b - kSub) % kSub;
  const int shift = octave;  // bucket width 2^octave
  const std::uint64_t lower = (static_cast<std::uint64_t>(kSub + sub)) << shift;
  return lower + ((std::uint64_t{1} << shift) - 1);
}

void DurationHistogram::record(std::uint64_t value_us) noexcept {
  // The maximum first, then the count with release order: a snapshot that sees the count (an
  // acquire load) sees a maximum at least this value. Counted first, a snapshot could see the
  // value counted and an older, smaller maximum, and clamp a quantile below a value it counted
  // (any architecture: the two are separate locations).
  if (value_us > max_us_.load(std::memory_order_relaxed)) {
    max_us_.store(value_us, std::memory_order_relaxed);  // one writer: no CAS needed
  }
  counts_[static_cast<std::size_t>(bucketOf(value_us))].fetch_add(1, std::memory_order_release);
}

void DurationHistogram::snapshot(Snapshot* out) const noexcept {
  std::uint64_t total = 0;
  for (std::size_t b = 0; b < counts_.size(); ++b) {
    out->counts[b] = counts_[b].load(std::memory_order_acquire);  // pairs with record()
    total += out->counts[b];
  }
  out->total = total;
  // After the counts: at least the maximum of every value counted above.
  out->max_us = max_us_.load(std::memory_order_relaxed);
}

double DurationHistogram::Snapshot::quantileUs(double q) const noexcept {
  if (total == 0) {
    return 0.0;
  }
  // The smallest bucket whose cumulative count reaches ceil(q * total) (at least 1).
  auto rank = static_cast<std::uint64_t>(q * static_cast<double>(total) + 0.999999);
  rank = rank == 0 ? 1 : (rank > total ? total : rank);
  std::uint64_t seen = 0;
  for (int b = 0; b < kBuckets; ++b) {
    seen += counts[static_cast<std::size_t>(b)];
    if (seen >= rank) {
      const std::uint64_t upper = bucketUpper(b);
      return static_cast<double>(upper < max_us ? upper : max_us);
    }
  }
  return static_cast<double>(max_us);
}

DurationHistogram::Snapshot DurationHistogram::Snapshot::since(
    const Snapshot& earlier) const noexcept {
  Snapshot d;
  for (std::size_t b = 0; b < counts.size(); ++b) {
    d.counts[b] = counts[b] - earlier.counts[b];
    d.total += d.counts[b];
  }
  d.max_us = max_us;
  return d;
}

}  // namespace raymap::pipeline
