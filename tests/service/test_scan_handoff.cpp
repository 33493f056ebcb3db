// SPDX-License-Identifier: BSD-3-Clause
// raymapd's hand-over of held scans between its ingest thread and its integrator
// (src/service/scan_handoff.hpp) under stress: its own pieces (ScanMailbox, PendingScans,
// Wakeup, the hand-over functions) on two threads that do nothing else, so that the race
// between a push and a release recurs thousands of times a second. No DDS: it is here, beside
// raymapd's end-to-end tests, because it needs the service library and runs in the
// ThreadSanitizer build with them (docs/arm64.md, "Memory ordering").
#include <atomic>
#include <chrono>
#include <cstdint>
#include <thread>

#include <gtest/gtest.h>

#include "platform/clock.hpp"
#include "platform/wakeup.hpp"
#include "src/pipeline/scan_mailbox.hpp"
#include "src/service/pending_scans.hpp"
#include "src/service/scan_handoff.hpp"

namespace raymap::service {
namespace {

constexpr std::int64_t kNsPerS = 1'000'000'000;

/// The integrator's release listener, as raymapd's: wake the ingest thread while scans are held.
struct HandOffWake {
  const PendingScans* pending;
  platform::Wakeup* ingest;
  static void onRelease(void* context) noexcept {
    auto* self = static_cast<HandOffWake*>(context);
    if (heldScansWait(*self->pending)) {
      self->ingest->notify();
    }
  }
};

struct HandOffCounts {
  std::uint64_t taken = 0;
  std::uint64_t out_of_order = 0;
  std::uint64_t stranded = 0;  // waits that ended without a wake-up while scans were held
  std::uint64_t acquire_failed = 0;
};

TEST(ScanHandOff, AHeldScanIsNeverStrandedWhileTheIntegratorIdles) {
  // Scan k carries k as its arrival time. Every 4th scan the ingest thread stops receiving and
  // waits for the integrator instead (with raymapd's Wakeup): only the release listener can
  // bring it back, so a wake-up lost between its push and the integrator's release strands the
  // held scans; the wait's 20 s bound (never reached otherwise) turns that into a failure.
  constexpr std::int64_t kScans = 20000;
  pipeline::ScanMailbox mailbox(3, 1);
  PendingScans pending(4);
  platform::Wakeup ingest_wake;
  HandOffWake wake{&pending, &ingest_wake};
  mailbox.setReleaseListener(&HandOffWake::onRelease, &wake);
  HandOffCounts counts;
  std::atomic<bool> received_all{false};

  std::thread integrator([&] {
    std::int64_t previous = -1;
    for (;;) {
      const bool last_round = received_all.load(std::memory_order_acquire);
      pipeline::ScanSlot* slot = mailbox.take();
      if (slot == nullptr) {
        if (last_round) {
          return;  // everything was published before received_all: nothing more comes
        }
        std::this_thread::yield();
        continue;
      }
      counts.out_of_order += slot->arrival_ns > previous ? 0 : 1;
      previous = slot->arrival_ns;
      ++counts.taken;
      mailbox.release(slot);
    }
  });

  const auto decode = [&](std::int64_t scan) {
    pipeline::ScanSlot* slot = mailbox.acquire();
    if (slot == nullptr) {
      ++counts.acquire_failed;
      return;
    }
    slot->arrival_ns = scan;
    slot->header.points = 1;
    mailbox.publish(slot);
  };
  const auto decode_pending = [&] {  // Service::Impl::decodePending
    decodeHeldWhileReady(pending, mailbox,
                         [&](PendingScans::Entry next) { decode(next.arrival_ns); });
  };
  for (std::int64_t scan = 0; scan < kScans && counts.stranded == 0; ++scan) {
    if (integratorBusy(pending, mailbox)) {  // Service::Impl::receiveCloud
      if (pending.push(0, scan, dds::HeldSample{})) {
        mailbox.noteDroppedUndecoded();
      }
    } else {
      decode(scan);
    }
    decode_pending();
    while (scan % 4 == 3 && pending.size() > 0) {
      if (!ingest_wake.waitUntilMonotonicNs(platform::monotonicNowNs() + 20 * kNsPerS)) {
        ++counts.stranded;
        break;
      }
      decode_pending();
    }
  }
  received_all.store(true, std::memory_order_release);
  integrator.join();

  EXPECT_EQ(counts.stranded, 0U) << "held scans waited 20 s for a wake-up that never came";
  EXPECT_EQ(counts.out_of_order, 0U);
  EXPECT_EQ(counts.acquire_failed, 0U);
  // Each scan was integrated or dropped, oldest first (held or decoded): none vanished.
  EXPECT_EQ(pending.size(), 0U);
  EXPECT_EQ(counts.taken + mailbox.droppedOldest(), static_cast<std::uint64_t>(kScans))
      << "taken " << counts.taken << ", dropped " << mailbox.droppedOldest() << " ("
      << mailbox.droppedUndecoded() << " undecoded)";
  EXPECT_GT(counts.taken, 0U);
}

}  // namespace
}  // namespace raymap::service
