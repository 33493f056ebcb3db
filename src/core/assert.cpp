// SPDX-License-Identifier: BSD-3-Clause
// Reporting of contract violations.
#include "raymap/assert.hpp"

#include <cstdio>
#include <cstdlib>

namespace raymap::detail {

void contractViolation(const char* kind, const char* condition, const char* file,
                       int line) noexcept {
  std::fprintf(stderr, "raymap: %s violated: %s (%s:%d)\n", kind, condition, file, line);
  std::fflush(stderr);
  std::abort();
}

}  // namespace raymap::detail
