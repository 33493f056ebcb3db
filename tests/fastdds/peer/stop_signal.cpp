// SPDX-License-Identifier: BSD-3-Clause
// The stop flag: a lock-free atomic, the only thing the handler touches.
#include "tests/fastdds/peer/stop_signal.hpp"

#include <atomic>
#include <csignal>  // and POSIX's sigaction, which glibc declares there too

namespace raymap::fastdds_peer {
namespace {

std::atomic<bool> g_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free);

void onStop(int /*signal*/) { g_stop.store(true); }

}  // namespace

void installStopHandlers() {
  struct sigaction action {};
  action.sa_handler = onStop;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGINT, &action, nullptr);
  ::sigaction(SIGTERM, &action, nullptr);
}

bool stopRequested() noexcept { return g_stop.load(); }

}  // namespace raymap::fastdds_peer
