// SPDX-License-Identifier: BSD-3-Clause
// Decoding sensor_msgs/PointCloud2 straight from its serialized XCDR1 bytes into caller buffers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <type_traits>

#include "raymap/expected.hpp"

namespace raymap::msgs {

/// ScanPoint::flags bit: x, y or z is not finite (no return); the point is kept so that a
/// caller can use the direction of an organised cloud, but its coordinates are meaningless.
inline constexpr std::uint32_t kPointNoReturn = 1U;
/// ScanPoint::flags bit: no return within the sensor's range along this point's ray (a depth
/// camera's pixel beyond its range, or an invalid pixel with invalid_as_free): x, y, z is the end
/// of a free-space ray; it clears the voxels up to there and never marks a hit.
inline constexpr std::uint32_t kPointFreeOnly = 2U;

/// @brief One decoded point, in the cloud's (sensor) frame.
struct ScanPoint {
  float x;              ///< metres (NaN when kPointNoReturn and the cloud said so)
  float y;              ///< metres
  float z;              ///< metres
  float time_s;         ///< seconds after the header stamp (0 without a time field)
  float intensity;      ///< the intensity field converted to float (0 without one)
  std::uint32_t flags;  ///< kPointNoReturn, ...
};
static_assert(sizeof(ScanPoint) == 24);
static_assert(std::is_trivially_copyable_v<ScanPoint>);

/// @brief What the header and layout of a decoded cloud said.
struct CloudHeader {
  std::int64_t stamp_ns;    ///< header.stamp, nanoseconds since the epoch of the sender's clock
  char frame_id[64];        ///< header.frame_id, NUL-terminated
  std::uint32_t width;      ///< points per row
  std::uint32_t height;     ///< rows (1 = unorganised)
  std::uint32_t points;     ///< points written to `out` (= width * height)
  std::uint32_t no_return;  ///< points flagged kPointNoReturn
  bool has_time;            ///< a time field was found and used
  bool has_intensity;       ///< an intensity field was found and used
};
static_assert(std::is_trivially_copyable_v<CloudHeader>);

/// Why a cloud was rejected. Every malformed input gives one of these; nothing is read out of
/// bounds.
enum class CloudError : std::uint8_t {
  kTruncated,          ///< the bytes end before the message does (also absurd sequence lengths)
  kBadEncapsulation,   ///< shorter than 4 bytes or not CDR_LE / CDR_BE
  kMalformed,          ///< a string without its NUL, or similar structural damage
  kMissingXyz,         ///< no x, y or z field
  kBadFieldType,       ///< x/y/z not FLOAT32/FLOAT64, count != 1, unknown datatype, or a time
                       ///< field of a type the time convention cannot take
  kPointStepTooSmall,  ///< point_step is 0 or smaller than the x/y/z fields need
  kFieldOutsidePoint,  ///< a used field (x, y, z, time, intensity) ends past point_step
  kRowStepTooSmall,    ///< row_step < width * point_step (or it overflows)
  kDataSizeMismatch,   ///< data size != row_step * height (too short; longer is also refused)
  kTooManyPoints,      ///< width * height exceeds `out` (the cloud is dropped whole)
  kFrameIdTooLong,     ///< header.frame_id has 64 or more characters
  kMissingTimeField,   ///< CloudDecodeOptions::time_field names a field the cloud lacks
};
/// The number of CloudError values (per-reason counters are indexed by the error).
inline constexpr std::size_t kCloudErrorCount =
    static_cast<std::size_t>(CloudError::kMissingTimeField) + 1;

/// @brief Short, stable name ("truncated", "bad_field_type", ...). @rt allocates: no.
const char* toString(CloudError error) noexcept;

/// How the values of the time field are read.
enum class TimeUnit : std::uint8_t {
  kAuto,                 ///< by datatype: integers -> kRelativeNanoseconds, FLOAT32 ->
                         ///< kRelativeSeconds, FLOAT64 -> by value: > 1e15 absolute
                         ///< nanoseconds (Livox), > 1e6 kAbsoluteSeconds, else kRelativeSeconds
  kRelativeNanoseconds,  ///< integer nanoseconds after the header stamp (Ouster "t", Livox)
  kRelativeSeconds,      ///< seconds after the header stamp (Velodyne "time")
  kAbsoluteSeconds,      ///< seconds since the epoch (Hesai/RoboSense "timestamp"); the header
                         ///< stamp is subtracted
};

/// @brief Options of decodePointCloud2 (an aggregate; the defaults suit ROS 2 lidar drivers).
struct CloudDecodeOptions {
  /// The per-point time field. nullptr = auto: the first of "t", "time", "timestamp",
  /// "time_stamp" that the cloud has (no time field: time_s = 0). Named explicitly: the cloud
  /// must have it (else kMissingTimeField).
  const char* time_field = nullptr;
  /// No per-point time: every point at the header stamp, whatever fields the cloud has
  /// (sensors[].time_field: none). Overrides time_field.
  bool ignore_time = false;
  TimeUnit time_unit = TimeUnit::kAuto;
  /// The field read into ScanPoint::intensity (any numeric type); nullptr = none.
  const char* intensity_field = "intensity";
  /// Also flag points at exactly (0, 0, 0) as kPointNoReturn: Ouster drivers publish missing
  /// returns that way (with is_dense true), and no lidar return lies at its own origin.
  bool origin_is_no_return = true;
};

/// PointField datatypes (sensor_msgs/PointField constants; not on the wire).
enum class PointFieldType : std::uint8_t {
  kInt8 = 1,
  kUInt8 = 2,
  kInt16 = 3,
  kUInt16 = 4,
  kInt32 = 5,
  kUInt32 = 6,
  kFloat32 = 7,
  kFloat64 = 8,
};

/// @brief Decodes a serialized sensor_msgs/PointCloud2 (the bytes from RawReader::take, with
/// the 4-byte encapsulation header) into `out`.
/// x/y/z must be FLOAT32 or FLOAT64 with count 1; intensity and time may be any numeric type;
/// is_bigendian is honoured for the point data, and the CDR byte order for the message. Points
/// are written row by row (row r at r * row_step; bytes after width * point_step are row padding).
/// Non-finite points are kept with kPointNoReturn and counted in CloudHeader::no_return.
/// @param[in] cdr the serialized message (starting with the encapsulation header)
/// @param[out] out room for the points; a bigger cloud gives kTooManyPoints and writes nothing
/// @param[in] options which fields to use
/// @return the header and counts, or why the cloud was refused (`out` is then unspecified)
/// @rt allocates: no; blocks: no; thread: any (no shared state).
Expected<CloudHeader, CloudError> decodePointCloud2(std::span<const std::byte> cdr,
                                                    std::span<ScanPoint> out,
                                                    const CloudDecodeOptions& options) noexcept;

}  // namespace raymap::msgs
