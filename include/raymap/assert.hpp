// SPDX-License-Identifier: BSD-3-Clause
// Contract checks: a failed check is a bug, so it reports where and aborts (systemd restarts the
// service).
#pragma once

namespace raymap::detail {
/// @brief Prints the failed condition and its location to stderr, then aborts. Never returns.
[[noreturn]] void contractViolation(const char* kind, const char* condition, const char* file,
                                    int line) noexcept;
}  // namespace raymap::detail

/// Precondition check, on in every build type (use only for O(1) checks).
#define RAYMAP_EXPECTS(cond)                                                          \
  do {                                                                                \
    if (!(cond)) [[unlikely]] {                                                       \
      ::raymap::detail::contractViolation("precondition", #cond, __FILE__, __LINE__); \
    }                                                                                 \
  } while (false)

/// Postcondition check, on in every build type (use only for O(1) checks).
#define RAYMAP_ENSURES(cond)                                                           \
  do {                                                                                 \
    if (!(cond)) [[unlikely]] {                                                        \
      ::raymap::detail::contractViolation("postcondition", #cond, __FILE__, __LINE__); \
    }                                                                                  \
  } while (false)

/// Expensive checks: compiled only into debug and test builds (RAYMAP_DEBUG_CHECKS).
#if defined(RAYMAP_DEBUG_CHECKS)
#define RAYMAP_DEBUG_ASSERT(cond)                                                        \
  do {                                                                                   \
    if (!(cond)) [[unlikely]] {                                                          \
      ::raymap::detail::contractViolation("debug assertion", #cond, __FILE__, __LINE__); \
    }                                                                                    \
  } while (false)
#else
#define RAYMAP_DEBUG_ASSERT(cond) \
  do {                            \
  } while (false)
#endif
