// SPDX-License-Identifier: BSD-3-Clause
// decodeDepthImage: the message is validated once, then the pixels are read row by row through
// one of a few specialised loops (pixel format × byte order × down-sampling), each a plain loop
// over the row without calls, so that the compiler keeps it tight.
#include "src/msgs/depth_image.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <string_view>

#include "raymap/assert.hpp"

#include "src/core/byte_order.hpp"
#include "src/msgs/cdr_reader.hpp"
#include "src/msgs/ros_time.hpp"

namespace raymap::msgs {
namespace {

/// In double: raw × 1e-3 rounded to double and then to float is the float nearest raw / 1000
/// (a whole number of millimetres gives back the metres it was written from, 1500 -> 1.5f, which
/// raw × 0.001f misses by an ulp); the unit test checks all 65,536 values.
constexpr double kMetresPerMillimetre = 1e-3;
constexpr float kLargestDepth = std::numeric_limits<float>::max();

/// One pixel's depth in the image's own unit, as float: millimetres for 16UC1 (exact: a uint16
/// converts to float without rounding; 0 = no data) and metres for 32FC1 (NaN/inf/<= 0 pass
/// through and are rejected by isValid()). Comparisons (validity, the block minimum) run in this
/// unit; only the depths that become points are converted to metres. The bytes may be unaligned
/// (step is any number); kOrder is the image's byte order.
template <bool kMillimetres, std::endian kOrder>
inline float loadDepth(const std::byte* p) noexcept {
  if constexpr (kMillimetres) {
    return static_cast<float>(loadEndian<std::uint16_t>(p, kOrder));
  } else {
    return loadEndian<float>(p, kOrder);
  }
}

/// A depth of loadDepth()'s unit in metres.
template <bool kMillimetres>
inline float toMetres(float depth) noexcept {
  if constexpr (kMillimetres) {
    return static_cast<float>(static_cast<double>(depth) * kMetresPerMillimetre);
  } else {
    return depth;
  }
}

/// What the loops need besides the pixels.
struct Limits {
  float min_range2 = 0.0f;  ///< min range², in the image's unit (mm² or m²), compared with the
                            ///< squared range along the ray
  float max_range = 0.0f;   ///< metres along the ray: the end of a free-only point
  bool free_invalid = false;
};

/// A usable return: a positive, finite depth whose range along its ray, d·sqrt(x²+y²+1), is at
/// least min range (compared squared: no square root per pixel; in the image's unit). NaN fails
/// every comparison.
inline bool isValid(float depth, float xn, float yn, const Limits& limits) noexcept {
  const float q = xn * xn + yn * yn + 1.0f;
  return depth > 0.0f && depth <= kLargestDepth && depth * depth * q >= limits.min_range2;
}

/// Something is there, nearer than min range (the robot's own body), or REP 117's -inf ("too
/// close to measure"): not a usable return, and not free space either (it occludes the ray).
inline bool isNear(float depth) noexcept {
  return depth == -std::numeric_limits<float>::infinity() ||
         (depth > 0.0f && depth <= kLargestDepth);
}

inline void writeReturn(ScanPoint& point, float depth, const float* ray) noexcept {
  point = ScanPoint{depth * ray[0], depth * ray[1], depth, 0.0f, 0.0f, 0u};
}

/// max_range_m along the ray: the end of a free-space ray (REP 117 "no return within range").
inline void writeFree(ScanPoint& point, const float* ray, float max_range) noexcept {
  const float scale = max_range / std::sqrt(ray[0] * ray[0] + ray[1] * ray[1] + 1.0f);
  point = ScanPoint{scale * ray[0], scale * ray[1], scale, 0.0f, 0.0f, kPointFreeOnly};
}

struct Counts {
  std::uint32_t points = 0;
  std::uint32_t free_only = 0;
  std::uint32_t invalid = 0;
  std::uint32_t too_near = 0;  ///< of invalid: something nearer than min range, no point given
};

struct Image {
  const std::byte* data = nullptr;
  std::size_t step = 0;
  std::uint32_t width = 0;
  std::uint32_t height = 0;
};

/// Every pixel: the fast path (no block bookkeeping).
template <bool kMillimetres, std::endian kOrder>
Counts decodeEveryPixel(const Image& image, const PixelRayTable& rays, const Limits& limits,
                        ScanPoint* out) noexcept {
  constexpr std::size_t kPixelBytes = kMillimetres ? 2 : 4;
  Counts counts;
  std::uint32_t n = 0;
  for (std::uint32_t v = 0; v < image.height; ++v) {
    const std::byte* row = image.data + v * image.step;
    const float* ray = rays.ray(0, v);
    for (std::uint32_t u = 0; u < image.width; ++u, ray += 2) {
      const float depth = loadDepth<kMillimetres, kOrder>(row + u * kPixelBytes);
      if (isValid(depth, ray[0], ray[1], limits)) [[likely]] {
        writeReturn(out[n++], toMetres<kMillimetres>(depth), ray);
      } else {
        ++counts.invalid;
        if (isNear(depth)) {
          ++counts.too_near;
        } else if (limits.free_invalid) {
          writeFree(out[n++], ray, limits.max_range);
          ++counts.free_only;
        }
      }
    }
  }
  counts.points = n;
  return counts;
}

/// N × N blocks: the nearest valid depth of each, at its own pixel's ray (ties: the first in
/// row-major order); a block without one gives a free-only point along its centre pixel's ray.
template <bool kMillimetres, std::endian kOrder>
Counts decodeBlocks(const Image& image, const PixelRayTable& rays, const Limits& limits,
                    std::uint32_t n_block, ScanPoint* out) noexcept {
  constexpr std::size_t kPixelBytes = kMillimetres ? 2 : 4;
  Counts counts;
  std::uint32_t n = 0;
  for (std::uint32_t v0 = 0; v0 < image.height; v0 += n_block) {
    const std::uint32_t v1 = v0 + std::min(n_block, image.height - v0);
    for (std::uint32_t u0 = 0; u0 < image.width; u0 += n_block) {
      const std::uint32_t u1 = u0 + std::min(n_block, image.width - u0);
      float best = std::numeric_limits<float>::infinity();
      std::uint32_t best_u = 0;
      std::uint32_t best_v = 0;
      bool occluded = false;  // a pixel nearer than min range: something is there, not free
      for (std::uint32_t v = v0; v < v1; ++v) {
        const std::byte* row = image.data + v * image.step;
        const float* ray = rays.ray(u0, v);
        for (std::uint32_t u = u0; u < u1; ++u, ray += 2) {
          const float depth = loadDepth<kMillimetres, kOrder>(row + u * kPixelBytes);
          if (isValid(depth, ray[0], ray[1], limits)) {
            if (depth < best) {
              best = depth;
              best_u = u;
              best_v = v;
            }
          } else {
            occluded = occluded || isNear(depth);
          }
        }
      }
      if (best <= kLargestDepth) {
        writeReturn(out[n++], toMetres<kMillimetres>(best), rays.ray(best_u, best_v));
      } else {
        ++counts.invalid;
        counts.too_near += occluded ? 1u : 0u;
        if (limits.free_invalid && !occluded) {
          const std::uint32_t centre_u = u0 + (u1 - u0 - 1) / 2;
          const std::uint32_t centre_v = v0 + (v1 - v0 - 1) / 2;
          writeFree(out[n++], rays.ray(centre_u, centre_v), limits.max_range);
          ++counts.free_only;
        }
      }
    }
  }
  counts.points = n;
  return counts;
}

template <bool kMillimetres, std::endian kOrder>
Counts decodePixels(const Image& image, const PixelRayTable& rays, const Limits& limits,
                    std::uint32_t downsample, ScanPoint* out) noexcept {
  return downsample == 1 ? decodeEveryPixel<kMillimetres, kOrder>(image, rays, limits, out)
                         : decodeBlocks<kMillimetres, kOrder>(image, rays, limits, downsample, out);
}

std::uint64_t blocks(std::uint32_t pixels, std::uint32_t downsample) noexcept {
  return (std::uint64_t{pixels} + downsample - 1) / downsample;
}

}  // namespace

const char* toString(DepthImageError error) noexcept {
  switch (error) {
    case DepthImageError::kTruncated:
      return "truncated";
    case DepthImageError::kBadEncapsulation:
      return "bad_encapsulation";
    case DepthImageError::kMalformed:
      return "malformed";
    case DepthImageError::kFrameIdTooLong:
      return "frame_id_too_long";
    case DepthImageError::kUnsupportedEncoding:
      return "unsupported_encoding";
    case DepthImageError::kStepTooSmall:
      return "step_too_small";
    case DepthImageError::kDataTooShort:
      return "data_too_short";
    case DepthImageError::kCameraInfoMismatch:
      return "camera_info_mismatch";
    case DepthImageError::kTooManyPoints:
      return "too_many_points";
  }
  return "unknown";
}

std::uint32_t depthPointCapacity(std::uint32_t width, std::uint32_t height,
                                 std::uint32_t downsample) noexcept {
  const std::uint32_t n = std::max<std::uint32_t>(downsample, 1);
  const std::uint64_t points = blocks(width, n) * blocks(height, n);  // < 2^64: no overflow
  return static_cast<std::uint32_t>(
      std::min<std::uint64_t>(points, std::numeric_limits<std::uint32_t>::max()));
}

namespace {

/// The fields of a serialized Image, checked for what every reader needs (encoding, step, data).
struct ParsedImage {
  DepthImageInfo info;
  std::span<const std::byte> data;
  std::size_t pixel_bytes = 0;
};

Expected<ParsedImage, DepthImageError> parseImage(std::span<const std::byte> cdr) noexcept {
  CdrReader reader(cdr);
  if (!reader.ok()) {
    return Unexpected(DepthImageError::kBadEncapsulation);
  }
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  std::string_view frame_id;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::string_view encoding;
  std::uint8_t is_bigendian = 0;
  std::uint32_t step = 0;
  std::uint32_t data_size = 0;
  ParsedImage parsed;
  if (!reader.readI32(sec) || !reader.readU32(nanosec) || !reader.readString(frame_id) ||
      !reader.readU32(height) || !reader.readU32(width) || !reader.readString(encoding) ||
      !reader.readU8(is_bigendian) || !reader.readU32(step) ||
      !reader.readSequenceLength(data_size, 1) || !reader.readBytes(data_size, parsed.data)) {
    return Unexpected(reader.malformed() ? DepthImageError::kMalformed
                                         : DepthImageError::kTruncated);
  }
  DepthImageInfo& info = parsed.info;
  if (frame_id.size() >= sizeof(info.frame_id)) {
    return Unexpected(DepthImageError::kFrameIdTooLong);
  }
  // sensor_msgs/image_encodings: "16UC1" and "mono16" are unsigned 16-bit (depth drivers use
  // millimetres, REP 118), "32FC1" is float metres.
  if (encoding == "16UC1" || encoding == "mono16") {
    info.millimetres = true;
    parsed.pixel_bytes = 2;
  } else if (encoding == "32FC1") {
    parsed.pixel_bytes = 4;
  } else {
    return Unexpected(DepthImageError::kUnsupportedEncoding);
  }
  // 64-bit products of 32-bit values cannot overflow.
  if (std::uint64_t{step} < std::uint64_t{width} * parsed.pixel_bytes) {
    return Unexpected(DepthImageError::kStepTooSmall);
  }
  // Longer data (padding after the last row) is accepted; nothing past step × height is read.
  if (std::uint64_t{data_size} < std::uint64_t{step} * height) {
    return Unexpected(DepthImageError::kDataTooShort);
  }
  info.stamp_ns = nanosecondsOf(sec, nanosec);
  if (!frame_id.empty()) {  // an empty view may have a null data()
    std::memcpy(info.frame_id, frame_id.data(), frame_id.size());
  }
  info.frame_id[frame_id.size()] = '\0';
  std::memcpy(info.encoding, encoding.data(), encoding.size());  // one of the three above
  info.encoding[encoding.size()] = '\0';
  info.width = width;
  info.height = height;
  info.step = step;
  info.big_endian = is_bigendian != 0;
  info.data_bytes = data_size;
  return parsed;
}

}  // namespace

Expected<DepthImageInfo, DepthImageError> inspectDepthImage(
    std::span<const std::byte> cdr) noexcept {
  auto parsed = parseImage(cdr);
  if (!parsed) {
    return Unexpected(parsed.error());
  }
  return parsed->info;
}

Expected<DepthImageHeader, DepthImageError> decodeDepthImage(std::span<const std::byte> cdr,
                                                             const PixelRayTable& rays,
                                                             const DepthDecodeOptions& options,
                                                             std::span<ScanPoint> out) noexcept {
  RAYMAP_EXPECTS(rays.built());
  RAYMAP_EXPECTS(options.downsample >= 1);
  auto parsed = parseImage(cdr);
  if (!parsed) {
    return Unexpected(parsed.error());
  }
  const DepthImageInfo& info = parsed->info;
  if (info.width != rays.width() || info.height != rays.height()) {
    return Unexpected(DepthImageError::kCameraInfoMismatch);
  }
  if (depthPointCapacity(info.width, info.height, options.downsample) > out.size()) {
    return Unexpected(DepthImageError::kTooManyPoints);
  }
  const DepthPixels pixels{parsed->data.data(), info.step,        info.width,
                           info.height,         info.millimetres, info.big_endian};
  DepthImageHeader decoded = decodeDepthPixels(pixels, rays, options, out);
  decoded.stamp_ns = info.stamp_ns;
  std::memcpy(decoded.frame_id, info.frame_id, sizeof(decoded.frame_id));
  return decoded;
}

DepthImageHeader decodeDepthPixels(const DepthPixels& pixels, const PixelRayTable& rays,
                                   const DepthDecodeOptions& options,
                                   std::span<ScanPoint> out) noexcept {
  RAYMAP_EXPECTS(rays.built() && pixels.width == rays.width() && pixels.height == rays.height());
  RAYMAP_EXPECTS(options.downsample >= 1);
  RAYMAP_EXPECTS(depthPointCapacity(pixels.width, pixels.height, options.downsample) <= out.size());
  DepthImageHeader header{};
  header.millimetres = pixels.millimetres;
  header.width = pixels.width;
  header.height = pixels.height;
  const bool is_bigendian = pixels.big_endian;

  Limits limits;
  // NaN -> 0: none. In millimetres for 16UC1 (the unit its pixels are compared in).
  const float min_range = std::max(options.min_range_m, 0.0f) * (header.millimetres ? 1e3f : 1.0f);
  limits.min_range2 = min_range * min_range;
  limits.max_range = options.max_range_m;
  // Free-only points need a length: without a max range invalid blocks are left out.
  limits.free_invalid =
      options.invalid_as_free && options.max_range_m > 0.0f && options.max_range_m <= kLargestDepth;
  const Image image{pixels.data, pixels.step, pixels.width, pixels.height};
  constexpr std::endian kBig = std::endian::big;
  constexpr std::endian kLittle = std::endian::little;
  ScanPoint* points = out.data();
  const std::uint32_t n = options.downsample;
  Counts counts;
  if (header.millimetres) {
    counts = is_bigendian ? decodePixels<true, kBig>(image, rays, limits, n, points)
                          : decodePixels<true, kLittle>(image, rays, limits, n, points);
  } else {
    counts = is_bigendian ? decodePixels<false, kBig>(image, rays, limits, n, points)
                          : decodePixels<false, kLittle>(image, rays, limits, n, points);
  }
  header.points = counts.points;
  header.free_only = counts.free_only;
  header.invalid = counts.invalid;
  header.too_near = counts.too_near;
  return header;
}

}  // namespace raymap::msgs
