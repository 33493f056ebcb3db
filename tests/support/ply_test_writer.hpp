// SPDX-License-Identifier: BSD-3-Clause
// Test-only PLY writer: every encoding, any property types and order, gzip, and deliberate damage.
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace raymap::test {

/// @brief The data encodings of PLY 1.0.
enum class PlyEncoding { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

/// @brief The header name of an encoding ("ascii", "binary_little_endian", ...).
const char* toString(PlyEncoding encoding);
/// @brief Lets GoogleTest print the encoding by name in parameterized test names.
void PrintTo(PlyEncoding encoding, std::ostream* os);

/// @brief One property. `type` is written as given (any PLY spelling: "float", "uint8", ...), so
/// tests can also write types the reader must reject. A non-empty `list_count_type` makes it a
/// list property `property list COUNT_TYPE TYPE NAME`.
struct PlyTestProperty {
  std::string type;
  std::string name;
  std::string list_count_type;
};

/// @brief An element and its records.
struct PlyTestElement {
  PlyTestElement(std::string element_name, std::vector<PlyTestProperty> element_properties)
      : name(std::move(element_name)), properties(std::move(element_properties)) {}

  std::string name;
  std::vector<PlyTestProperty> properties;
  /// Every record's values in file order, the way an ASCII PLY lists them: one value per scalar
  /// property; for a list, its item count followed by the items. Written converted to each
  /// property's type (integers truncated toward zero).
  std::vector<double> values;
  std::uint64_t records = 0;
  /// The count written in the header when it should differ from `records` (wrong-count tests).
  std::optional<std::uint64_t> declared_count;

  /// @brief Appends one record (see `values` for the layout).
  void add(std::initializer_list<double> record);
};

/// @brief A whole file.
struct PlyTestFile {
  PlyEncoding encoding = PlyEncoding::kBinaryLittleEndian;
  bool gzip = false;  ///< write through gzopen("wb")
  std::vector<std::string> comments;
  std::vector<PlyTestElement> elements;
  /// Raw bytes appended after the element data (trailing-data tests).
  std::string trailing;
  /// Keep only this many bytes of the element data (truncation tests); the header stays whole.
  std::optional<std::size_t> truncate_data_to;
};

/// @brief The header text (through the `end_header` newline).
std::string encodePlyHeader(const PlyTestFile& file);
/// @brief The element data, as the file's encoding lays it out (no trailing or truncation).
std::string encodePlyData(const PlyTestFile& file);
/// @brief Writes the file (header, data, damage), gzip-compressed when file.gzip.
/// Throws std::runtime_error when the file cannot be written (the test then fails).
void writePly(const std::string& path, const PlyTestFile& file);
/// @brief Writes raw bytes, gzip-compressed when `gzip`. Throws std::runtime_error on failure.
void writeBytes(const std::string& path, std::string_view bytes, bool gzip = false);

}  // namespace raymap::test
