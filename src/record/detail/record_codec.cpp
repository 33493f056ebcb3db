// SPDX-License-Identifier: BSD-3-Clause
// Record log encoding: integers are little-endian whatever the host's byte order.
#include "src/record/detail/record_codec.hpp"

#include <cstring>

#include "src/core/byte_order.hpp"
#include "src/core/crc32.hpp"

namespace raymap::record::detail {
namespace {

// Offsets inside the TOPIC payload (docs/record-format.md).
constexpr std::size_t kTopicFixedBytes = 8;  // id, reliability, durability, reserved
constexpr std::size_t kStringLengthBytes = 2;

std::string reasonAt(std::size_t offset, const std::string& what) {
  return what + " (payload offset " + std::to_string(offset) + ")";
}

}  // namespace

std::array<std::byte, kFileHeaderBytes> encodeFileHeader(std::int64_t created_unix_ns) noexcept {
  std::array<std::byte, kFileHeaderBytes> header{};
  std::memcpy(header.data(), kRecordLogMagic.data(), kRecordLogMagic.size());
  storeLe(header.data() + 8, kRecordLogVersion);
  storeLe(header.data() + 12, static_cast<std::uint32_t>(kFileHeaderBytes));
  storeLe(header.data() + 16, created_unix_ns);
  storeLe(header.data() + 24, std::uint32_t{0});  // flags: none defined in version 1
  storeLe(header.data() + 28, crc32(0, std::span(header).first(kFileHeaderBytes - 4)));
  return header;
}

std::uint32_t recordCrcSeed(std::uint32_t kind, std::uint32_t payload_length) noexcept {
  std::array<std::byte, 8> fields{};
  storeLe(fields.data(), kind);
  storeLe(fields.data() + 4, payload_length);
  return crc32(0, fields);
}

void encodeRecordHeader(std::byte* out, RecordKind kind, std::uint32_t payload_length,
                        std::uint32_t crc) noexcept {
  storeLe(out, static_cast<std::uint32_t>(kind));
  storeLe(out + 4, payload_length);
  storeLe(out + 8, crc);
}

std::size_t topicPayloadBytes(const LogTopic& topic) noexcept {
  return kTopicFixedBytes + kStringLengthBytes + topic.name.size() + kStringLengthBytes +
         topic.type.size();
}

void encodeTopicPayload(std::byte* out, const LogTopic& topic) noexcept {
  storeLe(out, topic.id);
  storeLe(out + 4, static_cast<std::uint8_t>(topic.reliability));
  storeLe(out + 5, static_cast<std::uint8_t>(topic.durability));
  storeLe(out + 6, std::uint16_t{0});  // reserved
  std::byte* at = out + kTopicFixedBytes;
  for (const std::string* text : {&topic.name, &topic.type}) {
    at = storeLe(at, static_cast<std::uint16_t>(text->size()));
    std::memcpy(at, text->data(), text->size());
    at += text->size();
  }
}

Expected<LogTopic, std::string> decodeTopicPayload(std::span<const std::byte> payload) {
  if (payload.size() < kTopicFixedBytes + 2 * kStringLengthBytes) {
    return Unexpected(std::string("TOPIC payload of ") + std::to_string(payload.size()) +
                      " bytes is shorter than the " +
                      std::to_string(kTopicFixedBytes + 2 * kStringLengthBytes) +
                      " bytes of its fixed fields");
  }
  LogTopic topic;
  topic.id = loadLe<std::uint32_t>(payload.data());
  const std::uint8_t reliability = std::to_integer<std::uint8_t>(payload[4]);
  const std::uint8_t durability = std::to_integer<std::uint8_t>(payload[5]);
  if (reliability > static_cast<std::uint8_t>(LogReliability::kReliable)) {
    return Unexpected(reasonAt(4, "unknown reliability " + std::to_string(reliability)));
  }
  if (durability > static_cast<std::uint8_t>(LogDurability::kTransientLocal)) {
    return Unexpected(reasonAt(5, "unknown durability " + std::to_string(durability)));
  }
  topic.reliability = static_cast<LogReliability>(reliability);
  topic.durability = static_cast<LogDurability>(durability);
  // The reserved u16 at offset 6 is ignored: a later writer may give it a meaning that older
  // readers can safely overlook (docs/record-format.md, compatibility).
  std::size_t at = kTopicFixedBytes;
  for (std::string* text : {&topic.name, &topic.type}) {
    const char* field = text == &topic.name ? "topic name" : "type name";
    if (payload.size() - at < kStringLengthBytes) {
      return Unexpected(reasonAt(at, std::string("no room for the length of the ") + field));
    }
    const std::size_t length = loadLe<std::uint16_t>(payload.data() + at);
    at += kStringLengthBytes;
    if (payload.size() - at < length) {
      return Unexpected(reasonAt(at, std::string("the ") + field + " of " + std::to_string(length) +
                                         " bytes runs past the " + std::to_string(payload.size()) +
                                         "-byte payload"));
    }
    text->assign(reinterpret_cast<const char*>(payload.data() + at), length);
    at += length;
  }
  if (topic.name.empty()) {
    return Unexpected(std::string("the topic name is empty"));
  }
  return topic;
}

void encodeMessagePrefix(std::byte* out, std::uint32_t topic_id, std::int64_t receive_unix_ns,
                         std::int64_t receive_monotonic_ns,
                         std::int64_t source_timestamp_ns) noexcept {
  storeLe(out, topic_id);
  storeLe(out + 4, receive_unix_ns);
  storeLe(out + 12, receive_monotonic_ns);
  storeLe(out + 20, source_timestamp_ns);
}

void encodeEndPayload(std::byte* out, const EndRecord& end) noexcept {
  storeLe(out, end.message_count);
  storeLe(out + 8, end.end_unix_ns);
}

Expected<EndRecord, std::string> decodeEndPayload(std::span<const std::byte> payload) {
  if (payload.size() < kEndPayloadBytes) {
    return Unexpected(std::string("END payload of ") + std::to_string(payload.size()) +
                      " bytes is shorter than its " + std::to_string(kEndPayloadBytes) +
                      " bytes of fields");
  }
  return EndRecord{loadLe<std::uint64_t>(payload.data()), loadLe<std::int64_t>(payload.data() + 8)};
}

}  // namespace raymap::record::detail
