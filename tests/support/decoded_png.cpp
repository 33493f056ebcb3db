// SPDX-License-Identifier: BSD-3-Clause
// decodePng: libpng's read path, with its error handling kept inside one function.
#include "tests/support/decoded_png.hpp"

#include <csetjmp>
#include <cstdio>
#include <memory>

#include <gtest/gtest.h>
#include <png.h>

namespace raymap::test {
namespace {

struct FileCloser {
  void operator()(std::FILE* file) const noexcept { std::fclose(file); }
};

/// Reads the whole image of `file` into `out`; false when libpng reports an error (it prints
/// the reason on stderr). libpng reports errors by longjmp to the setjmp below, so nothing
/// between them may own a resource: the read and info structures are made before setjmp and are
/// not changed after it, and `out` is filled only once png_read_png() has returned.
bool readPng(std::FILE* file, DecodedPng& out) {
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png != nullptr ? png_create_info_struct(png) : nullptr;
  if (info == nullptr) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    return false;
  }
  if (setjmp(png_jmpbuf(png)) != 0) {
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  png_init_io(png, file);
  png_read_png(png, info, PNG_TRANSFORM_IDENTITY, nullptr);
  out.width = static_cast<int>(png_get_image_width(png, info));
  out.height = static_cast<int>(png_get_image_height(png, info));
  out.bit_depth = png_get_bit_depth(png, info);
  out.colour_type = png_get_color_type(png, info);
  out.interlace = png_get_interlace_type(png, info);
  const std::size_t row_bytes = png_get_rowbytes(png, info);
  png_bytepp rows = png_get_rows(png, info);
  out.pixels.clear();
  out.pixels.reserve(row_bytes * static_cast<std::size_t>(out.height));
  for (int y = 0; y < out.height; ++y) {
    out.pixels.insert(out.pixels.end(), rows[y], rows[y] + row_bytes);
  }
  png_destroy_read_struct(&png, &info, nullptr);
  return true;
}

}  // namespace

std::optional<DecodedPng> decodePng(const std::string& path) {
  const std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
  if (file == nullptr) {
    ADD_FAILURE() << path << ": cannot be opened";
    return std::nullopt;
  }
  DecodedPng png;
  if (!readPng(file.get(), png)) {
    ADD_FAILURE() << path << ": libpng does not read it as a PNG (its reason is on stderr)";
    return std::nullopt;
  }
  return png;
}

std::string decodedPngBytes(const DecodedPng& png) {
  std::string out = "PNG " + std::to_string(png.width) + " " + std::to_string(png.height) + " " +
                    std::to_string(png.bit_depth) + " " + std::to_string(png.colour_type) + " " +
                    std::to_string(png.interlace) + "\n";
  out.append(png.pixels.begin(), png.pixels.end());
  return out;
}

}  // namespace raymap::test
