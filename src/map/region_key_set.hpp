// SPDX-License-Identifier: BSD-3-Clause
// The packed region keys one worker met in a batch, each with a stable bucket for per-key values.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "src/map/region_slot_cache.hpp"

namespace raymap::detail {

/// @brief Open-addressing set of packed region keys (RegionStore::packCoord) with room for
/// `max_keys`: twice as many buckets, rounded up to a power of two, probed linearly from
/// regionKeyHash. A key keeps its bucket until clear(), so callers keep their values in arrays of
/// bucketCount() entries (the parallel survey's work per region, a worker's miss plane per
/// region). The buckets in use are listed in insertion order, so clear() and a walk over the
/// keys cost what the batch used, not the capacity.
///
/// Thread-safety: one worker's object; not thread-safe. Real time: allocates only in the
/// constructor.
class RegionKeySet {
 public:
  static constexpr std::size_t kNoBucket = ~std::size_t{0};
  /// A value no packed key takes (packCoord keys have 63 bits): marks empty buckets, and the
  /// callers' direct-mapped fronts use it too.
  static constexpr std::uint64_t kNoKey = ~std::uint64_t{0};

  explicit RegionKeySet(std::size_t max_keys)
      : keys_(std::bit_ceil(max_keys * 2u + 2u), kNoKey), limit_(max_keys) {
    mask_ = keys_.size() - 1u;
    used_.reserve(max_keys);
  }

  std::size_t bucketCount() const noexcept { return keys_.size(); }
  std::size_t size() const noexcept { return used_.size(); }
  /// True when `max_keys` keys are held: insert() adds no more.
  bool full() const noexcept { return used_.size() >= limit_; }

  /// @brief The bucket of `key`, or kNoBucket when the set does not hold it.
  std::size_t find(std::uint64_t key) const noexcept {
    for (std::size_t b = firstBucket(key);; b = (b + 1u) & mask_) {
      if (keys_[b] == key) {
        return b;
      }
      if (keys_[b] == kNoKey) {
        return kNoBucket;
      }
    }
  }

  /// @brief The bucket of `key`, added if new (`*added` says so); kNoBucket when the key is new
  /// and the set is full.
  std::size_t insert(std::uint64_t key, bool* added) noexcept {
    *added = false;
    for (std::size_t b = firstBucket(key);; b = (b + 1u) & mask_) {
      if (keys_[b] == key) {
        return b;
      }
      if (keys_[b] == kNoKey) {
        if (full()) {
          return kNoBucket;
        }
        keys_[b] = key;
        used_.push_back(b);
        *added = true;
        return b;
      }
    }
  }

  std::uint64_t keyAt(std::size_t bucket) const noexcept { return keys_[bucket]; }
  /// The buckets in use, in the order their keys were added.
  std::span<const std::size_t> usedBuckets() const noexcept { return used_; }

  /// @brief Forgets every key.
  void clear() noexcept {
    for (std::size_t b : used_) {
      keys_[b] = kNoKey;
    }
    used_.clear();
  }

 private:
  std::size_t firstBucket(std::uint64_t key) const noexcept {
    return static_cast<std::size_t>(regionKeyHash(key) >> 20) & mask_;
  }

  std::vector<std::uint64_t> keys_;
  std::vector<std::size_t> used_;
  std::size_t mask_ = 0;
  std::size_t limit_;
};

}  // namespace raymap::detail
