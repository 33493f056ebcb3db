// SPDX-License-Identifier: BSD-3-Clause
// InterruptCleanup: fixed static slots that a signal handler unlinks, then the default action.
#include "platform/interrupt_cleanup.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <csignal>  // sigaction, sigprocmask and raise (POSIX, declared through <signal.h>)
#include <cstddef>
#include <cstring>

#include <unistd.h>

namespace raymap::platform {
namespace {

constexpr int kSlots = 32;
constexpr std::size_t kPathBytes = 4096;
constexpr std::size_t kCommandBytes = 32;
constexpr std::array<int, 3> kSignals = {SIGINT, SIGTERM, SIGHUP};

// Slot states. kFilling keeps a half-copied path away from the handler.
constexpr int kFree = 0;
constexpr int kFilling = 1;
constexpr int kRegistered = 2;

struct Slot {
  std::atomic<int> state{kFree};
  char path[kPathBytes] = {};
};

// Static storage only: the handler may run on any thread at any moment, so it must not
// allocate, lock or follow pointers that another thread frees.
Slot g_slots[kSlots];
char g_command[kCommandBytes] = "raymap";
std::atomic<bool> g_installed{false};
std::atomic<int> g_deferrals{0};
std::atomic<int> g_pending{0};  // a signal that arrived during a deferral

void say(const char* text) noexcept {
  const ssize_t ignored = ::write(STDERR_FILENO, text, std::strlen(text));
  static_cast<void>(ignored);
}

const char* signalName(int signal_number) noexcept {
  switch (signal_number) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    case SIGHUP:
      return "SIGHUP";
    default:
      return "a signal";
  }
}

/// Restores the default action and delivers the signal again: the process ends as it would have
/// without the handler, so its parent sees the signal.
[[noreturn]] void endBy(int signal_number) noexcept {
  struct sigaction action {};
  action.sa_handler = SIG_DFL;
  sigemptyset(&action.sa_mask);
  ::sigaction(signal_number, &action, nullptr);
  sigset_t only;
  sigemptyset(&only);
  sigaddset(&only, signal_number);
  ::pthread_sigmask(SIG_UNBLOCK, &only, nullptr);
  ::raise(signal_number);
  ::_exit(128 + signal_number);  // not reached: the default action of these signals ends us
}

void onSignal(int signal_number) {
  if (g_deferrals.load() > 0) {
    g_pending.store(signal_number);
    return;
  }
  int removed = 0;
  for (Slot& slot : g_slots) {
    if (slot.state.load(std::memory_order_acquire) == kRegistered && ::unlink(slot.path) == 0) {
      ++removed;
    }
  }
  say(g_command);
  say(": interrupted by ");
  say(signalName(signal_number));
  say(removed > 0 ? ": removed its unfinished (temporary) output files\n" : "\n");
  endBy(signal_number);
}

void installOnce() noexcept {
  if (g_installed.exchange(true)) {
    return;
  }
  for (const int signal_number : kSignals) {
    struct sigaction old {};
    if (::sigaction(signal_number, nullptr, &old) != 0 || old.sa_handler == SIG_IGN) {
      continue;  // ignored on purpose (nohup): stays ignored
    }
    struct sigaction action {};
    action.sa_handler = onSignal;
    sigemptyset(&action.sa_mask);
    for (const int other : kSignals) {
      sigaddset(&action.sa_mask, other);  // one handler at a time
    }
    ::sigaction(signal_number, &action, nullptr);
  }
}

}  // namespace

int InterruptCleanup::add(const std::string& command, const std::string& path) noexcept {
  if (path.size() >= kPathBytes) {
    return -1;
  }
  for (int i = 0; i < kSlots; ++i) {
    int expected = kFree;
    if (!g_slots[i].state.compare_exchange_strong(expected, kFilling)) {
      continue;
    }
    std::memcpy(g_slots[i].path, path.c_str(), path.size() + 1);
    g_slots[i].state.store(kRegistered, std::memory_order_release);
    if (!g_installed.load()) {
      const std::string name = "raymap " + command;
      const std::size_t n = std::min(name.size(), kCommandBytes - 1);
      std::memcpy(g_command, name.data(), n);
      g_command[n] = '\0';
      installOnce();
    }
    return i;
  }
  return -1;
}

void InterruptCleanup::remove(int slot) noexcept {
  if (slot >= 0 && slot < kSlots) {
    g_slots[slot].state.store(kFree, std::memory_order_release);
  }
}

InterruptCleanup::Deferral::Deferral() noexcept { g_deferrals.fetch_add(1); }

InterruptCleanup::Deferral::~Deferral() {
  if (g_deferrals.fetch_sub(1) == 1) {
    const int pending = g_pending.exchange(0);
    if (pending != 0) {
      say(g_command);
      say(": interrupted by ");
      say(signalName(pending));
      say(" while putting its outputs in place; they are complete\n");
      endBy(pending);
    }
  }
}

}  // namespace raymap::platform
