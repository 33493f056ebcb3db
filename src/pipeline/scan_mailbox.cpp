// SPDX-License-Identifier: BSD-3-Clause
// ScanMailbox: slot states moved by compare-and-swap (see the header's design note).
#include "src/pipeline/scan_mailbox.hpp"

#include "raymap/assert.hpp"

namespace raymap::pipeline {

ScanMailbox::ScanMailbox(std::uint32_t slots, std::uint32_t max_points)
    : slot_count_(slots),
      max_points_(max_points),
      entries_(std::make_unique<Entry[]>(slots)),
      points_(std::make_unique<msgs::ScanPoint[]>(std::size_t{slots} * max_points)) {
  RAYMAP_EXPECTS(slots >= 2 && max_points >= 1);
  for (std::uint32_t i = 0; i < slots; ++i) {
    entries_[i].slot.buffer =
        std::span<msgs::ScanPoint>(points_.get() + std::size_t{i} * max_points, max_points);
  }
}

ScanMailbox::Entry& ScanMailbox::entryOf(ScanSlot* slot) noexcept {
  for (std::uint32_t i = 0; i < slot_count_; ++i) {
    if (&entries_[i].slot == slot) {
      return entries_[i];
    }
  }
  RAYMAP_EXPECTS(false && "slot does not belong to this mailbox");
  return entries_[0];
}

std::uint32_t ScanMailbox::oldestReady(std::uint64_t* sequence_out) const noexcept {
  std::uint32_t best = slot_count_;
  std::uint64_t best_sequence = 0;
  for (std::uint32_t i = 0; i < slot_count_; ++i) {
    // Acquire, pairing with publish()'s release: a slot seen ready shows the sequence stored
    // before it. A stale view of another slot (still writing, on any architecture) is caught
    // by take()'s second look, which comes after this acquire.
    if (entries_[i].state.load(std::memory_order_acquire) != kReady) {
      continue;
    }
    const std::uint64_t sequence = entries_[i].sequence.load(std::memory_order_relaxed);
    if (best == slot_count_ || sequence < best_sequence) {
      best = i;
      best_sequence = sequence;
    }
  }
  if (sequence_out != nullptr) {
    *sequence_out = best_sequence;
  }
  return best;
}

ScanSlot* ScanMailbox::acquire() noexcept {
  // Each failed CAS means the consumer just took that slot; it holds at most one, so a few
  // rounds always settle. The bound keeps the producer wait-free against a misbehaving consumer.
  for (std::uint32_t attempt = 0; attempt < 4 * slot_count_ + 4; ++attempt) {
    for (std::uint32_t i = 0; i < slot_count_; ++i) {
      std::uint32_t expected = kFree;
      // Acquire, pairing with release()'s release store: the consumer's reads of the scan it
      // gave back are done before the producer writes the next one into the slot.
      if (entries_[i].state.compare_exchange_strong(expected, kWriting,
                                                    std::memory_order_acquire)) {
        return &entries_[i].slot;
      }
    }
    const std::uint32_t oldest = oldestReady();
    if (oldest == slot_count_) {
      continue;  // nothing ready either: the consumer is releasing one right now
    }
    std::uint32_t expected = kReady;
    // Acquire: the slot may be one take() claimed and handed back (its release store), whose
    // reads must be done before the overwrite.
    if (entries_[oldest].state.compare_exchange_strong(expected, kWriting,
                                                       std::memory_order_acquire)) {
      // Relaxed: a count for reports; nothing is published through it.
      dropped_oldest_.fetch_add(1, std::memory_order_relaxed);
      return &entries_[oldest].slot;
    }
  }
  return nullptr;
}

void ScanMailbox::publish(ScanSlot* slot) noexcept {
  Entry& entry = entryOf(slot);
  RAYMAP_EXPECTS(entry.state.load(std::memory_order_relaxed) == kWriting);
  // next_sequence_ has one writer (this thread): relaxed. The scan, the slot's sequence and the
  // entry's sequence are published together by the release store of the state (the consumer's
  // acquire in oldestReady() or take()'s CAS pairs with it), on arm64 as on x86-64.
  const std::uint64_t sequence = next_sequence_.load(std::memory_order_relaxed);
  slot->sequence = sequence;
  entry.sequence.store(sequence, std::memory_order_relaxed);
  next_sequence_.store(sequence + 1, std::memory_order_relaxed);
  entry.state.store(kReady, std::memory_order_release);
}

void ScanMailbox::abandon(ScanSlot* slot) noexcept {
  Entry& entry = entryOf(slot);
  RAYMAP_EXPECTS(entry.state.load(std::memory_order_relaxed) == kWriting);
  // Release: the partly written scan is ordered before whoever acquires the free slot next.
  entry.state.store(kFree, std::memory_order_release);
}

void ScanMailbox::noteDroppedUndecoded() noexcept {
  dropped_oldest_.fetch_add(1, std::memory_order_relaxed);
  dropped_undecoded_.fetch_add(1, std::memory_order_relaxed);
}

ScanSlot* ScanMailbox::take() noexcept {
  for (std::uint32_t attempt = 0; attempt < 4 * slot_count_ + 4; ++attempt) {
    const std::uint32_t oldest = oldestReady();
    if (oldest == slot_count_) {
      return nullptr;
    }
    Entry& entry = entries_[oldest];
    // Relaxed: only compared after the CAS, which (acquire, pairing with publish()'s release)
    // makes the sequence of the scan it claimed visible to the re-read below.
    const std::uint64_t sequence = entry.sequence.load(std::memory_order_relaxed);
    std::uint32_t expected = kReady;
    if (entry.state.compare_exchange_strong(expected, kReading, std::memory_order_acquire)) {
      // Two races make the claimed scan not the oldest, and both are undone by handing it back
      // as ready and looking again: between the scan and the CAS the producer dropped this scan
      // and published a newer one in the same slot (ABA); or the scan passed a slot while the
      // producer was still writing a scan older than this one. The second look compares the
      // sequence it saw: re-reading the oldest slot's sequence afterwards could find it dropped
      // and refilled with a newer scan while a third slot, older than ours, still waited.
      std::uint64_t older_sequence = 0;
      const std::uint32_t older = oldestReady(&older_sequence);
      const bool still_oldest = older == slot_count_ || older_sequence > sequence;
      if (entry.sequence.load(std::memory_order_relaxed) == sequence && still_oldest) {
        return &entry.slot;
      }
      // Release, pairing with acquire()'s CAS when the producer drops this scan next.
      entry.state.store(kReady, std::memory_order_release);
    }
    // Otherwise the producer took it back as the oldest: look again.
  }
  return nullptr;
}

void ScanMailbox::release(ScanSlot* slot) noexcept {
  Entry& entry = entryOf(slot);
  RAYMAP_EXPECTS(entry.state.load(std::memory_order_relaxed) == kReading);
  // Release, pairing with acquire()'s CAS: the consumer's reads of the scan happen before the
  // producer's next writes into the slot.
  entry.state.store(kFree, std::memory_order_release);
  if (release_listener_ != nullptr) {
    // Pairs with the ingest thread's fence after it pushed a held scan (a store-buffering pair:
    // src/service/scan_handoff.hpp): the released state is visible to it, or the listener reads
    // the size it pushed.
    std::atomic_thread_fence(std::memory_order_seq_cst);
    release_listener_(release_listener_context_);
  }
}

// consumerHolds() and waiting(): relaxed snapshots. A caller that decides on them against
// another thread's store fences first (service/scan_handoff.hpp: integratorReadyForHeld).
bool ScanMailbox::consumerHolds() const noexcept {
  for (std::uint32_t i = 0; i < slot_count_; ++i) {
    if (entries_[i].state.load(std::memory_order_relaxed) == kReading) {
      return true;
    }
  }
  return false;
}

std::uint32_t ScanMailbox::waiting() const noexcept {
  std::uint32_t n = 0;
  for (std::uint32_t i = 0; i < slot_count_; ++i) {
    n += entries_[i].state.load(std::memory_order_relaxed) == kReady ? 1u : 0u;
  }
  return n;
}

}  // namespace raymap::pipeline
