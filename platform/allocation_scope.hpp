// SPDX-License-Identifier: BSD-3-Clause
// Marks the steady-state loops of the real-time threads, so that a test can count heap
// allocations made there (and only there) and prove there are none.
#pragma once

#include <cstdint>

namespace raymap::platform {

/// @brief While one exists on a thread, the thread is in its real-time steady state: raymap's code
/// must not allocate. Nested scopes restore the previous state on exit.
/// Thread-safety: per thread (thread_local state). @rt allocates: no; wait-free.
class RealtimeScope {
 public:
  RealtimeScope() noexcept;
  ~RealtimeScope();
  RealtimeScope(const RealtimeScope&) = delete;
  RealtimeScope& operator=(const RealtimeScope&) = delete;

 private:
  int saved_;
};

/// @brief Around a call into a library that allocates internally by design (Cyclone DDS
/// serialises into its own buffers in dds_write and hands out samples from dds_take): those
/// allocations are the library's, not raymap's, and are not counted. A RealtimeScope inside it
/// (our callback called back by the library) counts again.
class ForeignScope {
 public:
  ForeignScope() noexcept;
  ~ForeignScope();
  ForeignScope(const ForeignScope&) = delete;
  ForeignScope& operator=(const ForeignScope&) = delete;

 private:
  int saved_;
};

/// @brief True inside a RealtimeScope and not inside a ForeignScope nested in it (for the
/// allocation-counting test's malloc hook). @rt wait-free; allocates: no.
bool inRealtimeScope() noexcept;

/// @brief Reads the process's count of allocations made inside RealtimeScopes so far.
using RealtimeAllocationCounter = std::uint64_t (*)() noexcept;

/// @brief A build whose malloc counts real-time allocations (the tests' allocation counter,
/// linked into raymapd_counted for tools/soak.sh) registers its reader here at start-up, and the
/// service reports the count in its diagnostics; production builds register none.
/// Thread-safety: any thread (an atomic pointer). @rt wait-free; allocates: no.
void registerRealtimeAllocationCounter(RealtimeAllocationCounter counter) noexcept;

/// @brief The registered reader, or nullptr when this build does not count.
/// @rt wait-free; allocates: no.
RealtimeAllocationCounter realtimeAllocationCounter() noexcept;

}  // namespace raymap::platform
