// SPDX-License-Identifier: BSD-3-Clause
// The bounded XCDR1 reader.
#include "src/msgs/cdr_reader.hpp"

#include <bit>
#include <cstring>

#include "src/core/byte_order.hpp"

namespace raymap::msgs {

CdrReader::CdrReader(std::span<const std::byte> cdr) noexcept {
  if (cdr.size() < 4 || cdr[0] != std::byte{0} ||
      (cdr[1] != std::byte{0} && cdr[1] != std::byte{1})) {
    return;
  }
  little_endian_ = cdr[1] == std::byte{1};
  payload_ = cdr.subspan(4);
  ok_ = true;
}

bool CdrReader::align(std::size_t alignment) noexcept {
  if (!ok_) {
    return false;
  }
  const std::size_t aligned = (position_ + alignment - 1) / alignment * alignment;
  if (aligned > payload_.size()) {
    ok_ = false;
    return false;
  }
  position_ = aligned;
  return true;
}

template <class T>
bool CdrReader::readPrimitive(T& out) noexcept {
  if (!align(sizeof(T)) || payload_.size() - position_ < sizeof(T)) {
    ok_ = false;
    return false;
  }
  out = loadEndian<T>(payload_.data() + position_,
                      little_endian_ ? std::endian::little : std::endian::big);
  position_ += sizeof(T);
  return true;
}

bool CdrReader::readU8(std::uint8_t& out) noexcept { return readPrimitive(out); }
bool CdrReader::readBool(bool& out) noexcept {
  std::uint8_t value = 0;
  if (!readPrimitive(value)) {
    return false;
  }
  out = value != 0;
  return true;
}
bool CdrReader::readU16(std::uint16_t& out) noexcept { return readPrimitive(out); }
bool CdrReader::readU32(std::uint32_t& out) noexcept { return readPrimitive(out); }
bool CdrReader::readI32(std::int32_t& out) noexcept { return readPrimitive(out); }
bool CdrReader::readU64(std::uint64_t& out) noexcept { return readPrimitive(out); }
bool CdrReader::readF32(float& out) noexcept { return readPrimitive(out); }
bool CdrReader::readF64(double& out) noexcept { return readPrimitive(out); }

bool CdrReader::readString(std::string& out) {
  std::string_view view;
  if (!readString(view)) {
    return false;
  }
  out.assign(view);
  return true;
}

bool CdrReader::readString(std::string_view& out) noexcept {
  std::uint32_t length = 0;
  if (!readU32(length)) {
    return false;
  }
  if (length == 0) {
    out = {};
    return true;
  }
  if (length > remaining()) {
    ok_ = false;
    return false;
  }
  const auto* chars = reinterpret_cast<const char*>(payload_.data() + position_);
  if (chars[length - 1] != '\0') {
    ok_ = false;
    malformed_ = true;
    return false;
  }
  position_ += length;
  // Stops at an embedded NUL like a C reader of the string would.
  out = std::string_view(chars, std::strlen(chars));
  return true;
}

bool CdrReader::readSequenceLength(std::uint32_t& count, std::size_t min_element_bytes) noexcept {
  std::uint32_t value = 0;
  if (!readU32(value)) {
    return false;
  }
  if (min_element_bytes > 0 && value > remaining() / min_element_bytes) {
    ok_ = false;
    return false;
  }
  count = value;
  return true;
}

bool CdrReader::readBytes(std::size_t count, std::span<const std::byte>& out) noexcept {
  if (!ok_ || count > remaining()) {
    ok_ = false;
    return false;
  }
  out = payload_.subspan(position_, count);
  position_ += count;
  return true;
}

bool CdrReader::skip(std::size_t count) noexcept {
  if (!ok_ || count > remaining()) {
    ok_ = false;
    return false;
  }
  position_ += count;
  return true;
}

}  // namespace raymap::msgs
