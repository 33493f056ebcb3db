// SPDX-License-Identifier: BSD-3-Clause
// Decoding a depth camera's sensor_msgs/Image (16UC1 millimetres or 32FC1 metres) straight from
// its serialized XCDR1 bytes into scan points: every pixel's depth back-projected along its
// undistorted ray (PixelRayTable), down-sampled and range-limited, without allocating.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "raymap/expected.hpp"

#include "src/core/pinhole_camera.hpp"
#include "src/msgs/point_cloud.hpp"

namespace raymap::msgs {

/// @brief How a depth image becomes points (raymapd's sensors[] with kind: depth).
struct DepthDecodeOptions {
  /// N >= 1: the image is cut into N × N blocks and each block gives one point: the nearest
  /// valid depth in it (not nearer than min_range_m), at that pixel's own ray (so the point is
  /// exact, and a thin near obstacle survives down-sampling). 1 = every pixel.
  std::uint32_t downsample = 1;
  /// Depths nearer than this (metres, along the ray) are the robot itself: left out of a block's
  /// minimum. 0 = none.
  float min_range_m = 0.0f;
  /// Points further than this (metres, along the ray) are kept as they are: the ray preparer
  /// clips them to free space up to max range. Also the length of invalid_as_free rays. 0 = none.
  float max_range_m = 0.0f;
  /// A block whose pixels all have no depth (0, NaN or +inf: REP 117's "no return") gives a
  /// kPointFreeOnly point max_range_m along the ray of its centre pixel, instead of nothing. A
  /// block with a pixel nearer than min_range_m (the robot's own body) or at REP 117's -inf (too
  /// close to measure) and no valid depth gives nothing: something occludes it. Needs
  /// max_range_m > 0 (with 0 such blocks are left out).
  bool invalid_as_free = false;
};

/// @brief What a decoded image said and gave.
struct DepthImageHeader {
  std::int64_t stamp_ns = 0;    ///< header.stamp, nanoseconds
  char frame_id[64] = {};       ///< header.frame_id, NUL-terminated
  std::uint32_t width = 0;      ///< pixels
  std::uint32_t height = 0;     ///< pixels
  std::uint32_t points = 0;     ///< points written to `out` (returns and free-only)
  std::uint32_t free_only = 0;  ///< of those, kPointFreeOnly (invalid_as_free)
  std::uint32_t invalid = 0;    ///< blocks with no valid depth (free-only or left out)
  /// Of invalid: blocks left out because a depth in them is nearer than min_range_m (or REP
  /// 117's -inf). All of an image's blocks here means min_range_m is beyond what the camera sees.
  std::uint32_t too_near = 0;
  bool millimetres = false;  ///< 16UC1 (else 32FC1)
};

/// Why an image was rejected. Every malformed input gives one of these; nothing is read out of
/// bounds.
enum class DepthImageError : std::uint8_t {
  kTruncated,            ///< the bytes end before the message does (also absurd lengths)
  kBadEncapsulation,     ///< shorter than 4 bytes or not CDR_LE / CDR_BE
  kMalformed,            ///< a string without its NUL, or similar structural damage
  kFrameIdTooLong,       ///< header.frame_id has 64 or more characters
  kUnsupportedEncoding,  ///< an encoding other than 16UC1 / mono16 and 32FC1
  kStepTooSmall,         ///< step < width × bytes per pixel (or it overflows)
  kDataTooShort,         ///< data shorter than step × height (longer data is accepted: the
                         ///< bytes after the last row are not read)
  kCameraInfoMismatch,   ///< the image's width or height differs from the CameraInfo's
  kTooManyPoints,        ///< more points than `out` holds (the image is dropped whole); checked
                         ///< against depthPointCapacity(), the most the image can give
};
inline constexpr std::size_t kDepthImageErrorCount =
    static_cast<std::size_t>(DepthImageError::kTooManyPoints) + 1;

/// @brief Short, stable name ("unsupported_encoding", "step_too_small", ...). @rt allocates: no.
const char* toString(DepthImageError error) noexcept;

/// @brief What an Image's fields say (for tools that show it without a camera model).
struct DepthImageInfo {
  std::int64_t stamp_ns = 0;  ///< header.stamp, nanoseconds
  char frame_id[64] = {};     ///< header.frame_id, NUL-terminated
  char encoding[8] = {};      ///< "16UC1", "mono16" or "32FC1"
  std::uint32_t width = 0;    ///< pixels
  std::uint32_t height = 0;   ///< pixels
  std::uint32_t step = 0;     ///< bytes per row
  std::uint32_t data_bytes = 0;
  bool big_endian = false;
  bool millimetres = false;  ///< 16UC1 / mono16
};

/// @brief Checks a serialized sensor_msgs/Image as decodeDepthImage() does (encoding, step, data
/// length) without a camera, and says what it holds. @rt allocates: no.
Expected<DepthImageInfo, DepthImageError> inspectDepthImage(
    std::span<const std::byte> cdr) noexcept;

/// @brief Points an image of `width` × `height` gives at most with `downsample`: one per block,
/// partial blocks at the right and bottom edges included (saturated at 2^32 - 1; 0 counts as 1).
/// @rt allocates: no.
std::uint32_t depthPointCapacity(std::uint32_t width, std::uint32_t height,
                                 std::uint32_t downsample) noexcept;

/// @brief Decodes a serialized sensor_msgs/Image (with its 4-byte encapsulation header) of a
/// depth camera whose pixel rays `rays` holds into points in the camera's optical frame (x right,
/// y down, z forward, metres; time_s 0, intensity 0), row by row of blocks.
/// is_bigendian is honoured for the pixels, and the CDR byte order for the message.
/// @pre rays.built(); options.downsample >= 1
/// @rt allocates: no; blocks: no; thread: any (no shared state).
Expected<DepthImageHeader, DepthImageError> decodeDepthImage(std::span<const std::byte> cdr,
                                                             const PixelRayTable& rays,
                                                             const DepthDecodeOptions& options,
                                                             std::span<ScanPoint> out) noexcept;

/// @brief The pixels of a depth image, wherever they came from (a message's data, a caller's
/// buffer). Row-major, `step` bytes per row.
struct DepthPixels {
  const std::byte* data = nullptr;
  std::size_t step = 0;
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  bool millimetres = false;  ///< 16-bit millimetres (else 32-bit float metres)
  bool big_endian = false;
};

/// @brief decodeDepthImage's back-projection of pixels already checked: the header's stamp and
/// frame are left empty.
/// @pre rays built for pixels.width × pixels.height; step >= width × bytes per pixel; data holds
/// step × height bytes; options.downsample >= 1; out.size() >= depthPointCapacity().
/// @rt allocates: no; blocks: no; thread: any (no shared state).
DepthImageHeader decodeDepthPixels(const DepthPixels& pixels, const PixelRayTable& rays,
                                   const DepthDecodeOptions& options,
                                   std::span<ScanPoint> out) noexcept;

}  // namespace raymap::msgs
