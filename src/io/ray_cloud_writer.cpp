// SPDX-License-Identifier: BSD-3-Clause
// RayCloudWriter: streams rays as binary little-endian PLY records (ray or point cloud) and
// patches the vertex count into the header on finish().
#include "src/io/ray_cloud_writer.hpp"

#include <algorithm>
#include <limits>
#include <vector>

#include "src/core/byte_order.hpp"
#include "src/io/atomic_file.hpp"

namespace raymap::io {
namespace {

// Ray cloud: double x y z time, float nx ny nz intensity, uint scan, uchar alpha.
constexpr std::size_t kRayRecordBytes = 4 * 8 + 4 * 4 + 4 + 1;
// Point cloud: double x y z time, float intensity, uint scan.
constexpr std::size_t kPointRecordBytes = 4 * 8 + 4 + 4;
constexpr std::size_t kRaysPerChunk = 16384;
// Digits reserved for the vertex count: any std::uint64_t fits.
constexpr std::size_t kCountDigits = 20;

/// The header for `count` vertices. Its length does not depend on the count: a comment line
/// before the element absorbs the digits the count does not use, so finish() can rewrite the
/// header in place and the count line carries exactly the digits, with no padding any PLY parser
/// could trip over.
std::string headerText(PlyLayout layout, std::uint64_t count) {
  const std::string digits = std::to_string(count);
  std::string header =
      "ply\n"
      "format binary_little_endian 1.0\n";
  header += layout == PlyLayout::kRayCloud
                ? "comment raymap ray cloud: x y z = sample, n = origin - sample (world frame, "
                  "metres)\n"
                : "comment raymap point cloud: returns only (world frame, metres); the sensor "
                  "positions are in the trajectory\n";
  header += "comment ";
  header.append(kCountDigits - digits.size(), '.');
  header +=
      "\n"
      "element vertex " +
      digits +
      "\n"
      "property double x\n"
      "property double y\n"
      "property double z\n"
      "property double time\n";
  if (layout == PlyLayout::kRayCloud) {
    header +=
        "property float nx\n"
        "property float ny\n"
        "property float nz\n";
  }
  header +=
      "property float intensity\n"
      "property uint scan\n";
  if (layout == PlyLayout::kRayCloud) {
    header += "property uchar alpha\n";
  }
  return header + "end_header\n";
}

class PlyRayCloudWriter final : public RayCloudWriter {
 public:
  PlyRayCloudWriter(AtomicFileWriter file, PlyLayout layout) noexcept
      : file_(std::move(file)), layout_(layout) {}

  Expected<void, Error> write(std::span<const Ray> rays) override {
    if (finished_) {
      return fail(ErrorCode::kInvalidArgument,
                  "cannot write '" + file_.path() + "': the ray cloud is already finished");
    }
    while (!rays.empty()) {
      const std::span<const Ray> chunk = rays.first(std::min(rays.size(), kRaysPerChunk));
      rays = rays.subspan(chunk.size());
      const bool rays_out = layout_ == PlyLayout::kRayCloud;
      buffer_.resize(chunk.size() * (rays_out ? kRayRecordBytes : kPointRecordBytes));
      std::byte* out = buffer_.data();
      std::uint64_t records = 0;
      for (const Ray& ray : chunk) {
        const bool no_return = (ray.flags & kRayNoReturn) != 0;
        if (no_return && !rays_out) {
          continue;
        }
        if (ray.scan > std::numeric_limits<std::uint32_t>::max()) {
          return fail(ErrorCode::kInvalidArgument, "cannot write '" + file_.path() +
                                                       "': scan index " + std::to_string(ray.scan) +
                                                       " does not fit the PLY uint scan property");
        }
        out = storeLe(out, ray.sample.x);
        out = storeLe(out, ray.sample.y);
        out = storeLe(out, ray.sample.z);
        out = storeLe(out, ray.time_s);
        if (rays_out) {
          out = storeLe(out, static_cast<float>(ray.origin.x - ray.sample.x));
          out = storeLe(out, static_cast<float>(ray.origin.y - ray.sample.y));
          out = storeLe(out, static_cast<float>(ray.origin.z - ray.sample.z));
        }
        out = storeLe(out, ray.intensity);
        out = storeLe(out, static_cast<std::uint32_t>(ray.scan));
        if (rays_out) {
          *out++ = static_cast<std::byte>(no_return ? 0u : 255u);
        }
        ++records;
      }
      const auto used = static_cast<std::size_t>(out - buffer_.data());
      if (auto ok = file_.write(std::span<const std::byte>(buffer_.data(), used)); !ok) {
        return ok;
      }
      count_ += records;
    }
    return {};
  }

  Expected<void, Error> finish() override {
    if (finished_) {
      return fail(ErrorCode::kInvalidArgument,
                  "cannot finish '" + file_.path() + "': already finished");
    }
    finished_ = true;
    if (auto ok = file_.patch(0, headerText(layout_, count_)); !ok) {
      return ok;
    }
    return file_.commit();
  }

  std::uint64_t count() const noexcept override { return count_; }

 private:
  AtomicFileWriter file_;
  PlyLayout layout_;
  std::vector<std::byte> buffer_;
  std::uint64_t count_ = 0;
  bool finished_ = false;
};

}  // namespace

Result<std::unique_ptr<RayCloudWriter>> RayCloudWriter::open(const std::string& path,
                                                             PlyLayout layout) {
  auto file = AtomicFileWriter::open(path);
  if (!file) {
    return Unexpected(file.error());
  }
  // Header for zero vertices now (same length as the final one); patched in finish().
  if (auto ok = file->write(headerText(layout, 0)); !ok) {
    return Unexpected(ok.error());
  }
  return std::unique_ptr<RayCloudWriter>(
      std::make_unique<PlyRayCloudWriter>(std::move(*file), layout));
}

}  // namespace raymap::io
