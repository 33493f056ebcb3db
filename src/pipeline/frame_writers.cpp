// SPDX-License-Identifier: BSD-3-Clause
// FrameWriters: a few slots, the least recently seen one reused for a new writer.
#include "src/pipeline/frame_writers.hpp"

namespace raymap::pipeline {

// Relaxed throughout: writers() may read a slot's writer from one update and its time from
// another (a new writer with the old one's time, for one report), which a count for diagnostics
// tolerates; nothing else is published through the slots. seen() has one writer thread, so its
// own loads see its own stores. Stress test: FrameWritersStress.* (tests/unit/concurrency).
void FrameWriters::seen(std::uint64_t writer, std::int64_t now_ns) noexcept {
  Slot* oldest = &slots_[0];
  for (Slot& slot : slots_) {
    if (slot.writer.load(std::memory_order_relaxed) == writer) {
      slot.last_ns.store(now_ns, std::memory_order_relaxed);
      return;
    }
    if (slot.last_ns.load(std::memory_order_relaxed) <
        oldest->last_ns.load(std::memory_order_relaxed)) {
      oldest = &slot;
    }
  }
  oldest->writer.store(writer, std::memory_order_relaxed);
  oldest->last_ns.store(now_ns, std::memory_order_relaxed);
}

std::uint32_t FrameWriters::writers(std::int64_t now_ns, std::int64_t window_ns) const noexcept {
  std::uint32_t n = 0;
  for (const Slot& slot : slots_) {
    const std::int64_t last = slot.last_ns.load(std::memory_order_relaxed);
    n += slot.writer.load(std::memory_order_relaxed) != 0 && last != 0 && now_ns - last <= window_ns
             ? 1u
             : 0u;
  }
  return n;
}

}  // namespace raymap::pipeline
