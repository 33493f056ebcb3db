// SPDX-License-Identifier: BSD-3-Clause
// Per-scan semantics on the CPU: one bit per voxel, "already updated in this batch".
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

namespace raymap::detail {

/// @brief The CPU backends' once-per-scan rule: two bits per voxel of every store slot for the
/// current batch (one scan): the *hit* plane, set when the voxel takes the scan's hit (hits come
/// first, so a set hit bit also means "occupied wins"), and the *miss* plane, set by every ray
/// that crosses the voxel. The misses are applied once per region at the end of the batch
/// (applyScanMisses: each voxel with a miss bit and no hit bit takes one miss).
///
/// Why a miss plane: the walk then only sets a bit per voxel crossed (an or into a word that
/// mostly stays in L1), where per ray it loads, updates and stores the occupancy, and where a
/// claim-as-you-go rule tested a bit and branched on it, then updated the occupancy of the first
/// crossing. Each voxel still takes at most one update per scan, so the map is the same bit for
/// bit as with any order of the updates (the device backends' scan marks included). Per scan ran
/// at 0.74-0.89 of per ray on one thread with the claim in the walk (docs/benchmarks.md).
///
/// Why bits and not the map's 32-bit scan-mark layer (which the device backends keep for their
/// atomic_max election): the marks cost 4 bytes per voxel that a CPU map must keep resident
/// (a per-scan map of the Ouster data peaked at 188 MB with them, 133 MB with a bit per voxel),
/// and a second cache line beside the occupancy for every voxel a walk crosses. A bit word covers
/// 64 voxels, 512 in one cache line.
///
/// A slot's planes are cleared lazily, when the slot is first used in a batch (its stamp is not
/// the batch's sequence), so a batch costs 8 KiB of clearing per region it touches and nothing
/// for the others. Memory: slots x region voxels / 4 bytes, reserved at construction and made
/// resident only for the slots that are used (1.6 % of a 16-byte voxel).
///
/// Thread-safety: beginBatch() and forEachSlotOfBatch() on one thread with no batch running.
/// During a batch, bitsFor() and the bits it returns may be used from several threads at once for
/// different slots; one slot's bits by one thread at a time (the parallel integrator's worker
/// applying the region). Real time: no allocation after construction.
class ScanBits {
 public:
  /// `slots`: the store's capacity; `region_voxels`: voxels along a region's edge.
  ScanBits(std::uint32_t slots, std::int32_t region_voxels);

  /// Starts a batch with the map's scan sequence. A sequence that does not grow (the map
  /// restarted its sequences) forgets every stamp, so old bits can never pass for new ones.
  void beginBatch(std::uint32_t sequence) noexcept;

  /// The hit plane of `slot` (region-local voxel i is bit i % 64 of word i / 64), all clear at
  /// the slot's first use in this batch; its miss plane follows it (missPlane()).
  std::uint64_t* bitsFor(std::uint32_t slot) noexcept;

  /// Words of one plane that hold voxels (the plane is padded to a whole cache line).
  std::size_t voxelWords() const noexcept { return voxel_words_; }
  /// Words that hold the voxels of a region `region_voxels` on an edge, one bit each.
  static std::size_t voxelWordsFor(std::int32_t region_voxels) noexcept {
    const auto n = static_cast<std::size_t>(region_voxels);
    return (n * n * n + 63u) / 64u;
  }
  /// The miss plane that follows the hit plane `hits` (from bitsFor()).
  std::uint64_t* missPlane(std::uint64_t* hits) const noexcept { return hits + words_per_slot_; }

  /// Calls fn(slot) for every slot whose planes were used in the current batch, in slot order.
  template <class Fn>
  void forEachSlotOfBatch(Fn&& fn) const {
    for (std::uint32_t slot = 0; slot < stamps_.size(); ++slot) {
      if (stamps_[slot] == sequence_) {
        fn(slot);
      }
    }
  }

  /// Sets voxel `i`'s hit bit; true when it was clear (the voxel's first hit in this batch).
  static bool claim(std::uint64_t* bits, std::uint32_t i) noexcept {
    std::uint64_t& word = bits[i >> 6u];
    const std::uint64_t bit = std::uint64_t{1} << (i & 63u);
    const bool first = (word & bit) == 0u;
    word |= bit;
    return first;
  }

  /// Sets voxel `i`'s bit in `misses` (a miss plane), without a test: the walk's whole cost.
  static void mark(std::uint64_t* misses, std::uint32_t i) noexcept {
    misses[i >> 6u] |= std::uint64_t{1} << (i & 63u);
  }

 private:
  std::size_t voxel_words_;     ///< per plane, holding voxels
  std::size_t words_per_slot_;  ///< per plane, padded
  std::uint32_t sequence_ = 0;
  std::vector<std::uint32_t> stamps_;  ///< per slot: the sequence its bits were cleared for
  std::unique_ptr<std::uint64_t[]> storage_;
  std::uint64_t* words_ = nullptr;  ///< slot 0's first word: storage_ aligned to a cache line
};

}  // namespace raymap::detail
