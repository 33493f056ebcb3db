// SPDX-License-Identifier: BSD-3-Clause
// `raymap echo`'s rendering of one received message per known type, as a human-readable block
// or one JSON Lines object.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "raymap/error.hpp"

#include "src/dds/topic_types.hpp"

namespace raymap::cli {

/// @brief One received sample and where and when it arrived.
struct EchoSample {
  std::string_view topic;                 ///< the DDS topic, e.g. "rt/height_map"
  const dds::KnownTopicType* type;        ///< the type it was read as (never nullptr)
  std::span<const std::byte> cdr;         ///< the serialized message with its encapsulation header
  std::uint64_t index = 0;                ///< 1 for the first message echo received, ...
  std::int64_t arrival_unix_ns = 0;       ///< CLOCK_REALTIME when echo took it
  std::int64_t arrival_monotonic_ns = 0;  ///< CLOCK_MONOTONIC when echo took it
  std::int64_t source_timestamp_ns = 0;   ///< the writer's DDS source timestamp (its clock)
};

/// How formatSample renders.
enum class EchoFormat : std::uint8_t {
  kHuman,      ///< a first line "#N TOPIC TYPE stamp S frame F", then indented detail lines
  kJsonLines,  ///< one compact JSON object, no newline inside
};

/// @brief Decodes `sample` by its type and renders it.
/// @return the text, ending in a newline; or an error naming the type and the reason when the
/// bytes do not decode (the caller reports it and carries on). Never throws for bad bytes.
Result<std::string> formatSample(const EchoSample& sample, EchoFormat format);

}  // namespace raymap::cli
