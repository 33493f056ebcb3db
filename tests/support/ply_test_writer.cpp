// SPDX-License-Identifier: BSD-3-Clause
// The test PLY writer: its own encoder (it shares no code with the reader it checks).
#include "tests/support/ply_test_writer.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <ostream>
#include <stdexcept>
#include <utility>

#include <zlib.h>

namespace raymap::test {
namespace {

/// Bytes of a PLY type in any spelling; 0 for a name this writer does not know.
std::size_t typeBytes(std::string_view type) {
  if (type == "char" || type == "int8" || type == "uchar" || type == "uint8") {
    return 1;
  }
  if (type == "short" || type == "int16" || type == "ushort" || type == "uint16") {
    return 2;
  }
  if (type == "int" || type == "int32" || type == "uint" || type == "uint32" || type == "float" ||
      type == "float32") {
    return 4;
  }
  if (type == "double" || type == "float64") {
    return 8;
  }
  return 0;
}

bool isFloat(std::string_view type) {
  return type == "float" || type == "float32" || type == "double" || type == "float64";
}

bool isSigned(std::string_view type) {
  return type == "char" || type == "int8" || type == "short" || type == "int16" || type == "int" ||
         type == "int32";
}

template <class T>
void appendBinary(std::string& out, T value, bool big_endian) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if (big_endian != (std::endian::native == std::endian::big)) {
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) {
      std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
    }
  }
  out.append(bytes, sizeof(T));
}

void appendValue(std::string& out, double value, std::string_view type, PlyEncoding encoding) {
  if (encoding == PlyEncoding::kAscii) {
    char text[40];
    std::to_chars_result result{};
    if (type == "float" || type == "float32") {
      result = std::to_chars(text, text + sizeof(text), static_cast<float>(value));
    } else if (isFloat(type)) {
      result = std::to_chars(text, text + sizeof(text), value);
    } else {
      result = std::to_chars(text, text + sizeof(text), static_cast<long long>(value));
    }
    out.append(text, result.ptr);
    return;
  }
  const bool big = encoding == PlyEncoding::kBinaryBigEndian;
  const std::size_t bytes = typeBytes(type);
  if (type == "float" || type == "float32") {
    appendBinary(out, static_cast<float>(value), big);
  } else if (bytes == 8) {
    appendBinary(out, value, big);
  } else if (bytes == 1) {
    isSigned(type) ? appendBinary(out, static_cast<std::int8_t>(value), big)
                   : appendBinary(out, static_cast<std::uint8_t>(value), big);
  } else if (bytes == 2) {
    isSigned(type) ? appendBinary(out, static_cast<std::int16_t>(value), big)
                   : appendBinary(out, static_cast<std::uint16_t>(value), big);
  } else if (bytes == 4) {
    isSigned(type) ? appendBinary(out, static_cast<std::int32_t>(value), big)
                   : appendBinary(out, static_cast<std::uint32_t>(value), big);
  } else {
    throw std::runtime_error("ply_test_writer: cannot encode values of type '" + std::string(type) +
                             "' in binary");
  }
}

}  // namespace

const char* toString(PlyEncoding encoding) {
  switch (encoding) {
    case PlyEncoding::kAscii:
      return "ascii";
    case PlyEncoding::kBinaryLittleEndian:
      return "binary_little_endian";
    case PlyEncoding::kBinaryBigEndian:
      return "binary_big_endian";
  }
  return "unknown";
}

void PrintTo(PlyEncoding encoding, std::ostream* os) { *os << toString(encoding); }

void PlyTestElement::add(std::initializer_list<double> record) {
  values.insert(values.end(), record.begin(), record.end());
  ++records;
}

std::string encodePlyHeader(const PlyTestFile& file) {
  std::string header = "ply\nformat " + std::string(toString(file.encoding)) + " 1.0\n";
  for (const std::string& comment : file.comments) {
    header += "comment " + comment + "\n";
  }
  for (const PlyTestElement& element : file.elements) {
    header += "element " + element.name + " " +
              std::to_string(element.declared_count.value_or(element.records)) + "\n";
    for (const PlyTestProperty& property : element.properties) {
      header += property.list_count_type.empty()
                    ? "property " + property.type + " " + property.name + "\n"
                    : "property list " + property.list_count_type + " " + property.type + " " +
                          property.name + "\n";
    }
  }
  return header + "end_header\n";
}

std::string encodePlyData(const PlyTestFile& file) {
  std::string data;
  for (const PlyTestElement& element : file.elements) {
    std::size_t next = 0;  // index into element.values
    const auto take = [&]() {
      if (next >= element.values.size()) {
        throw std::runtime_error("ply_test_writer: element '" + element.name +
                                 "' has fewer values than its records need");
      }
      return element.values[next++];
    };
    for (std::uint64_t record = 0; record < element.records; ++record) {
      bool first = true;
      const auto put = [&](double value, const std::string& type) {
        if (file.encoding == PlyEncoding::kAscii && !first) {
          data += ' ';
        }
        first = false;
        appendValue(data, value, type, file.encoding);
      };
      for (const PlyTestProperty& property : element.properties) {
        if (property.list_count_type.empty()) {
          put(take(), property.type);
          continue;
        }
        const double items = take();
        put(items, property.list_count_type);
        for (std::uint64_t i = 0; i < static_cast<std::uint64_t>(items); ++i) {
          put(take(), property.type);
        }
      }
      if (file.encoding == PlyEncoding::kAscii) {
        data += '\n';
      }
    }
    if (next != element.values.size()) {
      throw std::runtime_error("ply_test_writer: element '" + element.name +
                               "' has more values than its records use");
    }
  }
  return data;
}

void writePly(const std::string& path, const PlyTestFile& file) {
  std::string data = encodePlyData(file);
  if (file.truncate_data_to && *file.truncate_data_to < data.size()) {
    data.resize(*file.truncate_data_to);
  }
  writeBytes(path, encodePlyHeader(file) + data + file.trailing, file.gzip);
}

void writeBytes(const std::string& path, std::string_view bytes, bool gzip) {
  if (gzip) {
    gzFile out = gzopen(path.c_str(), "wb");
    if (out == nullptr) {
      throw std::runtime_error("cannot create " + path);
    }
    std::size_t written = 0;
    while (written < bytes.size()) {
      const unsigned chunk = static_cast<unsigned>(
          std::min<std::size_t>(bytes.size() - written, std::size_t{1} << 20));
      if (gzwrite(out, bytes.data() + written, chunk) != static_cast<int>(chunk)) {
        gzclose(out);
        throw std::runtime_error("cannot write " + path);
      }
      written += chunk;
    }
    if (gzclose(out) != Z_OK) {
      throw std::runtime_error("cannot finish " + path);
    }
    return;
  }
  std::FILE* out = std::fopen(path.c_str(), "wb");
  if (out == nullptr) {
    throw std::runtime_error("cannot create " + path);
  }
  const bool ok = std::fwrite(bytes.data(), 1, bytes.size(), out) == bytes.size();
  if (std::fclose(out) != 0 || !ok) {
    throw std::runtime_error("cannot write " + path);
  }
}

}  // namespace raymap::test
