// SPDX-License-Identifier: BSD-3-Clause
// Record log encoding: integers are built byte by byte, so the host's byte order never matters.
#include "src/record/detail/record_codec.hpp"

#include <cstring>

#include <zlib.h>

namespace raymap::record::detail {
namespace {

// Offsets inside the TOPIC payload (docs/record-format.md).
constexpr std::size_t kTopicFixedBytes = 8;  // id, reliability, durability, reserved
constexpr std::size_t kStringLengthBytes = 2;

std::string reasonAt(std::size_t offset, const std::string& what) {
  return what + " (payload offset " + std::to_string(offset) + ")";
}

}  // namespace

void putLe(std::byte* out, std::uint64_t value, int count) noexcept {
  for (int i = 0; i < count; ++i) {
    out[i] = static_cast<std::byte>((value >> (8 * i)) & 0xFFu);
  }
}

std::uint64_t getLe(const std::byte* in, int count) noexcept {
  std::uint64_t value = 0;
  for (int i = 0; i < count; ++i) {
    value |= std::to_integer<std::uint64_t>(in[i]) << (8 * i);
  }
  return value;
}

std::uint32_t crc32Update(std::uint32_t crc, std::span<const std::byte> bytes) noexcept {
  // NOTE: zlib treats a null buffer as "give me the initial value" and returns 0 whatever `crc`
  // is, and an empty span may well have a null data(): an empty piece must leave `crc` alone.
  if (bytes.empty()) {
    return crc;
  }
  // crc32_z takes a size_t length: no 4 GiB split needed.
  return static_cast<std::uint32_t>(
      ::crc32_z(crc, reinterpret_cast<const Bytef*>(bytes.data()), bytes.size()));
}

std::array<std::byte, kFileHeaderBytes> encodeFileHeader(std::int64_t created_unix_ns) noexcept {
  std::array<std::byte, kFileHeaderBytes> header{};
  std::memcpy(header.data(), kRecordLogMagic.data(), kRecordLogMagic.size());
  putLe(header.data() + 8, kRecordLogVersion, 4);
  putLe(header.data() + 12, kFileHeaderBytes, 4);
  putLe(header.data() + 16, static_cast<std::uint64_t>(created_unix_ns), 8);
  putLe(header.data() + 24, 0, 4);  // flags: none defined in version 1
  putLe(header.data() + 28, crc32Update(0, std::span(header).first(kFileHeaderBytes - 4)), 4);
  return header;
}

std::uint32_t recordCrcSeed(std::uint32_t kind, std::uint32_t payload_length) noexcept {
  std::array<std::byte, 8> fields{};
  putLe(fields.data(), kind, 4);
  putLe(fields.data() + 4, payload_length, 4);
  return crc32Update(0, fields);
}

void encodeRecordHeader(std::byte* out, RecordKind kind, std::uint32_t payload_length,
                        std::uint32_t crc) noexcept {
  putLe(out, static_cast<std::uint32_t>(kind), 4);
  putLe(out + 4, payload_length, 4);
  putLe(out + 8, crc, 4);
}

std::size_t topicPayloadBytes(const LogTopic& topic) noexcept {
  return kTopicFixedBytes + kStringLengthBytes + topic.name.size() + kStringLengthBytes +
         topic.type.size();
}

void encodeTopicPayload(std::byte* out, const LogTopic& topic) noexcept {
  putLe(out, topic.id, 4);
  putLe(out + 4, static_cast<std::uint8_t>(topic.reliability), 1);
  putLe(out + 5, static_cast<std::uint8_t>(topic.durability), 1);
  putLe(out + 6, 0, 2);  // reserved
  std::byte* at = out + kTopicFixedBytes;
  for (const std::string* text : {&topic.name, &topic.type}) {
    putLe(at, text->size(), 2);
    at += kStringLengthBytes;
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
  topic.id = getU32(payload.data());
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
    const std::size_t length = getU16(payload.data() + at);
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
  putLe(out, topic_id, 4);
  putLe(out + 4, static_cast<std::uint64_t>(receive_unix_ns), 8);
  putLe(out + 12, static_cast<std::uint64_t>(receive_monotonic_ns), 8);
  putLe(out + 20, static_cast<std::uint64_t>(source_timestamp_ns), 8);
}

void encodeEndPayload(std::byte* out, const EndRecord& end) noexcept {
  putLe(out, end.message_count, 8);
  putLe(out + 8, static_cast<std::uint64_t>(end.end_unix_ns), 8);
}

Expected<EndRecord, std::string> decodeEndPayload(std::span<const std::byte> payload) {
  if (payload.size() < kEndPayloadBytes) {
    return Unexpected(std::string("END payload of ") + std::to_string(payload.size()) +
                      " bytes is shorter than its " + std::to_string(kEndPayloadBytes) +
                      " bytes of fields");
  }
  return EndRecord{getU64(payload.data()), getI64(payload.data() + 8)};
}

}  // namespace raymap::record::detail
