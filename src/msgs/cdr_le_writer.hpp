// SPDX-License-Identifier: BSD-3-Clause
// Writing XCDR1 little-endian (CDR_LE) messages straight into a byte vector: the payload's size is
// computed first (CdrSizer), the vector resized once (within its capacity once warm) and filled
// through a CdrCursor that takes the same steps. The serializers of src/msgs use it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <vector>

#include "src/core/byte_order.hpp"
#include "src/msgs/ros_time.hpp"

namespace raymap::msgs {

/// CDR_LE: the encapsulation header of little-endian XCDR1 (representation 00 01, options 0).
inline constexpr std::byte kCdrLeHeader[4] = {std::byte{0x00}, std::byte{0x01}, std::byte{0x00},
                                              std::byte{0x00}};

/// @brief Positions relative to the first byte after the encapsulation header, as XCDR1 aligns.
/// Value type; allocates nothing.
class CdrSizer {
 public:
  void align(std::size_t alignment) noexcept {
    size_ = (size_ + alignment - 1) / alignment * alignment;
  }
  void add(std::size_t alignment, std::size_t bytes) noexcept {
    align(alignment);
    size_ += bytes;
  }
  void string(std::string_view text) noexcept { add(4, 4 + text.size() + 1); }
  std::size_t size() const noexcept { return size_; }

 private:
  std::size_t size_ = 0;
};

/// @brief Writes little-endian primitives into a payload sized by a CdrSizer that took the same
/// steps (padding zeroed). Not bounds-checked: the sizer is the bound. Allocates nothing.
class CdrCursor {
 public:
  explicit CdrCursor(std::byte* payload) noexcept : payload_(payload) {}
  void align(std::size_t alignment) noexcept {
    const std::size_t aligned = (at_ + alignment - 1) / alignment * alignment;
    std::memset(payload_ + at_, 0, aligned - at_);
    at_ = aligned;
  }
  template <ByteValue T>
  void put(T value) noexcept {
    align(sizeof(T));
    storeLe(payload_ + at_, value);
    at_ += sizeof(T);
  }
  void string(std::string_view text) noexcept {
    put(static_cast<std::uint32_t>(text.size() + 1));
    if (!text.empty()) {
      std::memcpy(payload_ + at_, text.data(), text.size());
    }
    at_ += text.size();
    payload_[at_++] = std::byte{0};
  }
  /// The next `bytes` bytes, for the caller to fill (unaligned, unzeroed).
  std::byte* raw(std::size_t bytes) noexcept {
    std::byte* p = payload_ + at_;
    at_ += bytes;
    return p;
  }
  std::size_t position() const noexcept { return at_; }

 private:
  std::byte* payload_;
  std::size_t at_ = 0;
};

/// @brief std_msgs/Header: builtin_interfaces/Time (msgs::rosTimeOf) and frame_id. Size it with
/// addStdHeader.
inline void putStdHeader(CdrCursor& cursor, std::int64_t stamp_ns,
                         std::string_view frame_id) noexcept {
  const RosTime t = rosTimeOf(stamp_ns);
  cursor.put(static_cast<std::int32_t>(t.sec));
  cursor.put(t.nanosec);
  cursor.string(frame_id);
}

inline void addStdHeader(CdrSizer& size, std::string_view frame_id) noexcept {
  size.add(4, 8);  // stamp
  size.string(frame_id);
}

/// @brief Resizes `out` to the encapsulation header and `payload_bytes`, writes the header and
/// returns where the payload starts. Allocates only beyond `out`'s capacity.
inline std::byte* startCdrLeMessage(std::vector<std::byte>& out, std::size_t payload_bytes) {
  out.resize(sizeof(kCdrLeHeader) + payload_bytes);
  std::memcpy(out.data(), kCdrLeHeader, sizeof(kCdrLeHeader));
  return out.data() + sizeof(kCdrLeHeader);
}

}  // namespace raymap::msgs
