// SPDX-License-Identifier: BSD-3-Clause
#include "src/map/miss_planes.hpp"

#include <algorithm>
#include <cstring>

namespace raymap::detail {

MissPlanes::MissPlanes(std::size_t max_regions, std::size_t plane_words)
    : plane_words_(plane_words), keys_(max_regions), plane_(keys_.bucketCount(), kNoPlane) {
  front_keys_.fill(kEmpty);
}

const std::uint64_t* MissPlanes::find(std::uint64_t key) const noexcept {
  const std::size_t b = keys_.find(key);
  return b == RegionKeySet::kNoBucket ? nullptr
                                      : words_.data() + (std::size_t{plane_[b]} * plane_words_);
}

std::uint32_t MissPlanes::insert(std::uint64_t key) noexcept {
  if (const std::size_t b = keys_.find(key); b != RegionKeySet::kNoBucket) {
    return plane_[b];
  }
  if (keys_.full()) {
    return kNoPlane;  // more regions than the store holds: the survey's work table says so too
  }
  // Planes in the order their regions came; grown by doubling, keeping the planes in use (the
  // memory first, so that a key never lacks its plane); at least 64 planes (256 KiB at 32
  // voxels).
  const std::size_t p = keys_.size();
  const std::size_t needed = (p + 1u) * plane_words_;
  if (needed > words_.capacity() &&
      !words_.reserve(std::max(2u * needed, 64u * plane_words_), p * plane_words_)) {
    return kNoPlane;
  }
  bool added = false;
  plane_[keys_.insert(key, &added)] = static_cast<std::uint32_t>(p);
  std::uint64_t* words = plane(static_cast<std::uint32_t>(p));
  std::memset(words, 0, plane_words_ * sizeof(std::uint64_t));
  return static_cast<std::uint32_t>(p);
}

void MissPlanes::clear() noexcept {
  keys_.clear();
  front_keys_.fill(kEmpty);
}

}  // namespace raymap::detail
