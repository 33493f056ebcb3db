// SPDX-License-Identifier: BSD-3-Clause
// The message of an errno value, for error texts ("cannot write 'map.rmap': No space left on
// device").
#pragma once

#include <cstring>
#include <string>

namespace raymap::platform {

/// @brief The system's message for `error` (an errno value), e.g. "No such file or directory".
/// Thread-safety: safe to call from any thread at once, unlike std::strerror, which may return
/// a buffer shared by all threads (clang-tidy's concurrency-mt-unsafe). Real-time: allocates
/// the returned string; not for a real-time loop.
inline std::string errnoText(int error) {
  char buffer[128];
  // GNU strerror_r (C++ on glibc defines _GNU_SOURCE): returns the message, either a static
  // string or one written into `buffer`, never a buffer another thread writes.
  return ::strerror_r(error, buffer, sizeof buffer);
}

}  // namespace raymap::platform
