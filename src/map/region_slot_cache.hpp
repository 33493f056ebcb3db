// SPDX-License-Identifier: BSD-3-Clause
// A small direct-mapped cache from region coordinate to slot, in front of a RegionIndex.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "src/map/region_store.hpp"

namespace raymap::detail {

/// @brief Fibonacci hash of a packed region key (key * 2^64 / golden ratio): its top bits are
/// the table index; the low bits of a packed key (one axis) alone would cluster.
inline std::uint64_t regionKeyHash(std::uint64_t key) noexcept {
  return key * 0x9E3779B97F4A7C15ull;
}

/// @brief Slot of a packed region key in a 256-entry direct-mapped table (the top 8 bits of
/// regionKeyHash).
inline std::size_t directMappedIndex(std::uint64_t key) noexcept {
  return static_cast<std::size_t>(regionKeyHash(key) >> 56);
}

/// @brief Direct-mapped cache in front of the store's index (region coordinate -> slot), one per
/// worker: a ray visits a handful of regions and neighbouring rays the same ones, so most lookups
/// hit a few kilobytes instead of probing the store's large index. Valid for one batch only
/// (regions may be recycled between batches). Not thread-safe; allocation-free. Aligned to a
/// cache line: find() writes to the cache on every lookup, and the caches of two workers lie side
/// by side in one array.
class alignas(64) RegionSlotCache {
 public:
  static constexpr std::size_t kEntries = 256;

  void reset() noexcept {
    for (Entry& e : entries_) {
      e.key = kEmpty;
    }
  }
  /// @brief Cached slot of a region (packed coordinate), or nullptr: then look it up and call
  /// remember().
  const std::uint32_t* find(std::uint64_t key) noexcept {
    key_ = key;
    entry_ = &entries_[directMappedIndex(key_)];
    return entry_->key == key_ ? &entry_->slot : nullptr;
  }
  /// @brief Records the slot of the region last passed to find().
  void remember(std::uint32_t slot) noexcept {
    entry_->key = key_;
    entry_->slot = slot;
  }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  static_assert(kEntries == 256, "the index is the top 8 bits of the hash");
  struct Entry {
    std::uint64_t key = kEmpty;
    std::uint32_t slot = RegionStore::kNoSlot;
  };
  std::array<Entry, kEntries> entries_{};
  std::uint64_t key_ = kEmpty;
  Entry* entry_ = nullptr;
};

}  // namespace raymap::detail
