// SPDX-License-Identifier: BSD-3-Clause
// logLine: one formatted write(2) per line, so lines from threads never interleave.
#include "src/service/log.hpp"

#include <cstdarg>
#include <cstdio>
#include <cstdlib>

#include <unistd.h>

namespace raymap::service {

void logLine(LogLevel level, const char* format, ...) {
  static const bool journal = std::getenv("JOURNAL_STREAM") != nullptr;
  char line[1024];
  int n = 0;
  if (journal) {
    n = std::snprintf(line, sizeof(line), "<%d>", static_cast<int>(level));
  } else {
    const char* name = level == LogLevel::kError     ? "error"
                       : level == LogLevel::kWarning ? "warning"
                       : level == LogLevel::kNotice  ? "notice"
                                                     : "info";
    n = std::snprintf(line, sizeof(line), "raymapd: %s: ", name);
  }
  va_list args;
  va_start(args, format);
  const int m =
      std::vsnprintf(line + n, sizeof(line) - static_cast<std::size_t>(n) - 1, format, args);
  va_end(args);
  std::size_t length = static_cast<std::size_t>(n) + (m < 0 ? 0u : static_cast<std::size_t>(m));
  length = length > sizeof(line) - 2 ? sizeof(line) - 2 : length;
  line[length++] = '\n';
  const ssize_t written = ::write(STDERR_FILENO, line, length);
  (void)written;  // nowhere else to report a failed log write
}

}  // namespace raymap::service
