// SPDX-License-Identifier: BSD-3-Clause
// The library's errors as Python exceptions: the message is the library's (the option, file or
// key and the reason); the type follows the code (raymap/__init__.py defines them).
#pragma once

#include <string>

#include "raymap/error.hpp"

namespace raymap::python {

/// @brief Raises the exception for `error` (raymap.InvalidArgument, raymap.IoError …). Call with
/// the GIL held.
[[noreturn]] void raiseError(const Error& error);

/// @brief Raises raymap.InvalidArgument (a ValueError) with `message`: bad arrays and options
/// found by the bindings themselves.
[[noreturn]] void raiseInvalid(const std::string& message);

/// @brief The value of `result`, or raises its error.
template <class T>
T valueOr(Expected<T, Error>&& result) {
  if (!result) {
    raiseError(result.error());
  }
  return std::move(*result);
}

/// @brief Raises the error of `result`, if any.
inline void check(const Expected<void, Error>& result) {
  if (!result) {
    raiseError(result.error());
  }
}

}  // namespace raymap::python
