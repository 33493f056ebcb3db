// SPDX-License-Identifier: BSD-3-Clause
#include "src/map/miss_planes.hpp"

#include <algorithm>
#include <bit>
#include <cstring>

namespace raymap::detail {

MissPlanes::MissPlanes(std::size_t max_regions, std::size_t plane_words)
    : plane_words_(plane_words), limit_(max_regions) {
  const std::size_t buckets = std::bit_ceil(max_regions * 2u + 2u);
  keys_.assign(buckets, kEmpty);
  plane_.assign(buckets, kNoPlane);
  used_.reserve(max_regions);
  mask_ = buckets - 1;
  front_keys_.fill(kEmpty);
}

const std::uint64_t* MissPlanes::find(std::uint64_t key) const noexcept {
  for (std::size_t b = bucketOf(key);; b = (b + 1) & mask_) {
    if (keys_[b] == key) {
      return words_.data() + (std::size_t{plane_[b]} * plane_words_);
    }
    if (keys_[b] == kEmpty) {
      return nullptr;
    }
  }
}

std::uint32_t MissPlanes::insert(std::uint64_t key) noexcept {
  std::size_t b = bucketOf(key);
  for (; keys_[b] != kEmpty; b = (b + 1) & mask_) {
    if (keys_[b] == key) {
      return plane_[b];
    }
  }
  const std::size_t p = used_.size();
  if (p >= limit_) {
    return kNoPlane;  // more regions than the store holds: the survey's work table says so too
  }
  // Grown by doubling, keeping the planes in use; at least 64 planes (256 KiB at 32 voxels).
  const std::size_t needed = (p + 1u) * plane_words_;
  if (needed > words_.capacity() &&
      !words_.reserve(std::max(2u * needed, 64u * plane_words_), p * plane_words_)) {
    return kNoPlane;
  }
  keys_[b] = key;
  plane_[b] = static_cast<std::uint32_t>(p);
  used_.push_back(b);
  std::uint64_t* words = plane(static_cast<std::uint32_t>(p));
  std::memset(words, 0, plane_words_ * sizeof(std::uint64_t));
  return static_cast<std::uint32_t>(p);
}

void MissPlanes::clear() noexcept {
  for (std::size_t b : used_) {
    keys_[b] = kEmpty;
  }
  used_.clear();
  front_keys_.fill(kEmpty);
}

}  // namespace raymap::detail
