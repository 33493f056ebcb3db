// SPDX-License-Identifier: BSD-3-Clause
// Real-time set-up of the calling thread and the process: SCHED_FIFO, CPU affinity, thread
// names and memory locking. Every call reports refusal instead of failing hard.
#pragma once

#include <cstdint>

namespace raymap::platform {

/// @brief What a thread asks for at start-up (an aggregate of the service configuration).
struct RtRequest {
  int priority = 0;            ///< SCHED_FIFO priority 1..99; 0 = keep normal scheduling
  std::uint64_t cpu_mask = 0;  ///< bit i = may run on CPU i; 0 = any CPU (affinity untouched)
};

/// @brief The outcome of one part of an RtRequest.
enum class RtOutcome : std::uint8_t {
  kNotRequested,  ///< the request left this part alone
  kApplied,       ///< the kernel accepted it
  kRefused,       ///< the kernel refused it (see the errno); the thread runs as before
};

/// @brief Short, stable name of an outcome ("not-requested", "applied", "refused").
/// @rt wait-free; allocates: no; thread: any.
const char* toString(RtOutcome outcome) noexcept;

/// @brief What applyRealtime() achieved. The errno fields are 0 unless the part was refused.
struct RtStatus {
  RtOutcome scheduling = RtOutcome::kNotRequested;
  RtOutcome affinity = RtOutcome::kNotRequested;
  int scheduling_errno = 0;  ///< EPERM: no CAP_SYS_NICE and RLIMIT_RTPRIO too low, or RT group
                             ///< scheduling gives the cgroup no RT time; EINVAL: bad priority
  int affinity_errno = 0;    ///< EINVAL: no CPU of the mask is online / allowed
};

/// @brief Applies `request` to the calling thread: SCHED_FIFO at `priority` (when non-zero) and
/// the CPU mask (when non-zero). Never fails hard: a refused part leaves the thread as it was and
/// is reported in the result, so the caller can log it and degrade to normal scheduling.
/// @param[in] request priority 1..99 or 0; cpu mask or 0.
/// @return the outcome of each part with its errno.
/// @rt allocates: no; syscalls: sched_setscheduler, sched_setaffinity; thread: the one to set up
/// (call it once at thread start, not in the loop).
RtStatus applyRealtime(const RtRequest& request) noexcept;

/// @brief Names the calling thread (shown by top -H, ps -L, gdb, /proc/<pid>/task/<tid>/comm).
/// Names longer than 15 characters are truncated (the kernel's limit).
/// @param[in] name NUL-terminated; nullptr is ignored.
/// @rt allocates: no; syscalls: prctl; thread: the one to name.
void nameCurrentThread(const char* name) noexcept;

/// @brief What lockMemory() achieved.
struct MemoryLockStatus {
  bool locked = false;            ///< mlockall(MCL_CURRENT | MCL_FUTURE) is in force
  int error_no = 0;               ///< 0 when locked; ENOMEM when skipped for a finite limit;
                                  ///< else mlockall's errno (EPERM, ENOMEM, ...)
  std::uint64_t limit_bytes = 0;  ///< RLIMIT_MEMLOCK soft limit; UINT64_MAX = unlimited
};

/// @brief Locks all current and future pages of the process in RAM (no page faults to disk on the
/// real-time path). Done ONLY when RLIMIT_MEMLOCK is unlimited (LimitMEMLOCK=infinity in the
/// unit): under a finite limit MCL_FUTURE would turn later allocations (heap, thread stacks, GPU
/// pinned memory) into ENOMEM once the limit is reached, so then nothing is locked and the result
/// says locked=false, error_no=ENOMEM with the limit; the caller reports it and carries on.
/// @pre Call once in main, after the large pools are allocated (and before prefaulting them).
/// @rt allocates: no; syscalls: getrlimit, mlockall (may take long: it faults in every page);
/// thread: any, start-up only. Process-wide effect.
MemoryLockStatus lockMemory() noexcept;

}  // namespace raymap::platform
