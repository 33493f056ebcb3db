// SPDX-License-Identifier: BSD-3-Clause
// PNG encoding: signature, IHDR, zlib-compressed IDAT chunks, IEND, each with its CRC-32.
#include "src/io/png_writer.hpp"

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdlib>
#include <limits>
#include <vector>

#include <zlib.h>

#include "src/io/atomic_file.hpp"

namespace raymap::io {
namespace {

constexpr std::array<std::uint8_t, 8> kSignature{0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
// IDAT data is split into chunks of at most this many bytes (any split is valid PNG; bounded
// chunks keep every length far below the format's 2^31 - 1 and zlib's uInt).
constexpr std::size_t kIdatChunkBytes = std::size_t{1} << 20;
constexpr int kCompressionLevel = 6;  // zlib's default trade-off
constexpr std::uint8_t kFilterNone = 0;
constexpr std::uint8_t kFilterUp = 2;

void putU32(std::vector<std::uint8_t>& out, std::uint32_t value) {
  out.push_back(static_cast<std::uint8_t>(value >> 24));
  out.push_back(static_cast<std::uint8_t>(value >> 16));
  out.push_back(static_cast<std::uint8_t>(value >> 8));
  out.push_back(static_cast<std::uint8_t>(value));
}

/// Appends one chunk: length, type, data, CRC-32 of type and data.
void appendChunk(std::vector<std::uint8_t>& out, const char (&type)[5],
                 std::span<const std::uint8_t> data) {
  putU32(out, static_cast<std::uint32_t>(data.size()));
  const std::size_t type_at = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), data.begin(), data.end());
  const uLong crc = crc32(0L, out.data() + type_at, static_cast<uInt>(4 + data.size()));
  putU32(out, static_cast<std::uint32_t>(crc));
}

/// Sum of the filtered bytes read as signed values' magnitudes: the PNG specification's
/// suggested heuristic for choosing a row filter (smaller compresses better, usually).
std::uint64_t filteredCost(std::span<const std::uint8_t> row, std::span<const std::uint8_t> prior) {
  std::uint64_t cost = 0;
  for (std::size_t k = 0; k < row.size(); ++k) {
    const std::uint8_t up = prior.empty() ? row[k] : static_cast<std::uint8_t>(row[k] - prior[k]);
    cost += static_cast<std::uint64_t>(std::abs(static_cast<int>(static_cast<std::int8_t>(up))));
  }
  return cost;
}

/// The filtered scanlines: each row is a filter byte, then the row. Filter None or Up per row,
/// whichever the heuristic prefers; the blocky images raymap writes favour Up (repeated rows
/// become zeros).
std::vector<std::uint8_t> filterRows(int width, int height, std::span<const std::uint8_t> rgb) {
  const std::size_t stride = static_cast<std::size_t>(width) * 3;
  std::vector<std::uint8_t> raw;
  raw.reserve((stride + 1) * static_cast<std::size_t>(height));
  for (std::size_t y = 0; y < static_cast<std::size_t>(height); ++y) {
    const std::span<const std::uint8_t> row = rgb.subspan(y * stride, stride);
    const bool up =
        y > 0 && filteredCost(row, rgb.subspan((y - 1) * stride, stride)) < filteredCost(row, {});
    raw.push_back(up ? kFilterUp : kFilterNone);
    if (up) {
      const std::uint8_t* prior = rgb.data() + (y - 1) * stride;
      for (std::size_t k = 0; k < stride; ++k) {
        raw.push_back(static_cast<std::uint8_t>(row[k] - prior[k]));
      }
    } else {
      raw.insert(raw.end(), row.begin(), row.end());
    }
  }
  return raw;
}

}  // namespace

Expected<void, Error> writePng(const std::string& path, int width, int height,
                               std::span<const std::uint8_t> rgb) {
  if (width < 1 || height < 1 || width > kMaxPngSide || height > kMaxPngSide) {
    return fail(ErrorCode::kInvalidArgument,
                "cannot write '" + path + "': image size " + std::to_string(width) + " x " +
                    std::to_string(height) + " is outside 1 to " + std::to_string(kMaxPngSide));
  }
  const std::size_t expected_bytes =
      static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3;
  if (rgb.size() != expected_bytes) {
    return fail(ErrorCode::kInvalidArgument,
                "cannot write '" + path + "': " + std::to_string(rgb.size()) + " RGB bytes for a " +
                    std::to_string(width) + " x " + std::to_string(height) + " image (expected " +
                    std::to_string(expected_bytes) + ")");
  }

  const std::vector<std::uint8_t> raw = filterRows(width, height, rgb);
  if (raw.size() > std::numeric_limits<uLong>::max()) {
    return fail(ErrorCode::kCapacity, "cannot write '" + path + "': image too large for zlib");
  }
  uLongf compressed_size = compressBound(static_cast<uLong>(raw.size()));
  std::vector<std::uint8_t> compressed(compressed_size);
  const int status = compress2(compressed.data(), &compressed_size, raw.data(),
                               static_cast<uLong>(raw.size()), kCompressionLevel);
  if (status != Z_OK) {
    return fail(ErrorCode::kCapacity, "cannot write '" + path + "': zlib compress2 failed (" +
                                          std::string(zError(status)) + ")");
  }
  compressed.resize(compressed_size);

  std::vector<std::uint8_t> png(kSignature.begin(), kSignature.end());
  png.reserve(png.size() + compressed.size() + 64 + 12 * (compressed.size() / kIdatChunkBytes));
  std::vector<std::uint8_t> header;
  putU32(header, static_cast<std::uint32_t>(width));
  putU32(header, static_cast<std::uint32_t>(height));
  header.push_back(8);  // bit depth
  header.push_back(2);  // colour type: truecolour (RGB)
  header.push_back(0);  // compression: deflate
  header.push_back(0);  // filter method: adaptive
  header.push_back(0);  // interlace: none
  appendChunk(png, "IHDR", header);
  const std::span<const std::uint8_t> data(compressed);
  for (std::size_t at = 0; at < data.size(); at += kIdatChunkBytes) {
    appendChunk(png, "IDAT", data.subspan(at, std::min(kIdatChunkBytes, data.size() - at)));
  }
  appendChunk(png, "IEND", {});

  auto file = AtomicFileWriter::open(path);
  if (!file.has_value()) {
    return Unexpected(std::move(file).error());
  }
  if (auto written = file->write(std::as_bytes(std::span<const std::uint8_t>(png)));
      !written.has_value()) {
    return written;
  }
  return file->commit();
}

}  // namespace raymap::io
