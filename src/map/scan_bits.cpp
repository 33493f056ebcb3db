// SPDX-License-Identifier: BSD-3-Clause
#include "src/map/scan_bits.hpp"

#include <algorithm>
#include <cstring>
#include <memory>

namespace raymap::detail {
namespace {

/// Bit words of one region, rounded up to a 64-byte line so that two slots' words never share
/// one (two workers own two slots).
constexpr std::size_t kLineBytes = 64;

std::size_t wordsPerSlot(std::int32_t region_voxels) {
  const std::size_t words = ScanBits::voxelWordsFor(region_voxels);
  constexpr std::size_t kLineWords = kLineBytes / sizeof(std::uint64_t);
  return (words + kLineWords - 1u) / kLineWords * kLineWords;
}

}  // namespace

ScanBits::ScanBits(std::uint32_t slots, std::int32_t region_voxels)
    : voxel_words_(ScanBits::voxelWordsFor(region_voxels)),
      words_per_slot_(wordsPerSlot(region_voxels)),
      stamps_(slots, 0u),
      // Default-initialised: pages of slots never used stay untouched (make_unique would zero
      // them all). Two planes per slot, and seven words more to start the first slot on a line.
      storage_(
          std::make_unique_for_overwrite<std::uint64_t[]>((2u * words_per_slot_ * slots) + 7u)) {
  void* start = storage_.get();
  std::size_t space = ((2u * words_per_slot_ * slots) + 7u) * sizeof(std::uint64_t);
  words_ = static_cast<std::uint64_t*>(
      std::align(kLineBytes, 2u * words_per_slot_ * slots * sizeof(std::uint64_t), start, space));
}

void ScanBits::beginBatch(std::uint32_t sequence) noexcept {
  if (sequence <= sequence_) {
    std::fill(stamps_.begin(), stamps_.end(), 0u);  // sequences start at 1: 0 is "never"
  }
  sequence_ = sequence;
}

std::uint64_t* ScanBits::bitsFor(std::uint32_t slot) noexcept {
  std::uint64_t* bits = words_ + (std::size_t{slot} * 2u * words_per_slot_);
  if (stamps_[slot] != sequence_) {
    std::memset(bits, 0, 2u * words_per_slot_ * sizeof(std::uint64_t));  // both planes
    stamps_[slot] = sequence_;
  }
  return bits;
}

}  // namespace raymap::detail
