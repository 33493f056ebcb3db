// SPDX-License-Identifier: BSD-3-Clause
// Real-time thread set-up and memory locking on Linux (pthread scheduling, affinity, mlockall).
#include "platform/rt.hpp"

#include <cerrno>
#include <cstring>
#include <limits>

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/resource.h>

namespace raymap::platform {

const char* toString(RtOutcome outcome) noexcept {
  switch (outcome) {
    case RtOutcome::kNotRequested:
      return "not-requested";
    case RtOutcome::kApplied:
      return "applied";
    case RtOutcome::kRefused:
      return "refused";
  }
  return "unknown";
}

RtStatus applyRealtime(const RtRequest& request) noexcept {
  RtStatus status;
  if (request.cpu_mask != 0) {
    // Affinity first: a thread that becomes SCHED_FIFO should already be on its CPUs.
    cpu_set_t set;
    CPU_ZERO(&set);
    for (unsigned cpu = 0; cpu < 64u && cpu < static_cast<unsigned>(CPU_SETSIZE); ++cpu) {
      if ((request.cpu_mask >> cpu) & 1u) {
        CPU_SET(cpu, &set);
      }
    }
    const int rc = pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
    status.affinity = rc == 0 ? RtOutcome::kApplied : RtOutcome::kRefused;
    status.affinity_errno = rc;
  }
  if (request.priority != 0) {
    const int lowest = sched_get_priority_min(SCHED_FIFO);
    const int highest = sched_get_priority_max(SCHED_FIFO);
    if (request.priority < lowest || request.priority > highest) {
      status.scheduling = RtOutcome::kRefused;
      status.scheduling_errno = EINVAL;
    } else {
      sched_param param{};
      param.sched_priority = request.priority;
      // pthread_setschedparam returns the error number instead of setting errno.
      const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
      status.scheduling = rc == 0 ? RtOutcome::kApplied : RtOutcome::kRefused;
      status.scheduling_errno = rc;
    }
  }
  return status;
}

void nameCurrentThread(const char* name) noexcept {
  if (name == nullptr) {
    return;
  }
  // The kernel keeps 15 characters and a NUL; pthread_setname_np would refuse (ERANGE) a longer
  // name instead of truncating it.
  char truncated[16] = {};
  std::strncpy(truncated, name, sizeof(truncated) - 1);
  (void)pthread_setname_np(pthread_self(), truncated);
}

MemoryLockStatus lockMemory() noexcept {
  MemoryLockStatus status;
  rlimit limit{};
  if (getrlimit(RLIMIT_MEMLOCK, &limit) != 0) {
    status.error_no = errno;
    return status;
  }
  if (limit.rlim_cur == RLIM_INFINITY) {
    status.limit_bytes = std::numeric_limits<std::uint64_t>::max();
  } else {
    status.limit_bytes = static_cast<std::uint64_t>(limit.rlim_cur);
    // MCL_FUTURE under a finite limit makes every later mmap/brk/stack beyond it fail: refuse.
    status.error_no = ENOMEM;
    return status;
  }
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    status.error_no = errno;
    return status;
  }
  status.locked = true;
  return status;
}

}  // namespace raymap::platform
