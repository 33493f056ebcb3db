// SPDX-License-Identifier: BSD-3-Clause
// Scans held as received, undecoded, while the integrator is behind: the ingest side of
// dropping before decoding (docs/raymapd.md, "When the input is more than it can take").
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>

#include "src/dds/entities.hpp"

namespace raymap::service {

/// @brief A bounded first-in first-out ring of received, undecoded scans (Cyclone's own receive
/// buffers, held without a copy), dropping the oldest when full.
///
/// Why: under overload most scans never reach the map. Decoding each on arrival and then
/// dropping it from the mailbox wasted the decode (70-90 % of clouds at 5-10x the sensor's rate),
/// on a real-time thread. The ingest thread decodes a scan only when the integrator is ready for
/// it; until then scans wait here as received, in arrival order, and the oldest is given back
/// undecoded when a newer one does not fit. The scans that reach the map are the same as with
/// decoded scans dropped oldest-first.
///
/// Thread-safety: push/pop/clear from one thread (the ingest thread); size() from any thread
/// (the integrator reads it to decide whether to wake the ingest thread).
/// @rt push/pop: no allocation (a full ring gives the oldest buffer back to Cyclone, which
/// frees it); construction allocates.
class PendingScans {
 public:
  struct Entry {
    std::uint32_t sensor = 0;     ///< index of the sensor in the configuration
    std::int64_t arrival_ns = 0;  ///< monotonic clock when it was taken from DDS
    dds::HeldSample sample;       ///< the message as received
  };

  /// @brief A ring of `capacity` scans (0: none can be held; push() must not be called).
  explicit PendingScans(std::uint32_t capacity);

  /// @brief Appends a scan; when the ring is full the oldest is given back undecoded first.
  /// @return true when a scan was dropped to make room.
  bool push(std::uint32_t sensor, std::int64_t arrival_ns, dds::HeldSample&& sample) noexcept;
  /// @brief Removes and returns the oldest scan. @pre size() > 0
  Entry pop() noexcept;
  /// @brief Gives every held buffer back (shutdown).
  void clear() noexcept;

  std::uint32_t capacity() const noexcept { return capacity_; }
  /// @brief Scans held now (a snapshot when read from another thread).
  std::uint32_t size() const noexcept { return size_.load(std::memory_order_seq_cst); }

 private:
  std::uint32_t capacity_;
  std::unique_ptr<Entry[]> ring_;
  std::uint32_t head_ = 0;  // index of the oldest entry
  std::atomic<std::uint32_t> size_{0};
};

}  // namespace raymap::service
