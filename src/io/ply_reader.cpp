// SPDX-License-Identifier: BSD-3-Clause
// PlyVertexReader: column decoders for binary records, a token walker for ASCII lines.
#include "src/io/ply_reader.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <limits>
#include <string_view>
#include <utility>

#include "src/core/byte_order.hpp"

namespace raymap::io {
namespace {

constexpr double kMaxExactCount = 9007199254740992.0;  // 2^53: larger doubles skip integers

/// Decodes `count` values of type T in the file's byte order `kOrder`, `stride` bytes apart.
template <class T, std::endian kOrder>
void decodeColumn(const std::byte* first, std::size_t stride, std::size_t count, double* out,
                  std::size_t out_stride) noexcept {
  for (std::size_t i = 0; i < count; ++i) {
    out[i * out_stride] = static_cast<double>(loadEndian<T>(first + i * stride, kOrder));
  }
}

template <std::endian kOrder>
detail::PlyColumnDecoder decoderFor(PlyType type) noexcept {
  switch (type) {
    case PlyType::kInt8:
      return &decodeColumn<std::int8_t, kOrder>;
    case PlyType::kUint8:
      return &decodeColumn<std::uint8_t, kOrder>;
    case PlyType::kInt16:
      return &decodeColumn<std::int16_t, kOrder>;
    case PlyType::kUint16:
      return &decodeColumn<std::uint16_t, kOrder>;
    case PlyType::kInt32:
      return &decodeColumn<std::int32_t, kOrder>;
    case PlyType::kUint32:
      return &decodeColumn<std::uint32_t, kOrder>;
    case PlyType::kFloat32:
      return &decodeColumn<float, kOrder>;
    case PlyType::kFloat64:
      return &decodeColumn<double, kOrder>;
  }
  return nullptr;
}

detail::PlyColumnDecoder decoderFor(PlyType type, PlyFormat format) noexcept {
  return format == PlyFormat::kBinaryBigEndian ? decoderFor<std::endian::big>(type)
                                               : decoderFor<std::endian::little>(type);
}

double decodeOne(const std::byte* bytes, PlyType type, PlyFormat format) noexcept {
  double value = 0.0;
  decoderFor(type, format)(bytes, 0, 1, &value, 1);
  return value;
}

bool isSpace(char c) noexcept {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

bool isBlank(std::string_view line) noexcept {
  return std::all_of(line.begin(), line.end(), isSpace);
}

/// Walks the whitespace-separated values of one ASCII line.
class Tokens {
 public:
  explicit Tokens(std::string_view line) noexcept : rest_(line) {}
  /// @return the next value, empty at the end of the line.
  std::string_view next() noexcept {
    std::size_t start = 0;
    while (start < rest_.size() && isSpace(rest_[start])) {
      ++start;
    }
    std::size_t end = start;
    while (end < rest_.size() && !isSpace(rest_[end])) {
      ++end;
    }
    const std::string_view token = rest_.substr(start, end - start);
    rest_.remove_prefix(end);
    return token;
  }
  std::size_t countRemaining() noexcept {
    std::size_t n = 0;
    while (!next().empty()) {
      ++n;
    }
    return n;
  }

 private:
  std::string_view rest_;
};

bool parseNumber(std::string_view token, double& value) noexcept {
  if (!token.empty() && token.front() == '+') {
    token.remove_prefix(1);  // from_chars rejects a leading '+', which some writers emit
  }
  const char* end = token.data() + token.size();
  const auto [stop, error] = std::from_chars(token.data(), end, value);
  return error == std::errc() && stop == end && !token.empty();
}

std::uint64_t saturatingMultiply(std::uint64_t a, std::uint64_t b) noexcept {
  if (a != 0 && b > std::numeric_limits<std::uint64_t>::max() / a) {
    return std::numeric_limits<std::uint64_t>::max();
  }
  return a * b;
}

/// "vertex 12" / "'face' element 3": how messages name one record of an element.
std::string recordName(const PlyElement& element, std::uint64_t number_1based) {
  if (equalsIgnoreCase(element.name, "vertex")) {
    return "vertex " + std::to_string(number_1based);
  }
  return "'" + element.name + "' element " + std::to_string(number_1based);
}

std::string countName(const PlyElement& element) {
  if (equalsIgnoreCase(element.name, "vertex")) {
    return std::to_string(element.count) + (element.count == 1 ? " vertex" : " vertices");
  }
  return std::to_string(element.count) + " '" + element.name + "' elements";
}

}  // namespace

Result<PlyVertexReader> PlyVertexReader::open(const std::string& path, std::size_t buffer_bytes) {
  auto reader = ByteReader::open(path, buffer_bytes);
  if (!reader) {
    return Unexpected(std::move(reader).error());
  }
  auto header = parsePlyHeader(*reader);
  if (!header) {
    return Unexpected(std::move(header).error());
  }
  const auto vertex = header->findElement("vertex");
  if (!vertex) {
    return fail(ErrorCode::kFormat, path + ": the header declares no 'vertex' element");
  }
  PlyVertexReader ply(std::move(*reader), std::move(*header), *vertex);
  if (auto skipped = ply.skipElementsBeforeVertex(); !skipped) {
    return Unexpected(std::move(skipped).error());
  }
  return ply;
}

PlyVertexReader::PlyVertexReader(ByteReader reader, PlyHeader header,
                                 std::size_t vertex_element) noexcept
    : reader_(std::move(reader)), header_(std::move(header)), vertex_element_(vertex_element) {
  const PlyElement& element = vertex();
  record_bytes_ =
      header_.format != PlyFormat::kAscii && !element.hasLists() ? element.recordBytes() : 0;
}

Unexpected<Error> PlyVertexReader::truncated(const PlyElement& element,
                                             std::uint64_t complete) const {
  return fail(ErrorCode::kTruncated, path() + ": truncated: header declares " + countName(element) +
                                         ", data ends in " + recordName(element, complete + 1));
}

Expected<void, Error> PlyVertexReader::skipElementsBeforeVertex() {
  for (std::size_t e = 0; e < vertex_element_; ++e) {
    const PlyElement& element = header_.elements[e];
    auto skipped = header_.format == PlyFormat::kAscii ? skipAsciiElement(element)
                                                       : skipBinaryElement(element);
    if (!skipped) {
      return skipped;
    }
  }
  return {};
}

Expected<void, Error> PlyVertexReader::skipBinaryElement(const PlyElement& element) {
  if (!element.hasLists()) {
    const std::uint64_t bytes = element.recordBytes();
    const std::uint64_t total = saturatingMultiply(element.count, bytes);
    auto skipped = reader_.skip(total);
    if (!skipped) {
      return Unexpected(std::move(skipped).error());
    }
    if (*skipped < total) {
      return truncated(element, *skipped / bytes);
    }
    return {};
  }
  for (std::uint64_t record = 0; record < element.count; ++record) {
    for (const PlyProperty& property : element.properties) {
      if (!property.is_list) {
        auto skipped = reader_.skip(sizeOf(property.type));
        if (!skipped) {
          return Unexpected(std::move(skipped).error());
        }
        if (*skipped < sizeOf(property.type)) {
          return truncated(element, record);
        }
        continue;
      }
      const std::size_t count_bytes = sizeOf(property.count_type);
      auto available = reader_.ensure(count_bytes);
      if (!available) {
        return Unexpected(std::move(available).error());
      }
      if (available->size() < count_bytes) {
        return truncated(element, record);
      }
      const double count = decodeOne(available->data(), property.count_type, header_.format);
      reader_.consume(count_bytes);
      if (count < 0.0) {
        return fail(ErrorCode::kFormat, path() + ": " + recordName(element, record + 1) +
                                            ": negative count in list '" + property.name + "'");
      }
      const std::uint64_t items =
          saturatingMultiply(static_cast<std::uint64_t>(count), sizeOf(property.type));
      auto skipped = reader_.skip(items);
      if (!skipped) {
        return Unexpected(std::move(skipped).error());
      }
      if (*skipped < items) {
        return truncated(element, record);
      }
    }
  }
  return {};
}

Expected<void, Error> PlyVertexReader::skipAsciiElement(const PlyElement& element) {
  std::uint64_t record = 0;
  while (record < element.count) {
    std::string_view line;
    auto got = reader_.readLine(line);
    if (!got) {
      return Unexpected(std::move(got).error());
    }
    if (!*got) {
      return truncated(element, record);
    }
    if (!isBlank(line)) {
      ++record;
    }
  }
  return {};
}

Expected<void, Error> PlyVertexReader::selectColumns(
    std::span<const std::size_t> property_indices) {
  if (vertices_read_ > 0) {
    return fail(ErrorCode::kInvalidArgument,
                path() + ": columns must be selected before the first vertex is read");
  }
  const PlyElement& element = vertex();
  std::vector<std::size_t> offsets(element.properties.size(), 0);
  std::size_t offset = 0;
  for (std::size_t p = 0; p < element.properties.size(); ++p) {
    offsets[p] = offset;
    offset += sizeOf(element.properties[p].type);
  }
  std::vector<detail::PlyColumn> columns;
  std::vector<int> column_of_property(element.properties.size(), -1);
  for (std::size_t c = 0; c < property_indices.size(); ++c) {
    const std::size_t p = property_indices[c];
    if (p >= element.properties.size()) {
      return fail(ErrorCode::kInvalidArgument,
                  path() + ": no vertex property number " + std::to_string(p));
    }
    const PlyProperty& property = element.properties[p];
    if (property.is_list) {
      return fail(ErrorCode::kUnsupported,
                  path() + ": vertex property '" + property.name + "' is a list, not a number");
    }
    if (column_of_property[p] >= 0) {
      return fail(ErrorCode::kInvalidArgument,
                  path() + ": vertex property '" + property.name + "' selected twice");
    }
    column_of_property[p] = static_cast<int>(c);
    columns.push_back(detail::PlyColumn{p, offsets[p], decoderFor(property.type, header_.format)});
  }
  columns_ = std::move(columns);
  column_of_property_ = std::move(column_of_property);
  return {};
}

Result<std::size_t> PlyVertexReader::read(std::span<double> out) {
  if (finished_) {
    return std::size_t{0};
  }
  if (columns_.empty() || out.size() < columns_.size()) {
    return fail(ErrorCode::kInvalidArgument,
                path() + ": read() needs selected columns and room for one vertex");
  }
  const std::uint64_t remaining = vertex().count - vertices_read_;
  if (remaining == 0) {
    if (auto checked = checkNothingAfterLastVertex(); !checked) {
      return Unexpected(std::move(checked).error());
    }
    finished_ = true;
    return std::size_t{0};
  }
  const std::size_t count =
      static_cast<std::size_t>(std::min<std::uint64_t>(remaining, out.size() / columns_.size()));
  if (header_.format == PlyFormat::kAscii) {
    return readAscii(out.data(), count);
  }
  if (record_bytes_ > 0) {
    return readBinaryFixed(out.data(), count);
  }
  return readBinaryVariable(out.data(), count);
}

Result<std::size_t> PlyVertexReader::readBinaryFixed(double* out, std::size_t count) {
  const std::size_t width = columns_.size();
  std::size_t done = 0;
  while (done < count) {
    std::span<const std::byte> available = reader_.buffered();
    if (available.size() < record_bytes_) {
      auto filled = reader_.ensure(record_bytes_);
      if (!filled) {
        return Unexpected(std::move(filled).error());
      }
      available = *filled;
      if (available.size() < record_bytes_) {
        return truncated(vertex(), vertices_read_);
      }
    }
    // Decode every whole record in the buffer, one column at a time: the type switch happens
    // once per column and chunk, and each inner loop is a plain strided load-convert-store.
    const std::size_t n = std::min(count - done, available.size() / record_bytes_);
    double* rows = out + done * width;
    for (std::size_t c = 0; c < width; ++c) {
      const detail::PlyColumn& column = columns_[c];
      column.decode(available.data() + column.offset, record_bytes_, n, rows + c, width);
    }
    reader_.consume(n * record_bytes_);
    done += n;
    vertices_read_ += n;
  }
  return done;
}

Result<std::size_t> PlyVertexReader::readBinaryVariable(double* out, std::size_t count) {
  const PlyElement& element = vertex();
  const std::size_t width = columns_.size();
  for (std::size_t r = 0; r < count; ++r) {
    double* row = out + r * width;
    for (std::size_t p = 0; p < element.properties.size(); ++p) {
      const PlyProperty& property = element.properties[p];
      const std::size_t bytes = sizeOf(property.is_list ? property.count_type : property.type);
      auto available = reader_.ensure(bytes);
      if (!available) {
        return Unexpected(std::move(available).error());
      }
      if (available->size() < bytes) {
        return truncated(element, vertices_read_);
      }
      if (!property.is_list) {
        if (const int c = column_of_property_[p]; c >= 0) {
          row[c] = decodeOne(available->data(), property.type, header_.format);
        }
        reader_.consume(bytes);
        continue;
      }
      const double items = decodeOne(available->data(), property.count_type, header_.format);
      reader_.consume(bytes);
      if (items < 0.0) {
        return fail(ErrorCode::kFormat, path() + ": " + recordName(element, vertices_read_ + 1) +
                                            ": negative count in list '" + property.name + "'");
      }
      const std::uint64_t list_bytes =
          saturatingMultiply(static_cast<std::uint64_t>(items), sizeOf(property.type));
      auto skipped = reader_.skip(list_bytes);
      if (!skipped) {
        return Unexpected(std::move(skipped).error());
      }
      if (*skipped < list_bytes) {
        return truncated(element, vertices_read_);
      }
    }
    ++vertices_read_;
  }
  return count;
}

Result<std::size_t> PlyVertexReader::readAscii(double* out, std::size_t count) {
  const PlyElement& element = vertex();
  const std::size_t width = columns_.size();
  for (std::size_t r = 0; r < count; ++r) {
    std::string_view line;
    do {
      auto got = reader_.readLine(line);
      if (!got) {
        return Unexpected(std::move(got).error());
      }
      if (!*got) {
        return truncated(element, vertices_read_);
      }
    } while (isBlank(line));

    const auto lineError = [&](const std::string& problem) {
      return fail(ErrorCode::kFormat,
                  path() + ": line " + std::to_string(reader_.lineNumber()) + ": " + problem);
    };
    double* row = out + r * width;
    Tokens tokens(line);
    std::size_t expected = 0;  // values this line should hold, known so far
    std::size_t found = 0;
    for (std::size_t p = 0; p < element.properties.size(); ++p) {
      const PlyProperty& property = element.properties[p];
      ++expected;
      const std::string_view token = tokens.next();
      if (token.empty()) {
        return lineError("too few values for vertex " + std::to_string(vertices_read_ + 1) +
                         ": expected " +
                         std::to_string(expected + element.properties.size() - p - 1) + ", found " +
                         std::to_string(found));
      }
      ++found;
      double value = 0.0;
      if (!parseNumber(token, value)) {
        return lineError("vertex " + std::to_string(vertices_read_ + 1) + ": value '" +
                         std::string(token) + "' of property '" + property.name +
                         "' is not a number");
      }
      if (!property.is_list) {
        if (const int c = column_of_property_[p]; c >= 0) {
          row[c] = value;
        }
        continue;
      }
      // Counts are whole numbers; the bound keeps the conversion below defined.
      if (!(value >= 0.0 && value <= kMaxExactCount) || value != std::floor(value)) {
        return lineError("vertex " + std::to_string(vertices_read_ + 1) + ": list '" +
                         property.name + "' has an invalid count '" + std::string(token) + "'");
      }
      const auto items = static_cast<std::uint64_t>(value);
      for (std::uint64_t i = 0; i < items; ++i) {
        ++expected;
        if (tokens.next().empty()) {
          return lineError("too few values for vertex " + std::to_string(vertices_read_ + 1) +
                           ": list '" + property.name + "' declares " + std::to_string(items) +
                           " items, found " + std::to_string(i));
        }
        ++found;
      }
    }
    if (const std::size_t extra = tokens.countRemaining(); extra > 0) {
      return lineError("too many values for vertex " + std::to_string(vertices_read_ + 1) +
                       ": expected " + std::to_string(expected) + ", found " +
                       std::to_string(found + extra));
    }
    ++vertices_read_;
  }
  return count;
}

Expected<void, Error> PlyVertexReader::checkNothingAfterLastVertex() {
  if (vertex_element_ + 1 != header_.elements.size()) {
    return {};  // later elements follow; they are not ours to read
  }
  if (header_.format == PlyFormat::kAscii) {
    std::uint64_t extra_lines = 0;
    std::uint64_t first_line = 0;
    for (;;) {
      std::string_view line;
      auto got = reader_.readLine(line);
      if (!got) {
        return Unexpected(std::move(got).error());
      }
      if (!*got) {
        break;
      }
      if (!isBlank(line)) {
        first_line = extra_lines == 0 ? reader_.lineNumber() : first_line;
        ++extra_lines;
      }
    }
    if (extra_lines > 0) {
      return fail(ErrorCode::kFormat,
                  path() + ": line " + std::to_string(first_line) +
                      ": unexpected data after the last vertex (" + std::to_string(extra_lines) +
                      " more non-empty lines; the header declares " + countName(vertex()) + ")");
    }
    return {};
  }
  auto extra = reader_.skip(std::numeric_limits<std::uint64_t>::max());
  if (!extra) {
    return Unexpected(std::move(extra).error());
  }
  if (*extra > 0) {
    return fail(ErrorCode::kFormat, path() + ": " + std::to_string(*extra) +
                                        " bytes of unexpected data after the last vertex (the "
                                        "header declares " +
                                        countName(vertex()) + ")");
  }
  return {};
}

}  // namespace raymap::io
