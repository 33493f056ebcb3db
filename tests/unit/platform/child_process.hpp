// SPDX-License-Identifier: BSD-3-Clause
// Runs a test step in a forked child, so process-wide changes (mlockall, signal masks, dropped
// privileges) never leak into the other tests of this executable.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <exception>

#include <sys/wait.h>
#include <unistd.h>

namespace raymap::test {

/// @brief Forks; the child runs `body` and exits with its return value (2 on an exception). No
/// GoogleTest assertion may be used inside `body`: report through the exit code and stderr.
/// @return the child's exit code, 128 + signal number when it was killed, -1 when fork failed.
template <class F>
int runInChild(F&& body) {
  std::fflush(nullptr);  // do not duplicate buffered output into the child
  const pid_t pid = fork();
  if (pid < 0) {
    return -1;
  }
  if (pid == 0) {
    int code = 2;
    try {
      code = body();
    } catch (...) {
      std::fputs("child: exception\n", stderr);
    }
    std::fflush(nullptr);
    _exit(code);
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
  }
  if (WIFEXITED(status)) {
    return WEXITSTATUS(status);
  }
  return WIFSIGNALED(status) ? 128 + WTERMSIG(status) : -1;
}

}  // namespace raymap::test
