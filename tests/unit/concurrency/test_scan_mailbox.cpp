// SPDX-License-Identifier: BSD-3-Clause
// ScanMailbox: hand-over order, drop-oldest overflow, abandon, counters, and a time-bounded
// producer/consumer stress test that checks every scan the consumer takes.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "src/pipeline/scan_mailbox.hpp"

namespace raymap::pipeline {
namespace {

/// Fills a slot with `n` points whose values all derive from `tag` (see checkPattern).
void writePattern(ScanSlot* slot, std::uint64_t tag, std::uint32_t n) {
  slot->header.stamp_ns = static_cast<std::int64_t>(tag);
  slot->header.points = n;
  slot->header.width = n;
  slot->header.height = 1;
  slot->sensor = static_cast<std::uint32_t>(tag % 3);
  slot->arrival_ns = static_cast<std::int64_t>(tag) * 7;
  for (std::uint32_t i = 0; i < n; ++i) {
    msgs::ScanPoint& p = slot->buffer[i];
    p.x = static_cast<float>(tag & 0xFFFFu);
    p.y = static_cast<float>(i);
    p.z = static_cast<float>((tag >> 16) & 0xFFFFu);
    p.time_s = static_cast<float>(n);
    p.intensity = static_cast<float>(i ^ 0x5Au);
    p.flags = static_cast<std::uint32_t>(tag * 2654435761u) ^ i;
  }
}

/// True when the slot holds exactly what writePattern(slot, tag, n) wrote.
bool checkPattern(const ScanSlot& slot, std::uint64_t tag) {
  if (slot.header.stamp_ns != static_cast<std::int64_t>(tag) ||
      slot.sensor != static_cast<std::uint32_t>(tag % 3) ||
      slot.arrival_ns != static_cast<std::int64_t>(tag) * 7) {
    return false;
  }
  const std::uint32_t n = slot.header.points;
  if (n == 0 || n > slot.buffer.size() || slot.header.width != n) {
    return false;
  }
  for (std::uint32_t i = 0; i < n; ++i) {
    const msgs::ScanPoint& p = slot.points()[i];
    if (p.x != static_cast<float>(tag & 0xFFFFu) || p.y != static_cast<float>(i) ||
        p.z != static_cast<float>((tag >> 16) & 0xFFFFu) || p.time_s != static_cast<float>(n) ||
        p.intensity != static_cast<float>(i ^ 0x5Au) ||
        p.flags != (static_cast<std::uint32_t>(tag * 2654435761u) ^ i)) {
      return false;
    }
  }
  return true;
}

/// Acquires, fills with writePattern(tag) and publishes one scan; returns its sequence.
std::uint64_t publishTagged(ScanMailbox& mailbox, std::uint64_t tag, std::uint32_t n = 4) {
  ScanSlot* slot = mailbox.acquire();
  EXPECT_NE(slot, nullptr);
  if (slot == nullptr) {
    return ~std::uint64_t{0};
  }
  writePattern(slot, tag, n);
  mailbox.publish(slot);
  return slot->sequence;
}

TEST(ScanMailbox, StartsEmpty) {
  ScanMailbox mailbox(4, 16);

  EXPECT_EQ(mailbox.capacity(), 4u);
  EXPECT_EQ(mailbox.maxPoints(), 16u);
  EXPECT_EQ(mailbox.take(), nullptr);
  EXPECT_EQ(mailbox.waiting(), 0u);
  EXPECT_EQ(mailbox.published(), 0u);
  EXPECT_EQ(mailbox.droppedOldest(), 0u);
}

TEST(ScanMailbox, EverySlotHasItsOwnBufferOfMaxPoints) {
  ScanMailbox mailbox(3, 10);
  std::vector<ScanSlot*> slots;

  for (int i = 0; i < 3; ++i) {
    ScanSlot* slot = mailbox.acquire();
    ASSERT_NE(slot, nullptr);
    slots.push_back(slot);
  }

  for (std::size_t i = 0; i < slots.size(); ++i) {
    EXPECT_EQ(slots[i]->buffer.size(), 10u);
    for (std::size_t j = i + 1; j < slots.size(); ++j) {
      EXPECT_NE(slots[i], slots[j]);
      const msgs::ScanPoint* a = slots[i]->buffer.data();
      const msgs::ScanPoint* b = slots[j]->buffer.data();
      EXPECT_TRUE(a + 10 <= b || b + 10 <= a) << "buffers " << i << " and " << j << " overlap";
    }
  }
  for (ScanSlot* slot : slots) {
    mailbox.abandon(slot);
  }
}

TEST(ScanMailbox, OneScanGoesThroughIntact) {
  ScanMailbox mailbox(2, 8);

  const std::uint64_t sequence = publishTagged(mailbox, 42, 8);
  EXPECT_EQ(mailbox.waiting(), 1u);
  ScanSlot* taken = mailbox.take();

  ASSERT_NE(taken, nullptr);
  EXPECT_EQ(sequence, 0u);
  EXPECT_EQ(taken->sequence, 0u);
  EXPECT_TRUE(checkPattern(*taken, 42));
  EXPECT_EQ(taken->points().size(), 8u);
  EXPECT_EQ(mailbox.waiting(), 0u);
  EXPECT_EQ(mailbox.take(), nullptr) << "one scan is taken once";
  mailbox.release(taken);
  EXPECT_EQ(mailbox.published(), 1u);
  EXPECT_EQ(mailbox.droppedOldest(), 0u);
}

TEST(ScanMailbox, ConsumerTakesOldestFirst) {
  ScanMailbox mailbox(4, 4);
  for (std::uint64_t tag = 100; tag < 103; ++tag) {
    publishTagged(mailbox, tag);
  }

  std::vector<std::uint64_t> sequences;
  std::vector<std::uint64_t> stamps;
  while (ScanSlot* slot = mailbox.take()) {
    sequences.push_back(slot->sequence);
    stamps.push_back(static_cast<std::uint64_t>(slot->header.stamp_ns));
    mailbox.release(slot);
  }

  EXPECT_EQ(sequences, (std::vector<std::uint64_t>{0, 1, 2}));
  EXPECT_EQ(stamps, (std::vector<std::uint64_t>{100, 101, 102}));
  EXPECT_EQ(mailbox.droppedOldest(), 0u);
}

TEST(ScanMailbox, FullMailboxDropsTheOldestWaitingScan) {
  ScanMailbox mailbox(3, 4);

  for (std::uint64_t tag = 0; tag < 5; ++tag) {  // 3 fit; the 4th and 5th replace 0 and 1
    publishTagged(mailbox, tag);
  }

  EXPECT_EQ(mailbox.published(), 5u);
  EXPECT_EQ(mailbox.droppedOldest(), 2u);
  EXPECT_EQ(mailbox.waiting(), 3u);
  std::vector<std::uint64_t> stamps;
  while (ScanSlot* slot = mailbox.take()) {
    EXPECT_TRUE(checkPattern(*slot, static_cast<std::uint64_t>(slot->header.stamp_ns)));
    EXPECT_EQ(slot->sequence, static_cast<std::uint64_t>(slot->header.stamp_ns));
    stamps.push_back(static_cast<std::uint64_t>(slot->header.stamp_ns));
    mailbox.release(slot);
  }
  EXPECT_EQ(stamps, (std::vector<std::uint64_t>{2, 3, 4}));
}

TEST(ScanMailbox, SlotHeldByTheConsumerIsNeverReused) {
  ScanMailbox mailbox(2, 4);
  publishTagged(mailbox, 7);
  ScanSlot* held = mailbox.take();
  ASSERT_NE(held, nullptr);

  // With the only other slot cycling, the producer keeps replacing its own newest scan.
  for (std::uint64_t tag = 8; tag < 12; ++tag) {
    ScanSlot* slot = mailbox.acquire();
    ASSERT_NE(slot, nullptr);
    EXPECT_NE(slot, held);
    writePattern(slot, tag, 4);
    mailbox.publish(slot);
  }

  EXPECT_TRUE(checkPattern(*held, 7)) << "the held scan was overwritten";
  EXPECT_EQ(mailbox.droppedOldest(), 3u);  // 8, 9, 10 replaced; 11 waits
  mailbox.release(held);
  ScanSlot* next = mailbox.take();
  ASSERT_NE(next, nullptr);
  EXPECT_TRUE(checkPattern(*next, 11));
  EXPECT_EQ(next->sequence, 4u);
  mailbox.release(next);
}

TEST(ScanMailbox, AbandonedSlotIsReusedAndNotCounted) {
  ScanMailbox mailbox(2, 4);

  for (int i = 0; i < 5; ++i) {  // more abandons than slots: each one came back
    ScanSlot* slot = mailbox.acquire();
    ASSERT_NE(slot, nullptr);
    mailbox.abandon(slot);
  }

  EXPECT_EQ(mailbox.published(), 0u);
  EXPECT_EQ(mailbox.droppedOldest(), 0u);
  EXPECT_EQ(mailbox.waiting(), 0u);
  EXPECT_EQ(mailbox.take(), nullptr);
  EXPECT_EQ(publishTagged(mailbox, 3), 0u) << "an abandoned slot uses no sequence number";
}

TEST(ScanMailbox, TheReleaseListenerHearsEveryReleaseAndTheConsumerIsSeenHolding) {
  ScanMailbox mailbox(3, 4);
  int heard = 0;
  mailbox.setReleaseListener([](void* context) noexcept { ++*static_cast<int*>(context); }, &heard);
  EXPECT_FALSE(mailbox.consumerHolds());
  ScanSlot* slot = mailbox.acquire();
  mailbox.publish(slot);
  EXPECT_FALSE(mailbox.consumerHolds());  // published, not taken
  ScanSlot* taken = mailbox.take();
  ASSERT_NE(taken, nullptr);
  EXPECT_TRUE(mailbox.consumerHolds());
  EXPECT_EQ(heard, 0);
  mailbox.release(taken);
  EXPECT_FALSE(mailbox.consumerHolds());
  EXPECT_EQ(heard, 1);
}

TEST(ScanMailbox, ScansDroppedBeforeDecodingAreOverflowDrops) {
  ScanMailbox mailbox(3, 4);
  mailbox.noteDroppedUndecoded();
  mailbox.noteDroppedUndecoded();
  EXPECT_EQ(mailbox.droppedUndecoded(), 2U);
  EXPECT_EQ(mailbox.droppedOldest(), 2U);
  // A decoded scan overwritten in the mailbox counts in droppedOldest only.
  for (int i = 0; i < 4; ++i) {
    mailbox.publish(mailbox.acquire());
  }
  EXPECT_EQ(mailbox.droppedOldest(), 3U);
  EXPECT_EQ(mailbox.droppedUndecoded(), 2U);
}

TEST(ScanMailboxDeathTest, ReleasingASlotThatWasNotTakenAborts) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  ScanMailbox mailbox(2, 4);
  ScanSlot* slot = mailbox.acquire();
  ASSERT_NE(slot, nullptr);

  EXPECT_DEATH(mailbox.release(slot), "precondition");
}

TEST(ScanMailboxDeathTest, PublishingAForeignSlotAborts) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  ScanMailbox mailbox(2, 4);
  ScanMailbox other(2, 4);
  ScanSlot* foreign = other.acquire();
  ASSERT_NE(foreign, nullptr);

  EXPECT_DEATH(mailbox.publish(foreign), "precondition");
}

/// What the consumer of a stress run saw: it checks every scan it takes.
struct StressResult {
  std::uint64_t taken = 0;
  std::uint64_t corrupt = 0;
  std::uint64_t out_of_order = 0;  // a sequence not above the previous one taken
  std::uint64_t first_bad_previous = 0;
  std::uint64_t first_bad_sequence = 0;
  std::uint64_t acquire_failed = 0;
};

/// One producer and one consumer, each on its own thread, for `duration`, and on until the
/// consumer has taken some scans: on a loaded machine a thread may not run at all for that long.
StressResult runStress(std::uint32_t slots, std::chrono::milliseconds duration) {
  constexpr std::uint32_t kMaxPoints = 48;
  constexpr std::uint64_t kMinTaken = 100;
  ScanMailbox mailbox(slots, kMaxPoints);
  std::atomic<bool> stop{false};
  std::atomic<std::uint64_t> acquire_failed{0};
  std::atomic<std::uint64_t> taken_so_far{0};
  StressResult result;

  std::thread producer([&] {
    std::uint64_t tag = 0;  // = the sequence publish() assigns (one producer)
    while (!stop.load(std::memory_order_relaxed)) {
      ScanSlot* slot = mailbox.acquire();
      if (slot == nullptr) {
        acquire_failed.fetch_add(1, std::memory_order_relaxed);
        continue;
      }
      if (tag % 97 == 96) {  // now and then a malformed message
        mailbox.abandon(slot);
        ++tag;
        continue;
      }
      const std::uint64_t sequence = mailbox.published();
      writePattern(slot, sequence, 1 + static_cast<std::uint32_t>(tag % kMaxPoints));
      mailbox.publish(slot);
      ++tag;
    }
  });
  std::thread consumer([&] {
    bool have_previous = false;
    std::uint64_t previous = 0;
    while (!stop.load(std::memory_order_relaxed)) {
      ScanSlot* slot = mailbox.take();
      if (slot == nullptr) {
        std::this_thread::yield();
        continue;
      }
      ++result.taken;
      taken_so_far.store(result.taken, std::memory_order_relaxed);
      if (!checkPattern(*slot, slot->sequence)) {
        ++result.corrupt;
      }
      if (have_previous && slot->sequence <= previous) {
        if (result.out_of_order == 0) {
          result.first_bad_previous = previous;
          result.first_bad_sequence = slot->sequence;
        }
        ++result.out_of_order;
      }
      // Keep the newest sequence seen: one inversion is counted once, not for every later scan.
      if (!have_previous || slot->sequence > previous) {
        previous = slot->sequence;
      }
      have_previous = true;
      mailbox.release(slot);
    }
  });

  std::this_thread::sleep_for(duration);
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (taken_so_far.load(std::memory_order_relaxed) < kMinTaken &&
         std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  stop.store(true);
  producer.join();
  consumer.join();

  result.acquire_failed = acquire_failed.load();
  // Both threads have stopped: the counters are final.
  EXPECT_EQ(mailbox.published(), result.taken + mailbox.droppedOldest() + mailbox.waiting())
      << "published " << mailbox.published() << ", taken " << result.taken << ", dropped "
      << mailbox.droppedOldest() << ", waiting " << mailbox.waiting();
  EXPECT_GT(result.taken, 0u);
  EXPECT_GT(mailbox.published(), 0u);
  return result;
}

// Regression: take() once claimed a slot by CAS on its state alone, so a slot the producer had
// dropped and refilled between the scan and the CAS (ABA), or a scan passed while still being
// written, let a newer scan out before an older one. Sequences must come out in order.
TEST(ScanMailboxStress, ProducerAndConsumerKeepEveryScanIntactAndInOrder) {
  struct Case {
    std::uint32_t slots;
    int ms;
  };
  // About 200 ms in all; 5 slots is raymapd's default (queues.scan_slots 4, plus one in use).
  for (const Case c : {Case{2, 50}, Case{5, 75}, Case{8, 75}}) {
    const StressResult r = runStress(c.slots, std::chrono::milliseconds(c.ms));

    SCOPED_TRACE(::testing::Message() << c.slots << " slots");
    EXPECT_EQ(r.corrupt, 0u) << r.corrupt << " of " << r.taken
                             << " scans taken were not as published";
    EXPECT_EQ(r.out_of_order, 0u) << r.out_of_order << " of " << r.taken
                                  << " scans were taken out of sequence order (first: "
                                  << r.first_bad_sequence << " after " << r.first_bad_previous
                                  << ")";
    EXPECT_EQ(r.acquire_failed, 0u);
  }
}

}  // namespace
}  // namespace raymap::pipeline
