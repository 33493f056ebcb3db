// SPDX-License-Identifier: BSD-3-Clause
// WorkerPool implementation.
#include "src/map/worker_pool.hpp"

#include <pthread.h>

namespace raymap {

WorkerPool::WorkerPool(unsigned workers) {
  const unsigned extra = workers > 1 ? workers - 1 : 0;
  threads_.reserve(extra);
  for (unsigned i = 0; i < extra; ++i) {
    threads_.emplace_back([this, i] { workerLoop(i + 1); });
  }
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  start_.notify_all();
  for (std::thread& t : threads_) {
    t.join();
  }
}

void WorkerPool::runErased(Trampoline trampoline, void* context) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    trampoline_ = trampoline;
    context_ = context;
    pending_ = static_cast<unsigned>(threads_.size());
    ++generation_;
  }
  start_.notify_all();
  trampoline(context, 0);
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [this] { return pending_ == 0; });
}

void WorkerPool::workerLoop(unsigned worker) {
  // Named, so that top -H and raymapd's benchmarks tell the CPU backend's helpers from the
  // thread that created them (they would otherwise carry the program's name).
  static_cast<void>(pthread_setname_np(pthread_self(), "raymap-worker"));
  std::uint64_t seen = 0;
  for (;;) {
    Trampoline trampoline = nullptr;
    void* context = nullptr;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      start_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) {
        return;
      }
      seen = generation_;
      trampoline = trampoline_;
      context = context_;
    }
    trampoline(context, worker);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      --pending_;
      if (pending_ == 0) {
        done_.notify_one();
      }
    }
  }
}

}  // namespace raymap
