// SPDX-License-Identifier: BSD-3-Clause
// Decoding diagnostic_msgs/DiagnosticArray from its serialized XCDR1 bytes, for tools that
// inspect the traffic (`raymap echo`) and for tests.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "raymap/expected.hpp"

namespace raymap::msgs {

/// diagnostic_msgs/KeyValue.
struct DiagnosticKeyValue {
  std::string key;
  std::string value;
};

/// diagnostic_msgs/DiagnosticStatus.
struct DecodedDiagnosticStatus {
  std::uint8_t level = 0;  ///< kDiagnosticOk .. kDiagnosticStale (other values are passed on)
  std::string name;
  std::string message;
  std::string hardware_id;
  std::vector<DiagnosticKeyValue> values;  ///< in the order sent (keys may repeat)
};

/// diagnostic_msgs/DiagnosticArray.
struct DecodedDiagnostics {
  std::int64_t stamp_ns = 0;  ///< header.stamp, nanoseconds since the epoch of the sender's clock
  std::string frame_id;       ///< header.frame_id (diagnostic_updater sends "")
  std::vector<DecodedDiagnosticStatus> statuses;
};

/// Why a DiagnosticArray was rejected. Nothing is read out of bounds for any input.
enum class DiagnosticsError : std::uint8_t {
  kTruncated,         ///< the bytes end before the message does (also absurd sequence lengths)
  kBadEncapsulation,  ///< shorter than 4 bytes or not CDR_LE / CDR_BE
  kMalformed,         ///< a string without its NUL
};

/// @brief Short, stable name ("truncated", ...). @rt allocates: no.
const char* toString(DiagnosticsError error) noexcept;

/// @brief "OK", "WARN", "ERROR", "STALE" for the DiagnosticStatus levels 0..3, else "LEVEL?".
/// @rt allocates: no.
const char* diagnosticLevelName(std::uint8_t level) noexcept;

/// @brief Decodes a serialized diagnostic_msgs/DiagnosticArray (with its 4-byte encapsulation
/// header), in either CDR byte order. Trailing bytes are ignored (padding).
/// Allocates (the strings): a tool and test decoder, not for the real-time path.
/// Thread-safety: any thread (no shared state).
Expected<DecodedDiagnostics, DiagnosticsError> decodeDiagnosticArray(
    std::span<const std::byte> cdr);

}  // namespace raymap::msgs
