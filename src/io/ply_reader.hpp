// SPDX-License-Identifier: BSD-3-Clause
// Streamed decoding of a PLY file's `vertex` element into rows of doubles, in every encoding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "raymap/error.hpp"

#include "src/io/byte_reader.hpp"
#include "src/io/ply_header.hpp"

namespace raymap::io {

namespace detail {
/// Converts `count` binary values of one property, `stride` bytes apart, to doubles written
/// `out_stride` doubles apart. One instance per (type, byte order); chosen once per column.
using PlyColumnDecoder = void (*)(const std::byte* first, std::size_t stride, std::size_t count,
                                  double* out, std::size_t out_stride) noexcept;

/// One selected property of the vertex element.
struct PlyColumn {
  std::size_t property = 0;  // index in the vertex element's properties
  std::size_t offset = 0;    // byte offset in a fixed-size binary record
  PlyColumnDecoder decode = nullptr;
};
}  // namespace detail

/// @brief Reads the `vertex` element of a PLY file (ASCII, binary little or big endian, plain or
/// gzip), a bounded chunk at a time. Any property order and numeric type is accepted; the caller
/// selects the properties it wants and receives them as doubles (integers as plain numbers).
/// Elements before `vertex` are skipped (lists included); elements after it are never read.
/// When `vertex` is the last element, bytes (binary) or non-empty lines (ASCII) after the last
/// vertex are an error, so wrong counts are caught.
/// Move-only; not thread-safe.
class PlyVertexReader {
 public:
  /// @brief Opens the file, parses the header and positions the reader at the first vertex.
  /// @return kFormat when the header is bad or has no `vertex` element; kTruncated when the data
  /// ends inside the elements before it; kIo when the file cannot be read.
  static Result<PlyVertexReader> open(const std::string& path,
                                      std::size_t buffer_bytes = ByteReader::kDefaultBufferBytes);

  const std::string& path() const noexcept { return reader_.path(); }
  const PlyHeader& header() const noexcept { return header_; }
  const PlyElement& vertex() const noexcept { return header_.elements[vertex_element_]; }
  bool compressed() const noexcept { return reader_.compressed(); }
  /// @brief Fraction of the file on disk consumed so far (see ByteReader::progress()).
  double progress() const noexcept { return reader_.progress(); }
  /// @brief Vertices decoded so far.
  std::uint64_t verticesRead() const noexcept { return vertices_read_; }

  /// @brief Chooses what read() returns: one column per entry, the value of that property
  /// (index into vertex().properties; scalar properties only), in this order. Call before the
  /// first read(); without a call, read() returns no columns.
  Expected<void, Error> selectColumns(std::span<const std::size_t> property_indices);
  std::size_t columnCount() const noexcept { return columns_.size(); }

  /// @brief Decodes the next vertices into `out`: row-major, columnCount() doubles per vertex.
  /// @param[out] out room for out.size() / columnCount() vertices (at least one).
  /// @return vertices decoded; 0 once all declared vertices are read (after the trailing-data
  /// check). Errors name the path and the vertex (and line for ASCII).
  Result<std::size_t> read(std::span<double> out);

 private:
  PlyVertexReader(ByteReader reader, PlyHeader header, std::size_t vertex_element) noexcept;
  Expected<void, Error> skipElementsBeforeVertex();
  Expected<void, Error> skipBinaryElement(const PlyElement& element);
  Expected<void, Error> skipAsciiElement(const PlyElement& element);
  Result<std::size_t> readBinaryFixed(double* out, std::size_t count);
  Result<std::size_t> readBinaryVariable(double* out, std::size_t count);
  Result<std::size_t> readAscii(double* out, std::size_t count);
  Expected<void, Error> checkNothingAfterLastVertex();
  Unexpected<Error> truncated(const PlyElement& element, std::uint64_t complete) const;

  ByteReader reader_;
  PlyHeader header_;
  std::size_t vertex_element_ = 0;
  std::vector<detail::PlyColumn> columns_;
  std::vector<int> column_of_property_;  // ASCII/variable records: property -> column or -1
  std::size_t record_bytes_ = 0;         // fixed-size binary records, else 0
  std::uint64_t vertices_read_ = 0;
  bool finished_ = false;  // all vertices read and the trailing check done
};

}  // namespace raymap::io
