// SPDX-License-Identifier: BSD-3-Clause
// PNG encoding with libpng (Debian's libpng16), into memory, then through an AtomicFileWriter.
#include "src/io/png_writer.hpp"

#include <csetjmp>
#include <cstddef>
#include <cstdio>
#include <new>
#include <string>
#include <vector>

#include <png.h>

#include "src/io/atomic_file.hpp"

namespace raymap::io {
namespace {

constexpr int kBitDepth = 8;              // bits per sample: R, G and B each a byte
constexpr int kCompressionLevel = 6;      // zlib's default trade-off of size against time
constexpr std::size_t kErrorBytes = 200;  // room for libpng's message (its own are shorter)

/// What libpng's callbacks report back: the encoded bytes, and the reason of a failure. libpng
/// reports errors by longjmp (below), so the callbacks leave their results here.
struct Encoding {
  std::vector<std::byte> png;
  char error[kErrorBytes] = "";
};

/// libpng's error callback: keeps the message and jumps back to encode()'s setjmp (it must not
/// return).
[[noreturn]] void onError(png_structp png, png_const_charp message) {
  auto* encoding = static_cast<Encoding*>(png_get_error_ptr(png));
  std::snprintf(encoding->error, sizeof(encoding->error), "%s", message);
  png_longjmp(png, 1);
}

/// libpng's warnings concern reading (and ancillary chunks we never write): nothing to report.
void onWarning(png_structp /*png*/, png_const_charp /*message*/) {}

/// libpng's output: the bytes are appended to Encoding::png. An allocation failure becomes a
/// libpng error once the exception is over (no exception may unwind through libpng's C frames).
void appendBytes(png_structp png, png_bytep data, std::size_t length) {
  auto* encoding = static_cast<Encoding*>(png_get_io_ptr(png));
  bool out_of_memory = false;
  try {
    const auto* bytes = reinterpret_cast<const std::byte*>(data);
    encoding->png.insert(encoding->png.end(), bytes, bytes + length);
  } catch (const std::bad_alloc&) {
    out_of_memory = true;
  }
  if (out_of_memory) {
    png_error(png, "out of memory for the encoded image");
  }
}

/// Nothing to flush: the image is written to the file after encoding.
void flushNothing(png_structp /*png*/) {}

/// Writes the header, the rows and the end. Called after encode()'s setjmp: any libpng error
/// jumps from here straight back to it (this frame holds nothing that needs destroying).
void writeImage(png_structp png, png_infop info, int width, int height, const std::uint8_t* rgb) {
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height),
               kBitDepth, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, kCompressionLevel);
  png_write_info(png, info);
  const std::size_t stride = static_cast<std::size_t>(width) * 3;
  for (std::size_t y = 0; y < static_cast<std::size_t>(height); ++y) {
    png_write_row(png, rgb + y * stride);
  }
  png_write_end(png, nullptr);
}

/// Encodes the image into `encoding.png`; false with `encoding.error` set when libpng fails.
/// Nothing in this frame changes after setjmp, so the longjmp of an error leaves it intact.
bool encode(int width, int height, const std::uint8_t* rgb, Encoding& encoding) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &encoding, onError, onWarning);
  png_infop info = png != nullptr ? png_create_info_struct(png) : nullptr;
  if (info == nullptr) {
    png_destroy_write_struct(&png, nullptr);
    std::snprintf(encoding.error, sizeof(encoding.error), "%s", "libpng is out of memory");
    return false;
  }
  if (setjmp(png_jmpbuf(png)) != 0) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_set_write_fn(png, &encoding, appendBytes, flushNothing);
  writeImage(png, info, width, height, rgb);
  png_destroy_write_struct(&png, &info);
  return true;
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

  Encoding encoding;
  if (!encode(width, height, rgb.data(), encoding)) {
    return fail(ErrorCode::kCapacity,
                "cannot write '" + path + "': libpng: " + std::string(encoding.error));
  }
  auto file = AtomicFileWriter::open(path);
  if (!file.has_value()) {
    return Unexpected(std::move(file).error());
  }
  if (auto written = file->write(encoding.png); !written.has_value()) {
    return written;
  }
  return file->commit();
}

}  // namespace raymap::io
