// SPDX-License-Identifier: BSD-3-Clause
// A mutex with priority inheritance, for data shared between real-time threads of different
// SCHED_FIFO priorities (a low-priority holder is boosted while a high-priority thread waits, so
// a middle-priority thread cannot stall the high one indefinitely).
#pragma once

#include <pthread.h>

namespace raymap::platform {

/// @brief PTHREAD_PRIO_INHERIT mutex with std::mutex's interface (usable with std::lock_guard and
/// std::unique_lock). Thread-safety: a mutex. @rt lock/unlock allocate: no; lock blocks while
/// another thread holds it (bounded by that holder's critical section).
class PiMutex {
 public:
  PiMutex() noexcept {
    pthread_mutexattr_t attr;
    pthread_mutexattr_init(&attr);
    // NOTE: where the kernel lacks PI futexes this fails and the mutex stays a plain one.
    pthread_mutexattr_setprotocol(&attr, PTHREAD_PRIO_INHERIT);
    pthread_mutex_init(&mutex_, &attr);
    pthread_mutexattr_destroy(&attr);
  }
  ~PiMutex() { pthread_mutex_destroy(&mutex_); }
  PiMutex(const PiMutex&) = delete;
  PiMutex& operator=(const PiMutex&) = delete;

  void lock() noexcept { pthread_mutex_lock(&mutex_); }
  bool try_lock() noexcept {
    return pthread_mutex_trylock(&mutex_) == 0;
  }  // NOLINT(readability-identifier-naming): std::mutex's name
  void unlock() noexcept { pthread_mutex_unlock(&mutex_); }

 private:
  pthread_mutex_t mutex_{};  // initialised by pthread_mutex_init in the constructor
};

}  // namespace raymap::platform
