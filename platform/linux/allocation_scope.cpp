// SPDX-License-Identifier: BSD-3-Clause
// RealtimeScope / ForeignScope: one thread_local word (initial-exec TLS: no allocation on first
// use, so a malloc hook may read it).
#include "platform/allocation_scope.hpp"

#include <atomic>

namespace raymap::platform {
namespace {

constexpr int kOutside = 0;
constexpr int kRealtime = 1;
constexpr int kForeign = 2;

// NOTE: initial-exec keeps the first access from calling __tls_get_addr (which may allocate)
// from inside a malloc hook.
thread_local int t_scope __attribute__((tls_model("initial-exec"))) = kOutside;

// Set once by a static initialiser before main, read by the diagnostics thread: acquire/release
// make the function it points to visible with it (the pointer is all there is).
std::atomic<RealtimeAllocationCounter> g_counter{nullptr};

}  // namespace

RealtimeScope::RealtimeScope() noexcept : saved_(t_scope) { t_scope = kRealtime; }
RealtimeScope::~RealtimeScope() { t_scope = saved_; }

ForeignScope::ForeignScope() noexcept : saved_(t_scope) {
  t_scope = t_scope == kOutside ? kOutside : kForeign;
}
ForeignScope::~ForeignScope() { t_scope = saved_; }

bool inRealtimeScope() noexcept { return t_scope == kRealtime; }

void registerRealtimeAllocationCounter(RealtimeAllocationCounter counter) noexcept {
  g_counter.store(counter, std::memory_order_release);
}

RealtimeAllocationCounter realtimeAllocationCounter() noexcept {
  return g_counter.load(std::memory_order_acquire);
}

}  // namespace raymap::platform
