// SPDX-License-Identifier: BSD-3-Clause
// The PLY header: format, elements and their typed properties, parsed with line-numbered errors.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "raymap/error.hpp"

#include "src/io/byte_reader.hpp"

namespace raymap::io {

/// @brief How the element data after `end_header` is encoded.
enum class PlyFormat : std::uint8_t { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

/// @brief The name used in the header ("ascii", "binary_little_endian", "binary_big_endian").
const char* toString(PlyFormat format) noexcept;

/// @brief A PLY scalar type. The header accepts both spellings (`uchar` or `uint8`, ...).
enum class PlyType : std::uint8_t {
  kInt8,
  kUint8,
  kInt16,
  kUint16,
  kInt32,
  kUint32,
  kFloat32,
  kFloat64,
};

/// @brief The classic name of a type ("char", "uchar", "short", ..., "float", "double").
const char* toString(PlyType type) noexcept;
/// @brief Size of one value in the binary encodings, bytes.
std::size_t sizeOf(PlyType type) noexcept;
/// @brief True for the integer types (the only ones allowed as list counts).
bool isInteger(PlyType type) noexcept;
/// @brief Parses a type name in either spelling; nullopt for an unknown name.
std::optional<PlyType> parsePlyType(std::string_view name) noexcept;

/// @brief One property of an element: a scalar, or a list (a count, then that many items).
struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;  ///< the scalar type, or the item type of a list
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;  ///< type of a list's count (lists only)
};

/// @brief An element (`element NAME COUNT`) and its properties in file order.
struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;

  /// @brief Index of the property called `name`, compared case-insensitively; nullopt if none.
  std::optional<std::size_t> findProperty(std::string_view name) const noexcept;
  /// @brief True when any property is a list (records then have varying sizes).
  bool hasLists() const noexcept;
  /// @brief Bytes of one binary record; only meaningful when !hasLists().
  std::size_t recordBytes() const noexcept;
};

/// @brief A parsed header.
struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<std::string> comments;  ///< `comment` lines, text after the keyword
  std::vector<std::string> obj_info;  ///< `obj_info` lines, text after the keyword
  std::vector<PlyElement> elements;   ///< in file order (the data follows this order)
  std::uint64_t header_lines = 0;     ///< lines up to and including `end_header`
  std::uint64_t header_bytes = 0;     ///< bytes up to and including the `end_header` newline

  /// @brief Index of the element called `name` (case-insensitive); nullopt if none.
  std::optional<std::size_t> findElement(std::string_view name) const noexcept;
};

/// @brief Reads the header from the start of `reader`, leaving it at the first data byte.
/// @return the header, or kFormat "PATH: line N: problem" (or "PATH: not a PLY file ...", or
/// "PATH is empty (0 bytes): not a PLY file").
Result<PlyHeader> parsePlyHeader(ByteReader& reader);

/// @brief Parses a header held in memory (tests, tools); `path` only names the source in errors.
/// The text must contain `end_header`; anything after its line is ignored.
Result<PlyHeader> parsePlyHeader(std::string_view text, const std::string& path);

/// @brief Case-insensitive ASCII comparison (PLY property names are matched this way).
bool equalsIgnoreCase(std::string_view a, std::string_view b) noexcept;

}  // namespace raymap::io
