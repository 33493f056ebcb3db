// SPDX-License-Identifier: BSD-3-Clause
// applyRealtime, nameCurrentThread and lockMemory: applied where permitted, cleanly refused
// otherwise. Nothing here requires RT privileges; the success path is checked only when granted.
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>

#include <grp.h>
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <unistd.h>

#include "platform/errno_text.hpp"
#include "platform/process.hpp"
#include "platform/rt.hpp"
#include "tests/unit/platform/child_process.hpp"

namespace raymap::platform {
namespace {

/// Runs `body` on a fresh thread (so this test thread keeps its scheduling) and waits for it.
template <class F>
void onFreshThread(F&& body) {
  std::thread worker(std::forward<F>(body));
  worker.join();
}

/// VmLck of this process in kB, or -1 when /proc does not say.
long lockedKiB() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmLck:", 0) == 0) {
      return std::strtol(line.c_str() + 6, nullptr, 10);
    }
  }
  return -1;
}

TEST(RtOutcome, HasStableNames) {
  EXPECT_STREQ(toString(RtOutcome::kNotRequested), "not-requested");
  EXPECT_STREQ(toString(RtOutcome::kApplied), "applied");
  EXPECT_STREQ(toString(RtOutcome::kRefused), "refused");
}

TEST(ApplyRealtime, EmptyRequestChangesNothing) {
  RtStatus status;
  int policy_after = -1;
  onFreshThread([&] {
    status = applyRealtime(RtRequest{});
    sched_param param{};
    pthread_getschedparam(pthread_self(), &policy_after, &param);
  });

  EXPECT_EQ(status.scheduling, RtOutcome::kNotRequested);
  EXPECT_EQ(status.affinity, RtOutcome::kNotRequested);
  EXPECT_EQ(status.scheduling_errno, 0);
  EXPECT_EQ(status.affinity_errno, 0);
  EXPECT_EQ(policy_after, SCHED_OTHER);
}

TEST(ApplyRealtime, PriorityOutOfRangeIsRefusedWithEinval) {
  RtStatus status;
  int policy_after = -1;
  onFreshThread([&] {
    status = applyRealtime(RtRequest{100, 0});
    sched_param param{};
    pthread_getschedparam(pthread_self(), &policy_after, &param);
  });

  EXPECT_EQ(status.scheduling, RtOutcome::kRefused);
  EXPECT_EQ(status.scheduling_errno, EINVAL);
  EXPECT_EQ(status.affinity, RtOutcome::kNotRequested);
  EXPECT_EQ(policy_after, SCHED_OTHER);
}

TEST(ApplyRealtime, FifoIsAppliedWhenPermittedOrRefusedWithEperm) {
  RtStatus status;
  int policy_after = -1;
  int priority_after = -1;
  onFreshThread([&] {
    status = applyRealtime(RtRequest{1, 0});
    sched_param param{};
    pthread_getschedparam(pthread_self(), &policy_after, &param);
    priority_after = param.sched_priority;
  });

  if (status.scheduling == RtOutcome::kApplied) {
    EXPECT_EQ(status.scheduling_errno, 0);
    EXPECT_EQ(policy_after, SCHED_FIFO);
    EXPECT_EQ(priority_after, 1);
  } else {
    // No CAP_SYS_NICE and RLIMIT_RTPRIO 0, or a cgroup without RT runtime (RT group scheduling).
    ASSERT_EQ(status.scheduling, RtOutcome::kRefused);
    EXPECT_EQ(status.scheduling_errno, EPERM);
    EXPECT_EQ(policy_after, SCHED_OTHER);
    std::printf("SCHED_FIFO refused here (EPERM); only the refusal was checked\n");
  }
}

TEST(ApplyRealtime, FifoIsRefusedWithoutPrivileges) {
  // In a child: drop RLIMIT_RTPRIO to 0 and, as root, become nobody (losing CAP_SYS_NICE).
  const int code = test::runInChild([] {
    const rlimit none{0, 0};
    if (setrlimit(RLIMIT_RTPRIO, &none) != 0) {
      return 10;
    }
    if (geteuid() == 0) {
      const gid_t nogroup = 65534;
      const uid_t nobody = 65534;
      if (setgroups(0, nullptr) != 0 || setresgid(nogroup, nogroup, nogroup) != 0 ||
          setresuid(nobody, nobody, nobody) != 0) {
        return 11;
      }
    }
    const RtStatus status = applyRealtime(RtRequest{10, 0});
    if (status.scheduling != RtOutcome::kRefused) {
      return 12;
    }
    if (status.scheduling_errno != EPERM) {
      std::fprintf(stderr, "child: errno %d\n", status.scheduling_errno);
      return 13;
    }
    int policy = -1;
    sched_param param{};
    pthread_getschedparam(pthread_self(), &policy, &param);
    return policy == SCHED_OTHER ? 0 : 14;
  });

  EXPECT_EQ(code, 0) << "10 setrlimit, 11 dropping privileges, 12 not refused, 13 wrong errno, "
                        "14 policy changed";
}

TEST(ApplyRealtime, AffinityToAnAllowedCpuIsApplied) {
  cpu_set_t allowed;
  CPU_ZERO(&allowed);
  ASSERT_EQ(sched_getaffinity(0, sizeof(allowed), &allowed), 0);
  std::size_t first = 64;
  for (std::size_t cpu = 0; cpu < 64; ++cpu) {
    if (CPU_ISSET(cpu, &allowed)) {
      first = cpu;
      break;
    }
  }
  if (first == 64) {
    GTEST_SKIP() << "no allowed CPU below 64";
  }
  RtStatus status;
  cpu_set_t after;
  CPU_ZERO(&after);
  onFreshThread([&] {
    status = applyRealtime(RtRequest{0, std::uint64_t{1} << first});
    pthread_getaffinity_np(pthread_self(), sizeof(after), &after);
  });

  EXPECT_EQ(status.affinity, RtOutcome::kApplied);
  EXPECT_EQ(status.affinity_errno, 0);
  EXPECT_EQ(status.scheduling, RtOutcome::kNotRequested);
  EXPECT_EQ(CPU_COUNT(&after), 1);
  EXPECT_TRUE(CPU_ISSET(first, &after));
}

TEST(ApplyRealtime, AffinityToAbsentCpuIsRefusedWithEinval) {
  if (availableCores() >= 64 || sysconf(_SC_NPROCESSORS_CONF) >= 64) {
    GTEST_SKIP() << "CPU 63 may exist here";
  }
  RtStatus status;
  int count_after = 0;
  onFreshThread([&] {
    status = applyRealtime(RtRequest{0, std::uint64_t{1} << 63});
    cpu_set_t after;
    CPU_ZERO(&after);
    pthread_getaffinity_np(pthread_self(), sizeof(after), &after);
    count_after = CPU_COUNT(&after);
  });

  EXPECT_EQ(status.affinity, RtOutcome::kRefused);
  EXPECT_EQ(status.affinity_errno, EINVAL);
  EXPECT_EQ(count_after, static_cast<int>(availableCores()));
}

TEST(NameCurrentThread, TruncatesToFifteenCharacters) {
  char short_name[16] = {};
  char long_name[16] = {};
  onFreshThread([&] {
    nameCurrentThread("rm-integrate");
    pthread_getname_np(pthread_self(), short_name, sizeof(short_name));
    nameCurrentThread("raymap-integrator-thread");
    pthread_getname_np(pthread_self(), long_name, sizeof(long_name));
    nameCurrentThread(nullptr);  // ignored
  });

  EXPECT_STREQ(short_name, "rm-integrate");
  EXPECT_STREQ(long_name, "raymap-integrat");
}

TEST(LockMemory, FollowsTheContractForThisProcessLimit) {
  // In a child: a successful mlockall(MCL_FUTURE) would stay in force for the other tests.
  const int code = test::runInChild([] {
    rlimit limit{};
    if (getrlimit(RLIMIT_MEMLOCK, &limit) != 0) {
      return 10;
    }
    const MemoryLockStatus status = lockMemory();
    if (limit.rlim_cur == RLIM_INFINITY) {
      if (status.limit_bytes != UINT64_MAX) {
        return 11;
      }
      if (!status.locked) {
        std::fprintf(stderr, "child: unlimited but mlockall failed: %s\n",
                     platform::errnoText(status.error_no).c_str());
        return status.error_no == EPERM ? 0 : 12;  // no CAP_IPC_LOCK: a clean refusal
      }
      return status.error_no == 0 && lockedKiB() > 0 ? 0 : 13;
    }
    if (status.locked || status.error_no != ENOMEM ||
        status.limit_bytes != static_cast<std::uint64_t>(limit.rlim_cur)) {
      return 14;
    }
    return lockedKiB() == 0 ? 0 : 15;
  });

  EXPECT_EQ(code, 0) << "10 getrlimit, 11 limit, 12 errno, 13 not locked, 14 contract, 15 VmLck";
}

TEST(LockMemory, FiniteLimitIsRefusedAndLeavesAllocationsWorking) {
  const int code = test::runInChild([] {
    const rlimit small{64 * 1024, 64 * 1024};  // lowering is always permitted
    if (setrlimit(RLIMIT_MEMLOCK, &small) != 0) {
      return 10;
    }
    const MemoryLockStatus status = lockMemory();
    if (status.locked || status.error_no != ENOMEM || status.limit_bytes != 64u * 1024u) {
      return 11;
    }
    if (lockedKiB() != 0) {
      return 12;
    }
    // With MCL_FUTURE in force this allocation would fail (16 MiB > 64 KiB).
    constexpr std::size_t kBytes = std::size_t{16} << 20;
    void* block = std::malloc(kBytes);
    if (block == nullptr) {
      return 13;
    }
    std::memset(block, 1, kBytes);
    std::free(block);
    return 0;
  });

  EXPECT_EQ(code, 0) << "10 setrlimit, 11 contract, 12 VmLck, 13 allocation failed";
}

}  // namespace
}  // namespace raymap::platform
