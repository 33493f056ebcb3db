// SPDX-License-Identifier: BSD-3-Clause
// Per-scan semantics on the CPU: one bit per voxel, "already updated in this batch".
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

namespace raymap::detail {

/// @brief The CPU backends' once-per-scan election: a bit per voxel of every store slot, set when
/// the voxel takes its hit or miss in the current batch (one scan; hits come first, so a set bit
/// also means "occupied wins").
///
/// Why bits and not the map's 32-bit scan-mark layer (which the device backends keep for their
/// atomic_max election): the marks cost 4 bytes per voxel that a CPU map must keep resident
/// (a per-scan map of the Ouster data peaked at 188 MB with them, 133 MB with the bits), and a
/// second cache line beside the occupancy for every voxel a walk crosses. A bit word covers 64
/// voxels, 512 in one cache line, so the bits of a ray's voxels mostly stay in L1. The speed did
/// not change measurably (per scan 0.74-0.89 of per ray on one thread, before and after; a
/// diagnostic build without the hit pass ran at 0.89-0.92, so the claims and the hit pass each
/// cost a few per cent; docs/benchmarks.md).
///
/// A slot's bits are cleared lazily, when the slot is first used in a batch (its stamp is not
/// the batch's sequence), so a batch costs 4 KiB of clearing per region it touches and nothing
/// for the others. Memory: slots x region voxels / 8 bytes, reserved at construction and made
/// resident only for the slots that are used (0.8 % of a 16-byte voxel).
///
/// Thread-safety: beginBatch() on one thread with no batch running. During a batch, bitsFor()
/// and the bits it returns may be used from several threads at once for different slots; one
/// slot's bits by one thread at a time (the parallel integrator's owner of the region). Real
/// time: no allocation after construction.
class ScanBits {
 public:
  /// `slots`: the store's capacity; `region_voxels`: voxels along a region's edge.
  ScanBits(std::uint32_t slots, std::int32_t region_voxels);

  /// Starts a batch with the map's scan sequence. A sequence that does not grow (the map
  /// restarted its sequences) forgets every stamp, so old bits can never pass for new ones.
  void beginBatch(std::uint32_t sequence) noexcept;

  /// The bit words of `slot` (region-local voxel i is bit i % 64 of word i / 64), all clear at
  /// the slot's first use in this batch.
  std::uint64_t* bitsFor(std::uint32_t slot) noexcept;

  /// Sets voxel `i`'s bit; true when it was clear (the voxel's first update in this batch).
  static bool claim(std::uint64_t* bits, std::uint32_t i) noexcept {
    std::uint64_t& word = bits[i >> 6u];
    const std::uint64_t bit = std::uint64_t{1} << (i & 63u);
    const bool first = (word & bit) == 0u;
    word |= bit;
    return first;
  }

 private:
  std::size_t words_per_slot_;
  std::uint32_t sequence_ = 0;
  std::vector<std::uint32_t> stamps_;  ///< per slot: the sequence its bits were cleared for
  std::unique_ptr<std::uint64_t[]> storage_;
  std::uint64_t* words_ = nullptr;  ///< slot 0's first word: storage_ aligned to a cache line
};

}  // namespace raymap::detail
