// SPDX-License-Identifier: BSD-3-Clause
// Fixed-capacity hash index from a packed region coordinate to a 32-bit value (a slot).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace raymap {

/// @brief Open-addressing index (linear probing, backward-shift deletion, no tombstones), sized
/// once for `max_entries` and kept at most half full. Keys are RegionStore::packCoord() values
/// (never all ones).
///
/// Used by the host region store (region -> pool slot) and by the device region caches (region ->
/// device slot). Thread-safety: find() may run concurrently with find(); insert/erase/clear need
/// exclusive access. Real-time: everything but the constructor is allocation-free and noexcept,
/// O(1) expected.
class RegionIndex {
 public:
  static constexpr std::uint32_t kNone = 0xFFFFFFFFu;

  RegionIndex() = default;
  explicit RegionIndex(std::uint32_t max_entries);

  /// @brief Value stored for `key`, or kNone.
  std::uint32_t find(std::uint64_t key) const noexcept;
  /// @brief Stores `value` for `key`. @pre key absent and fewer than max_entries stored.
  void insert(std::uint64_t key, std::uint32_t value) noexcept;
  /// @brief Removes `key`. @pre key present.
  void erase(std::uint64_t key) noexcept;
  void clear() noexcept;

 private:
  std::size_t bucketOf(std::uint64_t key) const noexcept;

  std::vector<std::uint64_t> keys_;  // kEmptyKey or a key
  std::vector<std::uint32_t> values_;
  std::size_t mask_ = 0;
};

}  // namespace raymap
