// SPDX-License-Identifier: BSD-3-Clause
// What the ingest thread tells the integrator about poses: the base in the world at a time, or a
// sensor's (static) extrinsic.
#pragma once

#include <atomic>
#include <cstdint>
#include <type_traits>

#include <boost/lockfree/spsc_queue.hpp>

#include "src/core/vec3.hpp"
#include "src/io/trajectory.hpp"

namespace raymap::pipeline {

/// @brief One pose message, as plain data crossing the SPSC queue.
struct PoseUpdate {
  enum Kind : std::uint8_t {
    kBaseInWorld = 0,      ///< `pose` is the base frame in the world frame at `stamp_ns`
    kSensorExtrinsic = 1,  ///< `pose` is sensor `sensor` in the base frame (static)
  };
  std::int64_t stamp_ns = 0;  ///< the pose source's clock (header.stamp), nanoseconds
  io::Pose pose;
  std::uint32_t sensor = 0;
  Kind kind = kBaseInWorld;
};
// What the queue and the integrator need of an update: boost::lockfree::spsc_queue copy-constructs
// it into its ring (placement new) and copy-assigns it out, so T needs a default constructor and
// copy operations, not trivial copyability (only boost::lockfree::queue, the MPMC one, asks for
// that). io::Pose holds Eigen's fixed-size Vector3d and Quaterniond, whose copy operations are
// user-provided (so the type is not trivially copyable) but copy three and four doubles in
// place: no allocation, no exception, no lock. Trivially destructible, so popping runs no
// destructor either. No code memcpy's an update or shares one between threads outside the queue.
static_assert(std::is_default_constructible_v<PoseUpdate> &&
              std::is_copy_constructible_v<PoseUpdate> && std::is_copy_assignable_v<PoseUpdate>);
static_assert(std::is_trivially_destructible_v<PoseUpdate>);

/// @brief Bounded wait-free SPSC queue of pose updates (ingest -> integrator); the capacity is set
/// at construction (start-up). Full: the ingest thread drops the update and counts it.
/// Orderings are Boost.Lockfree's: push() copies the element in, then stores the write index with
/// release; pop() loads it with acquire before copying the element out (and the read index
/// likewise the other way), so an update crosses whole on any architecture. Stress test:
/// PoseQueueStress.* (tests/unit/concurrency).
using PoseQueue = boost::lockfree::spsc_queue<PoseUpdate>;

/// @brief The newest position of the base in the world, published by the integrator for the
/// publisher (which centres the window and the height map on it).
///
/// Design: a sequence lock with one writer. The writer makes the sequence odd, stores the fields
/// and makes it even again; a reader retries while the sequence is odd or changed under it. All
/// fields are atomics (relaxed) ordered by fences, so there is no data race.
/// @rt store: wait-free; load: lock-free (retries only while a store is in progress).
class LatestPosition {
 public:
  // Orderings (Boehm's seqlock, "Can Seqlocks Get Along with Programming Language Memory
  // Models?", 2012): the release fence after the odd store keeps the field stores after it; a
  // reader that sees any of them sees the sequence odd or changed after its acquire fence. The
  // even store's release pairs with the reader's first, acquire, load. arm64 reorders plain
  // stores freely, so neither may be relaxed. Stress test:
  // PipelineLatestPosition.ReaderNeverSeesATornPosition (tests/unit/concurrency).
  void store(std::int64_t stamp_ns, Vec3d position) noexcept {
    const std::uint64_t s = sequence_.load(std::memory_order_relaxed);  // one writer
    sequence_.store(s + 1, std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_release);
    stamp_ns_.store(stamp_ns, std::memory_order_relaxed);
    x_.store(position.x, std::memory_order_relaxed);
    y_.store(position.y, std::memory_order_relaxed);
    z_.store(position.z, std::memory_order_relaxed);
    sequence_.store(s + 2, std::memory_order_release);
  }
  /// @brief False until the first store.
  bool load(std::int64_t* stamp_ns, Vec3d* position) const noexcept {
    for (;;) {
      const std::uint64_t before = sequence_.load(std::memory_order_acquire);
      if (before == 0) {
        return false;
      }
      if ((before & 1u) != 0) {
        continue;
      }
      *stamp_ns = stamp_ns_.load(std::memory_order_relaxed);
      position->x = x_.load(std::memory_order_relaxed);
      position->y = y_.load(std::memory_order_relaxed);
      position->z = z_.load(std::memory_order_relaxed);
      std::atomic_thread_fence(std::memory_order_acquire);
      if (sequence_.load(std::memory_order_relaxed) == before) {
        return true;
      }
    }
  }

 private:
  std::atomic<std::uint64_t> sequence_{0};
  std::atomic<std::int64_t> stamp_ns_{0};
  std::atomic<double> x_{0.0};
  std::atomic<double> y_{0.0};
  std::atomic<double> z_{0.0};
};

/// @brief Arrival times (monotonic ns) of scans fully integrated, for the publisher's latency
/// measure (integrator -> publisher).
using ArrivalQueue = boost::lockfree::spsc_queue<std::int64_t>;

}  // namespace raymap::pipeline
