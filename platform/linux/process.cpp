// SPDX-License-Identifier: BSD-3-Clause
// Process facts on Linux.
#include "platform/process.hpp"

#include <ctime>
#include <fstream>

#include <sched.h>
#include <sys/resource.h>
#include <unistd.h>

namespace raymap::platform {

std::uint64_t peakResidentBytes() noexcept {
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) {
    return 0;
  }
  return static_cast<std::uint64_t>(usage.ru_maxrss) * 1024u;  // Linux reports kibibytes
}

namespace {

double clockSeconds(clockid_t clock) noexcept {
  timespec t{};
  if (clock_gettime(clock, &t) != 0) {
    return 0.0;
  }
  return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}

}  // namespace

double processCpuSeconds() noexcept { return clockSeconds(CLOCK_PROCESS_CPUTIME_ID); }

double threadCpuSeconds() noexcept { return clockSeconds(CLOCK_THREAD_CPUTIME_ID); }

bool stderrIsTerminal() noexcept { return isatty(STDERR_FILENO) == 1; }

unsigned availableCores() noexcept {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0) {
    const int count = CPU_COUNT(&set);
    if (count > 0) {
      return static_cast<unsigned>(count);
    }
  }
  const long online = sysconf(_SC_NPROCESSORS_ONLN);
  return online > 0 ? static_cast<unsigned>(online) : 1u;
}

std::string cpuModelName() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpuinfo, line)) {
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) {
        return line.substr(line.find_first_not_of(' ', colon + 1));
      }
    }
  }
  return "unknown";
}

}  // namespace raymap::platform
