// SPDX-License-Identifier: BSD-3-Clause
// PendingScans: a fixed ring of held DDS samples.
#include "src/service/pending_scans.hpp"

#include <utility>

#include "raymap/assert.hpp"

namespace raymap::service {

PendingScans::PendingScans(std::uint32_t capacity)
    : capacity_(capacity), ring_(std::make_unique<Entry[]>(capacity > 0 ? capacity : 1)) {}

bool PendingScans::push(std::uint32_t sensor, std::int64_t arrival_ns,
                        dds::HeldSample&& sample) noexcept {
  RAYMAP_EXPECTS(capacity_ > 0);
  bool dropped = false;
  std::uint32_t size = size_.load(std::memory_order_relaxed);
  if (size == capacity_) {
    ring_[head_].sample.reset();  // the oldest, given back undecoded
    head_ = (head_ + 1) % capacity_;
    --size;
    dropped = true;
  }
  Entry& entry = ring_[(head_ + size) % capacity_];
  entry.sensor = sensor;
  entry.arrival_ns = arrival_ns;
  entry.sample = std::move(sample);
  // Sequentially consistent: the first store of a store-buffering pair with the integrator's
  // release (src/service/scan_handoff.hpp, where the fences and the argument are): the ingest
  // thread then looks at the mailbox, the integrator releases a slot and then reads this size;
  // one of the two sees the other (no wake-up is lost between a push and a release). The ring's
  // entries themselves are the ingest thread's alone.
  size_.store(size + 1, std::memory_order_seq_cst);
  return dropped;
}

PendingScans::Entry PendingScans::pop() noexcept {
  const std::uint32_t size = size_.load(std::memory_order_relaxed);
  RAYMAP_EXPECTS(size > 0);
  Entry out = std::move(ring_[head_]);
  head_ = (head_ + 1) % capacity_;
  // A smaller size only spares the integrator a wake-up; seq_cst as push() for simplicity.
  size_.store(size - 1, std::memory_order_seq_cst);
  return out;
}

void PendingScans::clear() noexcept {
  while (size() > 0) {
    pop().sample.reset();
  }
}

}  // namespace raymap::service
