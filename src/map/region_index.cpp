// SPDX-License-Identifier: BSD-3-Clause
// Open-addressing region index.
#include "src/map/region_index.hpp"

#include <bit>

#include "raymap/assert.hpp"

namespace raymap {
namespace {

constexpr std::uint64_t kEmptyKey = ~std::uint64_t{0};

}  // namespace

RegionIndex::RegionIndex(std::uint32_t max_entries) {
  const std::size_t buckets = std::bit_ceil(std::size_t{max_entries} * 2u + 2u);
  keys_.assign(buckets, kEmptyKey);
  values_.assign(buckets, kNone);
  mask_ = buckets - 1;
}

std::size_t RegionIndex::bucketOf(std::uint64_t key) const noexcept {
  // splitmix64 finaliser: neighbouring regions land in unrelated buckets.
  key ^= key >> 30;
  key *= 0xbf58476d1ce4e5b9ull;
  key ^= key >> 27;
  key *= 0x94d049bb133111ebull;
  key ^= key >> 31;
  return static_cast<std::size_t>(key) & mask_;
}

std::uint32_t RegionIndex::find(std::uint64_t key) const noexcept {
  if (keys_.empty()) {
    return kNone;
  }
  for (std::size_t b = bucketOf(key);; b = (b + 1) & mask_) {
    const std::uint64_t k = keys_[b];
    if (k == key) {
      return values_[b];
    }
    if (k == kEmptyKey) {
      return kNone;
    }
  }
}

void RegionIndex::insert(std::uint64_t key, std::uint32_t value) noexcept {
  RAYMAP_EXPECTS(!keys_.empty() && key != kEmptyKey);
  std::size_t b = bucketOf(key);
  while (keys_[b] != kEmptyKey) {
    RAYMAP_DEBUG_ASSERT(keys_[b] != key);
    b = (b + 1) & mask_;
  }
  keys_[b] = key;
  values_[b] = value;
}

void RegionIndex::erase(std::uint64_t key) noexcept {
  std::size_t b = bucketOf(key);
  while (keys_[b] != key) {
    RAYMAP_EXPECTS(keys_[b] != kEmptyKey);
    b = (b + 1) & mask_;
  }
  // Backward-shift deletion: pull later members of the probe run into the hole.
  std::size_t hole = b;
  for (std::size_t next = (hole + 1) & mask_; keys_[next] != kEmptyKey; next = (next + 1) & mask_) {
    const std::size_t home = bucketOf(keys_[next]);
    // Move `next` into the hole if its home is not cyclically within (hole, next].
    const bool home_in_range =
        hole <= next ? (home > hole && home <= next) : (home > hole || home <= next);
    if (!home_in_range) {
      keys_[hole] = keys_[next];
      values_[hole] = values_[next];
      hole = next;
    }
  }
  keys_[hole] = kEmptyKey;
  values_[hole] = kNone;
}

void RegionIndex::clear() noexcept {
  for (std::size_t b = 0; b < keys_.size(); ++b) {
    keys_[b] = kEmptyKey;
    values_[b] = kNone;
  }
}

}  // namespace raymap
