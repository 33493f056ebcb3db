// SPDX-License-Identifier: BSD-3-Clause
// decodeDiagnosticArray over the bounded CDR reader, in the order of
// config/idl/diagnostic_msgs.idl.
#include "src/msgs/diagnostics_decode.hpp"

#include <string_view>

#include "src/msgs/cdr_reader.hpp"
#include "src/msgs/diagnostic_levels.hpp"
#include "src/msgs/ros_time.hpp"

namespace raymap::msgs {
namespace {

// Smallest encodings, so that a corrupt count is refused before anything is reserved for it:
// a key/value pair is two string lengths; a status is its level byte, three string lengths and
// the value count (16 bytes at the least, counting no padding).
constexpr std::size_t kMinKeyValueBytes = 8;
constexpr std::size_t kMinStatusBytes = 16;

bool readStatus(CdrReader& reader, DecodedDiagnosticStatus& out) {
  std::uint32_t values = 0;
  if (!reader.readU8(out.level) || !reader.readString(out.name) ||
      !reader.readString(out.message) || !reader.readString(out.hardware_id) ||
      !reader.readSequenceLength(values, kMinKeyValueBytes)) {
    return false;
  }
  out.values.resize(values);
  for (DiagnosticKeyValue& pair : out.values) {
    if (!reader.readString(pair.key) || !reader.readString(pair.value)) {
      return false;
    }
  }
  return true;
}

}  // namespace

const char* toString(DiagnosticsError error) noexcept {
  switch (error) {
    case DiagnosticsError::kTruncated:
      return "truncated";
    case DiagnosticsError::kBadEncapsulation:
      return "bad_encapsulation";
    case DiagnosticsError::kMalformed:
      return "malformed";
  }
  return "unknown";
}

const char* diagnosticLevelName(std::uint8_t level) noexcept {
  switch (level) {
    case kDiagnosticOk:
      return "OK";
    case kDiagnosticWarn:
      return "WARN";
    case kDiagnosticError:
      return "ERROR";
    case kDiagnosticStale:
      return "STALE";
    default:
      return "LEVEL?";
  }
}

Expected<DecodedDiagnostics, DiagnosticsError> decodeDiagnosticArray(
    std::span<const std::byte> cdr) {
  CdrReader reader(cdr);
  if (!reader.ok()) {
    return Unexpected(DiagnosticsError::kBadEncapsulation);
  }
  DecodedDiagnostics array;
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  std::uint32_t statuses = 0;
  bool read = reader.readI32(sec) && reader.readU32(nanosec) && reader.readString(array.frame_id) &&
              reader.readSequenceLength(statuses, kMinStatusBytes);
  if (read) {
    array.statuses.resize(statuses);
    for (DecodedDiagnosticStatus& status : array.statuses) {
      if (!readStatus(reader, status)) {
        read = false;
        break;
      }
    }
  }
  if (!read) {
    return Unexpected(reader.malformed() ? DiagnosticsError::kMalformed
                                         : DiagnosticsError::kTruncated);
  }
  array.stamp_ns = nanosecondsOf(sec, nanosec);
  return array;
}

}  // namespace raymap::msgs
