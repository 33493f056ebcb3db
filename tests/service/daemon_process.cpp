// SPDX-License-Identifier: BSD-3-Clause
// DaemonProcess: fork/exec/waitpid.
#include "tests/service/daemon_process.hpp"

#include <cstdio>
#include <cstdlib>
#include <thread>

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

namespace raymap::test {
namespace {

int decode(int status) {
  if (WIFEXITED(status)) {
    return WEXITSTATUS(status);
  }
  return WIFSIGNALED(status) ? 128 + WTERMSIG(status) : -1;
}

std::vector<char*> argv(const std::string& binary, const std::vector<std::string>& args) {
  std::vector<char*> out;
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): execv's signature
  out.push_back(const_cast<char*>(binary.c_str()));
  for (const std::string& a : args) {
    // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): execv's signature
    out.push_back(const_cast<char*>(a.c_str()));
  }
  out.push_back(nullptr);
  return out;
}

}  // namespace

DaemonProcess::DaemonProcess(const std::string& binary, const std::vector<std::string>& args,
                             const std::vector<std::string>& environment,
                             const std::string& stderr_path) {
  std::vector<char*> arguments = argv(binary, args);
  const pid_t test = ::getpid();
  pid_ = ::fork();
  if (pid_ == 0) {
    // Killed with the test: a test that dies (an abort, a crash) leaves no daemon, capture or
    // peer running behind it. Kept across exec; lost only by a set-user-ID program.
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != test) {
      ::_exit(127);  // the test died before the line above
    }
    for (const std::string& e : environment) {
      // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): the child owns its copy
      ::putenv(const_cast<char*>(e.c_str()));
    }
    const int fd = ::open(stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      ::dup2(fd, STDERR_FILENO);
      ::dup2(fd, STDOUT_FILENO);
    }
    // The test may have blocked signals; the daemon sets its own mask.
    sigset_t none;
    sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    ::execv(binary.c_str(), arguments.data());
    ::_exit(127);
  }
}

DaemonProcess::~DaemonProcess() {
  if (pid_ > 0 && running()) {
    ::kill(pid_, SIGKILL);
    int status = 0;
    ::waitpid(pid_, &status, 0);
  }
}

bool DaemonProcess::running() {
  if (status_) {
    return false;
  }
  int status = 0;
  const pid_t r = ::waitpid(pid_, &status, WNOHANG);
  if (r == pid_) {
    status_ = decode(status);
    return false;
  }
  return r == 0;
}

std::optional<std::pair<int, std::chrono::milliseconds>> DaemonProcess::stop(
    int signal, std::chrono::milliseconds timeout) {
  const auto start = std::chrono::steady_clock::now();
  if (!running()) {
    return std::make_pair(*status_, std::chrono::milliseconds(0));
  }
  ::kill(pid_, signal);
  while (std::chrono::steady_clock::now() - start < timeout) {
    if (!running()) {
      return std::make_pair(*status_, std::chrono::duration_cast<std::chrono::milliseconds>(
                                          std::chrono::steady_clock::now() - start));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ::kill(pid_, SIGKILL);
  int status = 0;
  ::waitpid(pid_, &status, 0);
  status_ = decode(status);
  return std::nullopt;
}

std::pair<int, std::string> runToCompletion(const std::string& binary,
                                            const std::vector<std::string>& args) {
  std::string command = binary;
  for (const std::string& a : args) {
    command += " '" + a + "'";
  }
  command += " 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  std::string output;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) {
    output.append(buffer, n);
  }
  const int status = ::pclose(pipe);
  return {decode(status), output};
}

}  // namespace raymap::test
