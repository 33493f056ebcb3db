// SPDX-License-Identifier: BSD-3-Clause
// Staging memory for region moves between the host store and a device cache, so that neither
// direction waits for the device: an upload is copied into the staging ring and sent from there,
// a download lands there and reaches the host store once the device is known to be past it.
// API-agnostic (OpenCL and CUDA).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory_resource>
#include <vector>

namespace raymap::gpu {

/// @brief A ring of staging memory for region copies, freed batch by batch.
///
/// Every copy takes space tagged with the number of the first batch whose completion the device
/// reaches after it (the batch being planned when the copy is enqueued: copies and batches share
/// one in-order queue). When that batch has retired, complete() copies the downloads among them
/// into the host store and frees their space, oldest first. A download is therefore in the host
/// store only after its batch retired or after completeAll() (the backend calls it whenever it
/// has waited for the whole queue: synchronise(), a tier eviction, a host-side clear).
///
/// On CUDA the ring is page-locked memory (the backend's staging resource), which is what makes
/// copies asynchronous there (a copy to or from pageable memory waits); on OpenCL it frees the
/// host store from having to stay unchanged while a copy runs.
///
/// Thread-safety: none (the backend's integrating thread). Real-time: allocation-free after
/// construction; reserve() returns nullptr rather than wait when the ring is full.
class TransferStaging {
 public:
  /// `bytes` of staging (from `memory`); `host_slots`: the host store's slots (pending downloads
  /// are counted per slot). Throws std::bad_alloc.
  TransferStaging(std::size_t bytes, std::uint32_t host_slots, std::pmr::memory_resource* memory);

  /// @brief Space for one copy of `bytes` that the device passes before batch `batch` completes;
  /// nullptr when the ring holds no such space now (the caller waits for the device, calls
  /// completeAll() and asks again).
  std::byte* reserve(std::size_t bytes, std::uint64_t batch) noexcept;
  /// @brief The copy last reserved is a download of host store slot `host_slot`: `bytes` from
  /// `staged` go to `host` when it completes.
  void noteDownload(std::byte* staged, std::byte* host, std::size_t bytes,
                    std::uint32_t host_slot) noexcept;
  /// @brief The device has finished batch `batch` and everything before it: applies and frees
  /// the copies tagged up to it.
  void complete(std::uint64_t batch) noexcept;
  /// @brief The device's queue is empty: applies and frees every copy.
  void completeAll() noexcept;
  /// @brief A download into host store slot `host_slot` has not reached the host store yet.
  bool downloadPending(std::uint32_t host_slot) const noexcept { return pending_[host_slot] != 0; }
  /// @brief Where the newest download of `bytes` into `host` lands in the ring, or nullptr: a
  /// region wanted back before its download arrived is uploaded from there (the in-order queue
  /// runs the download first). Its space is then held until batch `batch` retires too.
  std::byte* stagedDownload(const std::byte* host, std::size_t bytes, std::uint64_t batch) noexcept;
  std::size_t capacity() const noexcept { return ring_.size(); }

 private:
  struct Copy {
    std::uint64_t batch = 0;
    std::size_t offset = 0;
    std::size_t bytes = 0;
    std::byte* host = nullptr;  // downloads: where the bytes go; uploads: nullptr
    std::uint32_t host_slot = 0;
  };
  void popOldest() noexcept;

  std::pmr::vector<std::byte> ring_;
  std::vector<Copy> copies_;  // a ring of records, oldest at first_copy_
  std::size_t first_copy_ = 0;
  std::size_t copy_count_ = 0;
  std::size_t head_ = 0;                // offset of the oldest live byte
  std::size_t tail_ = 0;                // where the next copy goes
  std::vector<std::uint16_t> pending_;  // per host store slot: downloads not yet applied
};

}  // namespace raymap::gpu
