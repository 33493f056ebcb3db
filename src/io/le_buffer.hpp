// SPDX-License-Identifier: BSD-3-Clause
// Little-endian binary records (PLY bodies) buffered on their way into an AtomicFileWriter.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "raymap/error.hpp"

#include "src/core/byte_order.hpp"
#include "src/io/atomic_file.hpp"

namespace raymap::io {

/// @brief Appends values in little-endian order (src/core/byte_order.hpp: correct on any host),
/// and writes them out once a megabyte has built up. Not thread-safe; offline tools only
/// (allocates).
class LeBuffer {
 public:
  static constexpr std::size_t kFlushBytes = std::size_t{1} << 20;

  void u8(std::uint8_t v) { appendLe(bytes_, v); }
  void u32(std::uint32_t v) { appendLe(bytes_, v); }
  /// A float32 (the value is rounded from double).
  void f32(double v) { appendLe(bytes_, static_cast<float>(v)); }
  /// @brief Writes what is still buffered and commits the file (renames it into place).
  Expected<void, Error> finish(AtomicFileWriter& writer) {
    if (auto ok = flush(writer, true); !ok) {
      return ok;
    }
    return writer.commit();
  }
  /// @brief Writes what is buffered once it is large (or always, when `force`).
  Expected<void, Error> flush(AtomicFileWriter& writer, bool force) {
    if (bytes_.empty() || (!force && bytes_.size() < kFlushBytes)) {
      return {};
    }
    auto ok = writer.write(bytes_);
    bytes_.clear();
    return ok;
  }

 private:
  std::vector<std::byte> bytes_;
};

}  // namespace raymap::io
