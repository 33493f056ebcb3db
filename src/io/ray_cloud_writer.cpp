// SPDX-License-Identifier: BSD-3-Clause
// RayCloudWriter: streams rays as binary little-endian PLY records and patches the vertex count
// into the header on finish().
#include "src/io/ray_cloud_writer.hpp"

#include <algorithm>
#include <bit>
#include <limits>
#include <vector>

#include "src/io/atomic_file.hpp"

namespace raymap::io {
namespace {

// double x y z time, float nx ny nz intensity, uint scan, uchar alpha.
constexpr std::size_t kRecordBytes = 4 * 8 + 4 * 4 + 4 + 1;
constexpr std::size_t kRaysPerChunk = 16384;
// Digits reserved for the vertex count: any std::uint64_t fits.
constexpr std::size_t kCountDigits = 20;

/// The header for `count` vertices. Its length does not depend on the count: a comment line
/// before the element absorbs the digits the count does not use, so finish() can rewrite the
/// header in place and the count line carries exactly the digits, with no padding any PLY parser
/// could trip over.
std::string headerText(std::uint64_t count) {
  const std::string digits = std::to_string(count);
  std::string header =
      "ply\n"
      "format binary_little_endian 1.0\n"
      "comment raymap ray cloud: x y z = sample, n = origin - sample (world frame, metres)\n"
      "comment ";
  header.append(kCountDigits - digits.size(), '.');
  header +=
      "\n"
      "element vertex " +
      digits +
      "\n"
      "property double x\n"
      "property double y\n"
      "property double z\n"
      "property double time\n"
      "property float nx\n"
      "property float ny\n"
      "property float nz\n"
      "property float intensity\n"
      "property uint scan\n"
      "property uchar alpha\n"
      "end_header\n";
  return header;
}

void putLe(std::byte*& out, std::uint64_t v, int bytes) noexcept {
  for (int i = 0; i < bytes; ++i) {
    *out++ = static_cast<std::byte>((v >> (8 * i)) & 0xFFu);
  }
}
void putF64(std::byte*& out, double v) noexcept { putLe(out, std::bit_cast<std::uint64_t>(v), 8); }
void putF32(std::byte*& out, float v) noexcept { putLe(out, std::bit_cast<std::uint32_t>(v), 4); }

class PlyRayCloudWriter final : public RayCloudWriter {
 public:
  explicit PlyRayCloudWriter(AtomicFileWriter file) noexcept : file_(std::move(file)) {}

  Expected<void, Error> write(std::span<const Ray> rays) override {
    if (finished_) {
      return fail(ErrorCode::kInvalidArgument,
                  "cannot write '" + file_.path() + "': the ray cloud is already finished");
    }
    while (!rays.empty()) {
      const std::span<const Ray> chunk = rays.first(std::min(rays.size(), kRaysPerChunk));
      rays = rays.subspan(chunk.size());
      buffer_.resize(chunk.size() * kRecordBytes);
      std::byte* out = buffer_.data();
      for (const Ray& ray : chunk) {
        if (ray.scan > std::numeric_limits<std::uint32_t>::max()) {
          return fail(ErrorCode::kInvalidArgument, "cannot write '" + file_.path() +
                                                       "': scan index " + std::to_string(ray.scan) +
                                                       " does not fit the PLY uint scan property");
        }
        putF64(out, ray.sample.x);
        putF64(out, ray.sample.y);
        putF64(out, ray.sample.z);
        putF64(out, ray.time_s);
        putF32(out, static_cast<float>(ray.origin.x - ray.sample.x));
        putF32(out, static_cast<float>(ray.origin.y - ray.sample.y));
        putF32(out, static_cast<float>(ray.origin.z - ray.sample.z));
        putF32(out, ray.intensity);
        putLe(out, ray.scan, 4);
        *out++ = static_cast<std::byte>((ray.flags & kRayNoReturn) != 0 ? 0u : 255u);
      }
      if (auto ok = file_.write(buffer_); !ok) {
        return ok;
      }
      count_ += chunk.size();
    }
    return {};
  }

  Expected<void, Error> finish() override {
    if (finished_) {
      return fail(ErrorCode::kInvalidArgument,
                  "cannot finish '" + file_.path() + "': already finished");
    }
    finished_ = true;
    if (auto ok = file_.patch(0, headerText(count_)); !ok) {
      return ok;
    }
    return file_.commit();
  }

  std::uint64_t count() const noexcept override { return count_; }

 private:
  AtomicFileWriter file_;
  std::vector<std::byte> buffer_;
  std::uint64_t count_ = 0;
  bool finished_ = false;
};

}  // namespace

Result<std::unique_ptr<RayCloudWriter>> RayCloudWriter::open(const std::string& path) {
  auto file = AtomicFileWriter::open(path);
  if (!file) {
    return Unexpected(file.error());
  }
  // Header for zero vertices now (same length as the final one); patched in finish().
  if (auto ok = file->write(headerText(0)); !ok) {
    return Unexpected(ok.error());
  }
  return std::unique_ptr<RayCloudWriter>(std::make_unique<PlyRayCloudWriter>(std::move(*file)));
}

}  // namespace raymap::io
