// SPDX-License-Identifier: BSD-3-Clause
// A diagnostic_msgs/DiagnosticArray sample with fixed slots, refilled each period without
// allocating.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include <dds/dds.h>

#include "src/msgs/diagnostic_levels.hpp"

namespace raymap::dds {

/// @brief A DiagnosticArray with room for `max_statuses` statuses of `max_values` key/value
/// pairs each. Strings live in fixed buffers and are truncated: name, message and hardware_id
/// kTextBytes - 1 characters, keys kKeyBytes - 1, values kValueBytes - 1.
///
/// Usage per period: begin(stamp); s = addStatus(...); addValue(s, "key", "%d", n); ...;
/// writer.write(sample()).
/// Thread-safety: none; one publishing thread. Move-only.
class DiagnosticsMessage {
 public:
  static constexpr std::size_t kTextBytes = 512;  // a status message names its reasons
  static constexpr std::size_t kKeyBytes = 64;
  static constexpr std::size_t kValueBytes = 96;

  /// @brief Preallocates every slot. Start-up only (allocates).
  /// @pre max_statuses > 0, max_values >= 0
  DiagnosticsMessage(int max_statuses, int max_values);
  DiagnosticsMessage(DiagnosticsMessage&&) noexcept;
  DiagnosticsMessage& operator=(DiagnosticsMessage&&) noexcept;
  DiagnosticsMessage(const DiagnosticsMessage&) = delete;
  DiagnosticsMessage& operator=(const DiagnosticsMessage&) = delete;
  ~DiagnosticsMessage();

  /// @brief Empties the array and sets header.stamp (header.frame_id is empty, as ROS's
  /// diagnostic_updater sends it). @rt allocates: no.
  void begin(std::int64_t stamp_ns) noexcept;

  /// @brief Appends a status (level kDiagnosticOk..kDiagnosticStale; nullptr strings read as "").
  /// @return its index for addValue(), or -1 when all max_statuses slots are used
  /// @rt allocates: no.
  int addStatus(std::uint8_t level, const char* name, const char* message,
                const char* hardware_id) noexcept;

  /// @brief Appends key = printf(fmt, ...) to status `status`; does nothing when `status` is -1
  /// or out of range or its value slots are full. Formats with vsnprintf into the fixed slot
  /// (truncating). @rt allocates: no (glibc's vsnprintf allocates only for field widths or
  /// precisions in the thousands); formats: yes, so not for a hard-deadline loop.
  void addValue(int status, const char* key, const char* fmt, ...) noexcept
      __attribute__((format(printf, 4, 5)));

  /// @brief Statuses added since begin().
  int statusCount() const noexcept;

  /// @brief The idlc struct (diagnostic_msgs_msg_dds__DiagnosticArray_) to pass to
  /// Writer::write().
  const void* sample() const noexcept;
  /// @brief The type of sample() (= diagnosticArrayType()).
  static const dds_topic_descriptor_t* descriptor() noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace raymap::dds
