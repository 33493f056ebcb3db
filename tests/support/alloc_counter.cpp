// SPDX-License-Identifier: BSD-3-Clause
// The malloc interposition behind AllocationScope: glibc lets an executable replace malloc,
// free, calloc and realloc; ours count and forward to glibc's own (__libc_*).
#include "tests/support/alloc_counter.hpp"

#include <atomic>
#include <cstddef>
#include <cstdlib>

#include <execinfo.h>
#include <unistd.h>

#include "platform/allocation_scope.hpp"

namespace raymap::test {
namespace {
thread_local std::uint64_t t_allocations = 0;
thread_local int t_scopes = 0;
std::atomic<std::uint64_t> g_realtime_allocations{0};
}  // namespace

std::uint64_t realtimeAllocations() noexcept {
  return g_realtime_allocations.load(std::memory_order_relaxed);
}

#if defined(RAYMAP_SANITIZED_BUILD)
bool allocationCountingAvailable() noexcept { return false; }
void noteAllocation() noexcept {}
#else
/// RAYMAP_ALLOC_TRACE=1: a backtrace on stderr for each real-time allocation (symbolise the
/// addresses with addr2line -f -C -e THE_TEST_EXECUTABLE), to find where one comes from.
void traceRealtimeAllocation() noexcept {
  static const bool enabled = [] {
    const char* trace = std::getenv("RAYMAP_ALLOC_TRACE");
    return trace != nullptr && trace[0] == '1';
  }();
  thread_local bool tracing = false;  // backtrace() may allocate once, on its first call
  if (!enabled || tracing) {
    return;
  }
  tracing = true;
  void* frames[32];
  const int n = backtrace(frames, 32);
  static const char kHeader[] = "real-time allocation:\n";
  (void)!write(2, kHeader, sizeof(kHeader) - 1);
  backtrace_symbols_fd(frames, n, 2);
  tracing = false;
}
bool allocationCountingAvailable() noexcept { return true; }

namespace {
// Tells the service (platform::realtimeAllocationCounter) that this executable counts, so that
// raymapd_counted reports realtime_allocations in its diagnostics for tools/soak.sh.
[[maybe_unused]] const bool g_registered = [] {
  platform::registerRealtimeAllocationCounter(&realtimeAllocations);
  return true;
}();
}  // namespace
void noteAllocation() noexcept {
  if (t_scopes > 0) {
    ++t_allocations;
  }
  if (platform::inRealtimeScope()) {
    g_realtime_allocations.fetch_add(1, std::memory_order_relaxed);
    traceRealtimeAllocation();
  }
}
#endif

AllocationScope::AllocationScope() noexcept : start_(t_allocations) { ++t_scopes; }
AllocationScope::~AllocationScope() { --t_scopes; }
std::uint64_t AllocationScope::count() const noexcept { return t_allocations - start_; }

}  // namespace raymap::test

#if !defined(RAYMAP_SANITIZED_BUILD)
extern "C" {
// glibc's allocator entry points (exported for exactly this use).
// NOLINTNEXTLINE(bugprone-reserved-identifier): glibc's name
void* __libc_malloc(std::size_t size);
// NOLINTNEXTLINE(bugprone-reserved-identifier): glibc's name
void __libc_free(void* p);
// NOLINTNEXTLINE(bugprone-reserved-identifier): glibc's name
void* __libc_calloc(std::size_t n, std::size_t size);
// NOLINTNEXTLINE(bugprone-reserved-identifier): glibc's name
void* __libc_realloc(void* p, std::size_t size);
// NOLINTNEXTLINE(bugprone-reserved-identifier): glibc's name
void* __libc_memalign(std::size_t alignment, std::size_t size);

void* malloc(std::size_t size) noexcept {
  raymap::test::noteAllocation();
  return __libc_malloc(size);
}
void free(void* p) noexcept { __libc_free(p); }
void* calloc(std::size_t n, std::size_t size) noexcept {
  raymap::test::noteAllocation();
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t size) noexcept {
  raymap::test::noteAllocation();
  return __libc_realloc(p, size);
}
void* memalign(std::size_t alignment, std::size_t size) noexcept {
  raymap::test::noteAllocation();
  return __libc_memalign(alignment, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) noexcept {
  raymap::test::noteAllocation();
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) noexcept {
  raymap::test::noteAllocation();
  void* p = __libc_memalign(alignment, size);
  if (p == nullptr) {
    return 12;  // ENOMEM
  }
  *out = p;
  return 0;
}
}
#endif
