// SPDX-License-Identifier: BSD-3-Clause
// The hand-over of decoded scans from the DDS ingest thread to the integrator: a fixed set of
// preallocated scan buffers passed between exactly one producer and one consumer without locks,
// dropping the oldest waiting scan when the consumer falls behind.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <span>

#include "src/msgs/point_cloud.hpp"

namespace raymap::pipeline {

/// @brief One scan buffer: a decoded point cloud (sensor frame) and where it came from.
/// Owned by the mailbox; whoever holds it (see ScanMailbox) may read and write it freely.
struct ScanSlot {
  msgs::CloudHeader header{};         ///< stamp, frame and counts as decoded
  std::uint32_t sensor = 0;           ///< index of the sensor in the configuration
  std::int64_t arrival_ns = 0;        ///< monotonic clock when the message was taken from DDS
  std::uint64_t sequence = 0;         ///< order of publication (set by ScanMailbox::publish)
  std::span<msgs::ScanPoint> buffer;  ///< the slot's whole capacity
  /// The decoded points: the first header.points of buffer.
  std::span<const msgs::ScanPoint> points() const noexcept { return buffer.first(header.points); }
};

/// @brief A bounded single-producer single-consumer mailbox of scan buffers with a drop-oldest
/// overflow policy.
///
/// Design: `slots` buffers, each with an atomic state. Ownership moves by compare-and-swap, so
/// producer and consumer never wait for each other and never touch a slot the other holds:
///
///      producer                                  consumer
///   free --acquire--> writing --publish--> ready --take--> reading --release--> free
///                        ^                   |
///                        +--- acquire when no slot is free: the oldest ready slot
///                             (lowest sequence) is taken back and counted as dropped
///
/// publish() stores the sequence and then the state with release order; take() reads the state
/// with acquire order, so the consumer sees the whole scan. The consumer takes ready slots in
/// sequence order (oldest first). Capacity: with the consumer holding one slot, slots - 1 scans
/// can wait; at least 2 slots.
///
/// Thread-safety: exactly one producer thread calls acquire/publish/abandon, exactly one consumer
/// thread calls take/release; counters may be read from any thread.
/// @rt every method: lock-free (bounded retries), allocates: no, blocks: no.
class ScanMailbox {
 public:
  /// @brief Allocates `slots` buffers of `max_points` points each (start-up only).
  /// @pre slots >= 2, max_points >= 1
  ScanMailbox(std::uint32_t slots, std::uint32_t max_points);
  ~ScanMailbox() = default;
  ScanMailbox(const ScanMailbox&) = delete;
  ScanMailbox& operator=(const ScanMailbox&) = delete;

  // ---- producer ----
  /// @brief A slot to decode the next scan into: a free one, else the oldest waiting scan
  /// (dropped, counted). nullptr only when the consumer holds every other slot (never with
  /// slots >= 2 and a consumer that holds at most one). @rt producer thread.
  ScanSlot* acquire() noexcept;
  /// @brief Hands an acquired slot to the consumer. @rt producer thread.
  void publish(ScanSlot* slot) noexcept;
  /// @brief Returns an acquired slot unused (the message was malformed). @rt producer thread.
  void abandon(ScanSlot* slot) noexcept;
  /// @brief Counts a scan dropped before it was decoded (the producer held it as received
  /// while a decoded scan waited, and a newer one took its place: see PendingScans). It is an
  /// overflow drop like those of acquire(). @rt producer thread.
  void noteDroppedUndecoded() noexcept;

  /// @brief Called by the consumer after each release(): it is done with a scan and will want
  /// the next (the service wakes its ingest thread with it, to decode the oldest scan it holds
  /// as received). Set at start-up, before either thread runs; the function must not block and
  /// must not throw.
  using ReleaseListener = void (*)(void* context) noexcept;
  void setReleaseListener(ReleaseListener listener, void* context) noexcept {
    release_listener_ = listener;
    release_listener_context_ = context;
  }

  // ---- consumer ----
  /// @brief The oldest published scan, or nullptr when none waits. @rt consumer thread.
  ScanSlot* take() noexcept;
  /// @brief Gives a taken slot back for reuse. @rt consumer thread.
  void release(ScanSlot* slot) noexcept;

  // ---- any thread ----
  std::uint32_t capacity() const noexcept { return slot_count_; }
  std::uint32_t maxPoints() const noexcept { return max_points_; }
  /// @brief Scans published and not yet taken (a snapshot).
  std::uint32_t waiting() const noexcept;
  /// @brief Whether the consumer holds a scan it took and has not released (a snapshot).
  bool consumerHolds() const noexcept;
  /// @brief Scans dropped on overflow, oldest first: overwritten before the consumer took them,
  /// or dropped before they were decoded (noteDroppedUndecoded).
  std::uint64_t droppedOldest() const noexcept {
    return dropped_oldest_.load(std::memory_order_relaxed);
  }
  /// @brief Of droppedOldest(), those dropped before they were decoded.
  std::uint64_t droppedUndecoded() const noexcept {
    return dropped_undecoded_.load(std::memory_order_relaxed);
  }
  /// @brief Scans published so far.
  std::uint64_t published() const noexcept {
    return next_sequence_.load(std::memory_order_relaxed);
  }

 private:
  enum State : std::uint32_t { kFree = 0, kWriting = 1, kReady = 2, kReading = 3 };
  struct Entry {
    std::atomic<std::uint32_t> state{kFree};
    std::atomic<std::uint64_t> sequence{0};
    ScanSlot slot;
  };
  Entry& entryOf(ScanSlot* slot) noexcept;
  /// Index of the ready entry with the lowest sequence, or slot_count_ when none is ready; its
  /// sequence as read during the scan goes to `*sequence` when given.
  std::uint32_t oldestReady(std::uint64_t* sequence = nullptr) const noexcept;

  std::uint32_t slot_count_;
  std::uint32_t max_points_;
  std::unique_ptr<Entry[]> entries_;
  std::unique_ptr<msgs::ScanPoint[]> points_;
  std::atomic<std::uint64_t> next_sequence_{0};  // written by the producer only
  std::atomic<std::uint64_t> dropped_oldest_{0};
  std::atomic<std::uint64_t> dropped_undecoded_{0};
  ReleaseListener release_listener_ = nullptr;
  void* release_listener_context_ = nullptr;
};

}  // namespace raymap::pipeline
