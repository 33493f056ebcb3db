// SPDX-License-Identifier: BSD-3-Clause
// The staging ring of region moves.
#include "src/device/staging/transfer_staging.hpp"

#include <algorithm>
#include <cstring>

#include "raymap/assert.hpp"

namespace raymap::gpu {
namespace {

// Copies in flight at most: a batch moves a few regions of a few layers each; past this the
// ring reports itself full.
constexpr std::size_t kMaxCopies = 4096;

}  // namespace

TransferStaging::TransferStaging(std::size_t bytes, std::uint32_t host_slots,
                                 std::pmr::memory_resource* memory)
    : ring_(bytes, std::byte{0}, memory), copies_(kMaxCopies), pending_(host_slots, 0) {}

std::byte* TransferStaging::reserve(std::size_t bytes, std::uint64_t batch) noexcept {
  if (copy_count_ == copies_.size() || bytes > ring_.size()) {
    return nullptr;
  }
  std::size_t offset = 0;
  if (copy_count_ == 0) {
    head_ = 0;
    tail_ = 0;
  } else if (tail_ > head_) {
    // Free: [tail_, end) and, wrapping, [0, head_).
    if (bytes <= ring_.size() - tail_) {
      offset = tail_;
    } else if (bytes <= head_) {
      offset = 0;
    } else {
      return nullptr;
    }
  } else if (tail_ < head_ && bytes <= head_ - tail_) {
    offset = tail_;  // wrapped: free is [tail_, head_)
  } else {
    return nullptr;  // tail_ == head_ with copies in flight: full
  }
  RAYMAP_DEBUG_ASSERT(copy_count_ == 0 ||
                      batch >= copies_[(first_copy_ + copy_count_ - 1) % copies_.size()].batch);
  Copy& c = copies_[(first_copy_ + copy_count_) % copies_.size()];
  c = Copy{batch, offset, bytes, nullptr, 0};
  ++copy_count_;
  tail_ = offset + bytes;
  return ring_.data() + offset;
}

void TransferStaging::noteDownload(std::byte* staged, std::byte* host, std::size_t bytes,
                                   std::uint32_t host_slot) noexcept {
  RAYMAP_EXPECTS(copy_count_ > 0);
  Copy& c = copies_[(first_copy_ + copy_count_ - 1) % copies_.size()];
  RAYMAP_EXPECTS(staged == ring_.data() + c.offset && bytes == c.bytes);
  c.host = host;
  c.host_slot = host_slot;
  ++pending_[host_slot];
}

std::byte* TransferStaging::stagedDownload(const std::byte* host, std::size_t bytes,
                                           std::uint64_t batch) noexcept {
  for (std::size_t k = copy_count_; k-- > 0;) {
    Copy& c = copies_[(first_copy_ + k) % copies_.size()];
    if (c.host == host && c.bytes == bytes) {
      // Held past its place in the ring: the copies behind it wait for it (space is freed oldest
      // first), which only delays them.
      c.batch = std::max(c.batch, batch);
      return ring_.data() + c.offset;
    }
  }
  return nullptr;
}

void TransferStaging::popOldest() noexcept {
  Copy& c = copies_[first_copy_];
  if (c.host != nullptr) {
    std::memcpy(c.host, ring_.data() + c.offset, c.bytes);
    --pending_[c.host_slot];
  }
  first_copy_ = (first_copy_ + 1) % copies_.size();
  --copy_count_;
  head_ = copy_count_ > 0 ? copies_[first_copy_].offset : tail_;
}

void TransferStaging::complete(std::uint64_t batch) noexcept {
  while (copy_count_ > 0 && copies_[first_copy_].batch <= batch) {
    popOldest();
  }
}

void TransferStaging::completeAll() noexcept {
  while (copy_count_ > 0) {
    popOldest();
  }
}

}  // namespace raymap::gpu
