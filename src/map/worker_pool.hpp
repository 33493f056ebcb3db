// SPDX-License-Identifier: BSD-3-Clause
// A fixed set of worker threads that run one job on every worker and wait for all of them.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

namespace raymap {

/// @brief Runs `job(worker)` on workers 0..size()-1 at once; the calling thread is worker 0.
///
/// Design: size()-1 threads are started in the constructor and sleep on a condition variable.
/// run() publishes the job under the mutex with a new generation number, runs worker 0 itself and
/// waits until the pending count drops to zero. Jobs must not throw.
/// Thread-safety: run() must not be called concurrently. Not real-time: run() takes a mutex and
/// wakes threads (fine at batch granularity, milliseconds per call).
class WorkerPool {
 public:
  explicit WorkerPool(unsigned workers);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  unsigned size() const noexcept { return static_cast<unsigned>(threads_.size()) + 1u; }

  template <class Fn>
  void run(Fn& job) {
    runErased([](void* context, unsigned worker) { (*static_cast<Fn*>(context))(worker); }, &job);
  }

 private:
  using Trampoline = void (*)(void*, unsigned);
  void runErased(Trampoline trampoline, void* context);
  void workerLoop(unsigned worker);

  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable start_;
  std::condition_variable done_;
  Trampoline trampoline_ = nullptr;
  void* context_ = nullptr;
  std::uint64_t generation_ = 0;
  unsigned pending_ = 0;
  bool stop_ = false;
};

}  // namespace raymap
