// SPDX-License-Identifier: BSD-3-Clause
// The error type of start-up and offline code (file readers, map files, configuration).
#pragma once

#include <cstdint>
#include <string>
#include <utility>

#include "raymap/expected.hpp"

namespace raymap {

/// What kind of failure an Error reports; the message carries the detail.
enum class ErrorCode : std::uint8_t {
  kInvalidArgument,  ///< a parameter or option is out of range or inconsistent
  kIo,               ///< the operating system refused to open, read, write or rename a file
  kFormat,           ///< a file is not in the expected format (bad header, missing field)
  kTruncated,        ///< a file ends before the data it declares
  kCorrupt,          ///< a checksum or a structural check failed
  kCapacity,         ///< a fixed-size store or buffer is full
  kUnsupported,      ///< valid input that this build cannot handle
};

/// @brief Short, stable name of an error code (for logs and JSON).
const char* toString(ErrorCode code) noexcept;

/// @brief An error with a message that names the file, field or key and the reason.
/// Not for the real-time path (the message allocates); RT code returns enum codes instead.
struct Error {
  ErrorCode code = ErrorCode::kInvalidArgument;
  std::string message;
};

/// @brief Shorthand for returning an error: `return fail(ErrorCode::kIo, "...");`
inline Unexpected<Error> fail(ErrorCode code, std::string message) {
  return Unexpected<Error>(Error{code, std::move(message)});
}

template <class T>
using Result = Expected<T, Error>;

}  // namespace raymap
