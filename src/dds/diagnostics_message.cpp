// SPDX-License-Identifier: BSD-3-Clause
// The preallocated DiagnosticArray: fixed text slots, sequences over them with _release false.
#include "src/dds/diagnostics_message.hpp"

#include <cstdarg>
#include <cstdio>
#include <vector>

#include "diagnostic_msgs.h"
#include "raymap/assert.hpp"

#include "src/dds/frame_id.hpp"
#include "src/dds/ros_time.hpp"
#include "src/dds/topic_types.hpp"

namespace raymap::dds {

/// Design: one heap block per message (moves keep the addresses in `msg` valid). Text slots:
/// status s has name/message/hardware_id at text[(3 s + k) * kTextBytes]; value v of status s
/// has its key at keys[(s * max_values + v) * kKeyBytes] and its value likewise in `values`.
struct DiagnosticsMessage::Impl {
  int max_statuses = 0;
  int max_values = 0;
  diagnostic_msgs_msg_dds__DiagnosticArray_ msg{};
  char frame_id[1] = {'\0'};
  std::vector<diagnostic_msgs_msg_dds__DiagnosticStatus_> statuses;
  std::vector<diagnostic_msgs_msg_dds__KeyValue_> pairs;
  std::vector<char> text;
  std::vector<char> keys;
  std::vector<char> values;
};

DiagnosticsMessage::DiagnosticsMessage(int max_statuses, int max_values)
    : impl_(std::make_unique<Impl>()) {
  RAYMAP_EXPECTS(max_statuses > 0 && max_values >= 0);
  Impl& m = *impl_;
  m.max_statuses = max_statuses;
  m.max_values = max_values;
  const auto statuses = static_cast<std::size_t>(max_statuses);
  const auto per_status = static_cast<std::size_t>(max_values);
  m.statuses.resize(statuses);
  m.pairs.resize(statuses * per_status);
  m.text.assign(statuses * 3 * kTextBytes, '\0');
  m.keys.assign(statuses * per_status * kKeyBytes, '\0');
  m.values.assign(statuses * per_status * kValueBytes, '\0');
  for (std::size_t s = 0; s < statuses; ++s) {
    auto& status = m.statuses[s];
    status.name = &m.text[(3 * s + 0) * kTextBytes];
    status.message = &m.text[(3 * s + 1) * kTextBytes];
    status.hardware_id = &m.text[(3 * s + 2) * kTextBytes];
    status.values._buffer = per_status > 0 ? &m.pairs[s * per_status] : nullptr;
    status.values._maximum = static_cast<std::uint32_t>(per_status);
    status.values._length = 0;
    status.values._release = false;
    for (std::size_t v = 0; v < per_status; ++v) {
      auto& pair = m.pairs[s * per_status + v];
      pair.key = &m.keys[(s * per_status + v) * kKeyBytes];
      pair.value = &m.values[(s * per_status + v) * kValueBytes];
    }
  }
  m.msg.header.frame_id = m.frame_id;
  m.msg.status._buffer = m.statuses.data();
  m.msg.status._maximum = static_cast<std::uint32_t>(statuses);
  m.msg.status._length = 0;
  m.msg.status._release = false;
}

DiagnosticsMessage::DiagnosticsMessage(DiagnosticsMessage&&) noexcept = default;
DiagnosticsMessage& DiagnosticsMessage::operator=(DiagnosticsMessage&&) noexcept = default;
DiagnosticsMessage::~DiagnosticsMessage() = default;

void DiagnosticsMessage::begin(std::int64_t stamp_ns) noexcept {
  Impl& m = *impl_;
  setRosTime(m.msg.header.stamp, stamp_ns);
  m.msg.status._length = 0;
}

int DiagnosticsMessage::addStatus(std::uint8_t level, const char* name, const char* message,
                                  const char* hardware_id) noexcept {
  Impl& m = *impl_;
  const std::uint32_t index = m.msg.status._length;
  if (index >= m.msg.status._maximum) {
    return -1;
  }
  auto& status = m.statuses[index];
  status.level = level;
  copyText(status.name, kTextBytes, name);
  copyText(status.message, kTextBytes, message);
  copyText(status.hardware_id, kTextBytes, hardware_id);
  status.values._length = 0;
  m.msg.status._length = index + 1;
  return static_cast<int>(index);
}

void DiagnosticsMessage::addValue(int status, const char* key, const char* fmt, ...) noexcept {
  Impl& m = *impl_;
  if (status < 0 || static_cast<std::uint32_t>(status) >= m.msg.status._length) {
    return;
  }
  auto& entry = m.statuses[static_cast<std::size_t>(status)];
  if (entry.values._length >= entry.values._maximum) {
    return;
  }
  auto& pair = entry.values._buffer[entry.values._length];
  copyText(pair.key, kKeyBytes, key);
  if (fmt == nullptr) {
    pair.value[0] = '\0';
  } else {
    va_list args;
    va_start(args, fmt);
    const int written = std::vsnprintf(pair.value, kValueBytes, fmt, args);
    va_end(args);
    if (written < 0) {
      pair.value[0] = '\0';
    }
  }
  entry.values._length += 1;
}

int DiagnosticsMessage::statusCount() const noexcept {
  return static_cast<int>(impl_->msg.status._length);
}

const void* DiagnosticsMessage::sample() const noexcept { return &impl_->msg; }

const dds_topic_descriptor_t* DiagnosticsMessage::descriptor() noexcept {
  return diagnosticArrayType();
}

}  // namespace raymap::dds
