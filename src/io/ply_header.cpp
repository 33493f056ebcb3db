// SPDX-License-Identifier: BSD-3-Clause
// PLY header parsing: one line at a time, from a ByteReader or from text in memory.
#include "src/io/ply_header.hpp"

#include <array>
#include <charconv>
#include <string>
#include <unordered_set>
#include <utility>

namespace raymap::io {
namespace {

struct TypeName {
  std::string_view name;
  PlyType type;
};

// Both spellings of the PLY 1.0 specification and of later writers (rply, tinyply, PCL).
constexpr std::array<TypeName, 16> kTypeNames{{
    {"char", PlyType::kInt8},
    {"int8", PlyType::kInt8},
    {"uchar", PlyType::kUint8},
    {"uint8", PlyType::kUint8},
    {"short", PlyType::kInt16},
    {"int16", PlyType::kInt16},
    {"ushort", PlyType::kUint16},
    {"uint16", PlyType::kUint16},
    {"int", PlyType::kInt32},
    {"int32", PlyType::kInt32},
    {"uint", PlyType::kUint32},
    {"uint32", PlyType::kUint32},
    {"float", PlyType::kFloat32},
    {"float32", PlyType::kFloat32},
    {"double", PlyType::kFloat64},
    {"float64", PlyType::kFloat64},
}};

bool isSpace(char c) noexcept {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

std::string_view trim(std::string_view text) noexcept {
  while (!text.empty() && isSpace(text.front())) {
    text.remove_prefix(1);
  }
  while (!text.empty() && isSpace(text.back())) {
    text.remove_suffix(1);
  }
  return text;
}

/// Splits off the first whitespace-separated word of `text` (advancing `text` past it).
std::string_view nextWord(std::string_view& text) noexcept {
  text = trim(text);
  std::size_t end = 0;
  while (end < text.size() && !isSpace(text[end])) {
    ++end;
  }
  const std::string_view word = text.substr(0, end);
  text.remove_prefix(end);
  return word;
}

/// ASCII lower case: PLY names are compared case-insensitively (equalsIgnoreCase).
std::string lowerCase(std::string_view text) {
  std::string lower(text);
  for (char& c : lower) {
    if (c >= 'A' && c <= 'Z') {
      c = static_cast<char>(c - 'A' + 'a');
    }
  }
  return lower;
}

/// Builds the header from its lines, in order; every error names the path and the line.
class HeaderParser {
 public:
  explicit HeaderParser(const std::string& path) : path_(path) {}

  /// @return true once `end_header` was seen.
  Result<bool> feed(std::string_view line, std::uint64_t line_number) {
    line_number_ = line_number;
    if (line_number == 1) {
      if (trim(line) != "ply") {
        return notPly();
      }
      return false;
    }
    std::string_view rest = line;
    const std::string_view keyword = nextWord(rest);
    if (keyword.empty()) {
      return false;  // blank lines carry nothing; tolerate them
    }
    if (keyword == "comment" || keyword == "obj_info") {
      // Keep the text as written, minus the one separator after the keyword.
      std::string_view text = rest;
      if (!text.empty() && isSpace(text.front())) {
        text.remove_prefix(1);
      }
      while (!text.empty() && text.back() == '\r') {
        text.remove_suffix(1);
      }
      (keyword == "comment" ? header_.comments : header_.obj_info).emplace_back(text);
      return false;
    }
    if (keyword == "format") {
      return parseFormat(rest);
    }
    if (keyword == "element") {
      return parseElement(rest);
    }
    if (keyword == "property") {
      return parseProperty(rest);
    }
    if (keyword == "end_header") {
      if (!seen_format_) {
        return lineError("'end_header' before any 'format' line");
      }
      header_.header_lines = line_number;
      return true;
    }
    return lineError("unknown header keyword '" + std::string(keyword) + "'");
  }

  Unexpected<Error> notPly() const {
    return fail(ErrorCode::kFormat, path_ + ": not a PLY file (missing 'ply' magic)");
  }
  Unexpected<Error> empty() const {
    return fail(ErrorCode::kFormat, path_ + " is empty (0 bytes): not a PLY file");
  }
  Unexpected<Error> missingEnd() const {
    return fail(ErrorCode::kFormat, path_ + ": header ends without 'end_header'");
  }
  PlyHeader take() { return std::move(header_); }

 private:
  Unexpected<Error> lineError(const std::string& problem) const {
    return fail(ErrorCode::kFormat,
                path_ + ": line " + std::to_string(line_number_) + ": " + problem);
  }

  Result<bool> parseFormat(std::string_view rest) {
    if (seen_format_) {
      return lineError("a second 'format' line");
    }
    const std::string_view name = nextWord(rest);
    const std::string_view version = nextWord(rest);
    if (name.empty() || version.empty() || !trim(rest).empty()) {
      return lineError("expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
    }
    if (name == "ascii") {
      header_.format = PlyFormat::kAscii;
    } else if (name == "binary_little_endian") {
      header_.format = PlyFormat::kBinaryLittleEndian;
    } else if (name == "binary_big_endian") {
      header_.format = PlyFormat::kBinaryBigEndian;
    } else {
      return lineError("unknown format '" + std::string(name) + "'");
    }
    if (version != "1.0" && version != "1") {
      return lineError("unsupported PLY version '" + std::string(version) + "' (only 1.0)");
    }
    seen_format_ = true;
    return false;
  }

  Result<bool> parseElement(std::string_view rest) {
    const std::string_view name = nextWord(rest);
    const std::string_view count_text = nextWord(rest);
    if (name.empty() || count_text.empty() || !trim(rest).empty()) {
      return lineError("expected 'element NAME COUNT'");
    }
    std::uint64_t count = 0;
    const auto [end, error] =
        std::from_chars(count_text.data(), count_text.data() + count_text.size(), count);
    if (error != std::errc() || end != count_text.data() + count_text.size()) {
      return lineError("invalid count '" + std::string(count_text) + "' for element '" +
                       std::string(name) + "'");
    }
    if (!element_names_.insert(lowerCase(name)).second) {
      return lineError("element '" + std::string(name) + "' declared twice");
    }
    header_.elements.push_back(PlyElement{std::string(name), count, {}});
    property_names_.clear();
    return false;
  }

  Result<bool> parseProperty(std::string_view rest) {
    if (header_.elements.empty()) {
      return lineError("'property' before any 'element'");
    }
    PlyElement& element = header_.elements.back();
    PlyProperty property;
    std::string_view type_name = nextWord(rest);
    if (type_name == "list") {
      property.is_list = true;
      const std::string_view count_name = nextWord(rest);
      const auto count_type = parsePlyType(count_name);
      if (!count_type) {
        return lineError("unknown list count type '" + std::string(count_name) + "'");
      }
      if (!isInteger(*count_type)) {
        return lineError("list count type '" + std::string(count_name) +
                         "' is not an integer type");
      }
      property.count_type = *count_type;
      type_name = nextWord(rest);
    }
    const auto type = parsePlyType(type_name);
    if (!type) {
      return lineError(type_name.empty()
                           ? std::string("expected 'property TYPE NAME'")
                           : "unknown property type '" + std::string(type_name) + "'");
    }
    property.type = *type;
    const std::string_view name = nextWord(rest);
    if (name.empty() || !trim(rest).empty()) {
      return lineError(property.is_list ? "expected 'property list COUNT_TYPE ITEM_TYPE NAME'"
                                        : "expected 'property TYPE NAME'");
    }
    if (!property_names_.insert(lowerCase(name)).second) {
      return lineError("property '" + std::string(name) + "' declared twice in element '" +
                       element.name + "'");
    }
    property.name = std::string(name);
    element.properties.push_back(std::move(property));
    return false;
  }

  const std::string& path_;
  PlyHeader header_;
  // The names seen so far, lower-cased, to find a duplicate in constant time: a search of the
  // properties declared before made a header of n properties cost n^2 / 2 name comparisons
  // (35 s for 100,000 properties).
  std::unordered_set<std::string> element_names_;
  std::unordered_set<std::string> property_names_;  // of the current (last) element
  std::uint64_t line_number_ = 0;
  bool seen_format_ = false;
};

}  // namespace

const char* toString(PlyFormat format) noexcept {
  switch (format) {
    case PlyFormat::kAscii:
      return "ascii";
    case PlyFormat::kBinaryLittleEndian:
      return "binary_little_endian";
    case PlyFormat::kBinaryBigEndian:
      return "binary_big_endian";
  }
  return "unknown";
}

const char* toString(PlyType type) noexcept {
  switch (type) {
    case PlyType::kInt8:
      return "char";
    case PlyType::kUint8:
      return "uchar";
    case PlyType::kInt16:
      return "short";
    case PlyType::kUint16:
      return "ushort";
    case PlyType::kInt32:
      return "int";
    case PlyType::kUint32:
      return "uint";
    case PlyType::kFloat32:
      return "float";
    case PlyType::kFloat64:
      return "double";
  }
  return "unknown";
}

std::size_t sizeOf(PlyType type) noexcept {
  switch (type) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 0;
}

bool isInteger(PlyType type) noexcept {
  return type != PlyType::kFloat32 && type != PlyType::kFloat64;
}

std::optional<PlyType> parsePlyType(std::string_view name) noexcept {
  for (const TypeName& entry : kTypeNames) {
    if (entry.name == name) {
      return entry.type;
    }
  }
  return std::nullopt;
}

bool equalsIgnoreCase(std::string_view a, std::string_view b) noexcept {
  if (a.size() != b.size()) {
    return false;
  }
  for (std::size_t i = 0; i < a.size(); ++i) {
    const auto lower = [](char c) {
      return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
    };
    if (lower(a[i]) != lower(b[i])) {
      return false;
    }
  }
  return true;
}

std::optional<std::size_t> PlyElement::findProperty(std::string_view property_name) const noexcept {
  for (std::size_t i = 0; i < properties.size(); ++i) {
    if (equalsIgnoreCase(properties[i].name, property_name)) {
      return i;
    }
  }
  return std::nullopt;
}

bool PlyElement::hasLists() const noexcept {
  for (const PlyProperty& property : properties) {
    if (property.is_list) {
      return true;
    }
  }
  return false;
}

std::size_t PlyElement::recordBytes() const noexcept {
  std::size_t bytes = 0;
  for (const PlyProperty& property : properties) {
    bytes += sizeOf(property.type);
  }
  return bytes;
}

std::optional<std::size_t> PlyHeader::findElement(std::string_view element_name) const noexcept {
  for (std::size_t i = 0; i < elements.size(); ++i) {
    if (equalsIgnoreCase(elements[i].name, element_name)) {
      return i;
    }
  }
  return std::nullopt;
}

Result<PlyHeader> parsePlyHeader(ByteReader& reader) {
  HeaderParser parser(reader.path());
  for (;;) {
    std::string_view line;
    auto got = reader.readLine(line);
    if (!got) {
      // A first "line" longer than the buffer is binary data, not a header.
      if (reader.lineNumber() == 0 && got.error().code == ErrorCode::kFormat) {
        return parser.notPly();
      }
      return Unexpected(std::move(got).error());
    }
    if (!*got) {
      if (reader.lineNumber() == 0) {
        return reader.position() == 0 ? parser.empty() : parser.notPly();
      }
      return parser.missingEnd();
    }
    auto done = parser.feed(line, reader.lineNumber());
    if (!done) {
      return Unexpected(std::move(done).error());
    }
    if (*done) {
      PlyHeader header = parser.take();
      header.header_bytes = reader.position();
      return header;
    }
  }
}

Result<PlyHeader> parsePlyHeader(std::string_view text, const std::string& path) {
  HeaderParser parser(path);
  std::uint64_t line_number = 0;
  std::size_t offset = 0;
  while (offset < text.size()) {
    const std::size_t newline = text.find('\n', offset);
    const std::size_t end = newline == std::string_view::npos ? text.size() : newline;
    std::string_view line = text.substr(offset, end - offset);
    offset = newline == std::string_view::npos ? text.size() : newline + 1;
    if (!line.empty() && line.back() == '\r') {
      line.remove_suffix(1);
    }
    auto done = parser.feed(line, ++line_number);
    if (!done) {
      return Unexpected(std::move(done).error());
    }
    if (*done) {
      PlyHeader header = parser.take();
      header.header_bytes = offset;
      return header;
    }
  }
  if (text.empty()) {
    return parser.empty();
  }
  return line_number == 0 ? parser.notPly() : parser.missingEnd();
}

}  // namespace raymap::io
