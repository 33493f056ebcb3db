// SPDX-License-Identifier: BSD-3-Clause
// decodePointCloud2: validates the layout once, then reads the points row by row.
#include "src/msgs/point_cloud.hpp"

#include <bit>
#include <cmath>
#include <cstring>
#include <string_view>

#include "src/core/byte_order.hpp"
#include "src/msgs/cdr_reader.hpp"
#include "src/msgs/ros_time.hpp"

namespace raymap::msgs {
namespace {

/// A field of the cloud that the decoder uses.
struct Field {
  bool present = false;
  std::uint32_t offset = 0;
  std::uint8_t datatype = 0;
  std::uint32_t count = 0;
};

std::uint32_t datatypeSize(std::uint8_t datatype) noexcept {
  switch (static_cast<PointFieldType>(datatype)) {
    case PointFieldType::kInt8:
    case PointFieldType::kUInt8:
      return 1;
    case PointFieldType::kInt16:
    case PointFieldType::kUInt16:
      return 2;
    case PointFieldType::kInt32:
    case PointFieldType::kUInt32:
    case PointFieldType::kFloat32:
      return 4;
    case PointFieldType::kFloat64:
      return 8;
  }
  return 0;  // not a PointField datatype
}

bool isFloatType(std::uint8_t datatype) noexcept {
  return datatype == static_cast<std::uint8_t>(PointFieldType::kFloat32) ||
         datatype == static_cast<std::uint8_t>(PointFieldType::kFloat64);
}

/// Reads one value of a validated datatype, stored in byte order `order`, as double (exact for
/// every PointField type).
double loadValue(const std::byte* p, std::uint8_t datatype, std::endian order) noexcept {
  switch (static_cast<PointFieldType>(datatype)) {
    case PointFieldType::kInt8:
      return loadEndian<std::int8_t>(p, order);
    case PointFieldType::kUInt8:
      return loadEndian<std::uint8_t>(p, order);
    case PointFieldType::kInt16:
      return loadEndian<std::int16_t>(p, order);
    case PointFieldType::kUInt16:
      return loadEndian<std::uint16_t>(p, order);
    case PointFieldType::kInt32:
      return loadEndian<std::int32_t>(p, order);
    case PointFieldType::kUInt32:
      return loadEndian<std::uint32_t>(p, order);
    case PointFieldType::kFloat32:
      return static_cast<double>(loadEndian<float>(p, order));
    case PointFieldType::kFloat64:
      return loadEndian<double>(p, order);
  }
  return 0.0;
}

float loadCoordinate(const std::byte* p, std::uint8_t datatype, std::endian order) noexcept {
  if (datatype == static_cast<std::uint8_t>(PointFieldType::kFloat32)) {
    return loadEndian<float>(p, order);
  }
  return static_cast<float>(loadEndian<double>(p, order));
}

/// How the time values of this cloud become seconds after the header stamp.
enum class TimeRule : std::uint8_t {
  kNone,
  kNanoseconds,
  kSeconds,
  kAbsoluteSeconds,
  kFloat64ByValue,
};

bool nameIs(std::string_view name, const char* wanted) noexcept {
  return wanted != nullptr && name == std::string_view(wanted);
}

constexpr const char* kAutoTimeFields[] = {"t", "time", "timestamp", "time_stamp"};
constexpr int kAutoTimeFieldCount = 4;

}  // namespace

const char* toString(CloudError error) noexcept {
  switch (error) {
    case CloudError::kTruncated:
      return "truncated";
    case CloudError::kBadEncapsulation:
      return "bad_encapsulation";
    case CloudError::kMalformed:
      return "malformed";
    case CloudError::kMissingXyz:
      return "missing_xyz";
    case CloudError::kBadFieldType:
      return "bad_field_type";
    case CloudError::kPointStepTooSmall:
      return "point_step_too_small";
    case CloudError::kFieldOutsidePoint:
      return "field_outside_point";
    case CloudError::kRowStepTooSmall:
      return "row_step_too_small";
    case CloudError::kDataSizeMismatch:
      return "data_size_mismatch";
    case CloudError::kTooManyPoints:
      return "too_many_points";
    case CloudError::kFrameIdTooLong:
      return "frame_id_too_long";
    case CloudError::kMissingTimeField:
      return "missing_time_field";
  }
  return "unknown";
}

Expected<CloudHeader, CloudError> decodePointCloud2(std::span<const std::byte> cdr,
                                                    std::span<ScanPoint> out,
                                                    const CloudDecodeOptions& options) noexcept {
  CdrReader reader(cdr);
  if (!reader.ok()) {
    return Unexpected(CloudError::kBadEncapsulation);
  }
  const auto truncatedOrMalformed = [&reader]() {
    return Unexpected(reader.malformed() ? CloudError::kMalformed : CloudError::kTruncated);
  };

  // header
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  std::string_view frame_id;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::uint32_t field_count = 0;
  if (!reader.readI32(sec) || !reader.readU32(nanosec) || !reader.readString(frame_id) ||
      !reader.readU32(height) || !reader.readU32(width) ||
      // A PointField takes at least 16 bytes: name length, offset, datatype (+3 padding), count.
      !reader.readSequenceLength(field_count, 16)) {
    return truncatedOrMalformed();
  }

  // fields: remember the ones we use (the first of each name wins)
  Field x, y, z, intensity;
  Field time_fields[kAutoTimeFieldCount];  // auto mode: one per candidate name
  Field explicit_time;
  for (std::uint32_t i = 0; i < field_count; ++i) {
    std::string_view name;
    Field field;
    field.present = true;
    if (!reader.readString(name) || !reader.readU32(field.offset) ||
        !reader.readU8(field.datatype) || !reader.readU32(field.count)) {
      return truncatedOrMalformed();
    }
    Field* slot = nullptr;
    if (name == "x") {
      slot = &x;
    } else if (name == "y") {
      slot = &y;
    } else if (name == "z") {
      slot = &z;
    } else if (nameIs(name, options.intensity_field)) {
      slot = &intensity;
    } else if (options.ignore_time) {
      // every point at the header stamp
    } else if (options.time_field != nullptr) {
      if (nameIs(name, options.time_field)) {
        slot = &explicit_time;
      }
    } else {
      for (int k = 0; k < kAutoTimeFieldCount; ++k) {
        if (name == kAutoTimeFields[k]) {
          slot = &time_fields[k];
        }
      }
    }
    if (slot != nullptr && !slot->present) {
      *slot = field;
    }
  }

  bool is_bigendian = false;
  std::uint32_t point_step = 0;
  std::uint32_t row_step = 0;
  std::uint32_t data_size = 0;
  std::span<const std::byte> data;
  bool is_dense = false;
  if (!reader.readBool(is_bigendian) || !reader.readU32(point_step) || !reader.readU32(row_step) ||
      !reader.readSequenceLength(data_size, 1) || !reader.readBytes(data_size, data) ||
      !reader.readBool(is_dense)) {
    return truncatedOrMalformed();
  }

  // header checks
  if (frame_id.size() >= sizeof(CloudHeader::frame_id)) {
    return Unexpected(CloudError::kFrameIdTooLong);
  }

  // x, y, z
  if (!x.present || !y.present || !z.present) {
    return Unexpected(CloudError::kMissingXyz);
  }
  for (const Field* f : {&x, &y, &z}) {
    if (!isFloatType(f->datatype) || f->count != 1) {
      return Unexpected(CloudError::kBadFieldType);
    }
  }
  const std::uint64_t xyz_bytes =
      std::uint64_t{datatypeSize(x.datatype)} + datatypeSize(y.datatype) + datatypeSize(z.datatype);
  if (point_step == 0 || point_step < xyz_bytes) {
    return Unexpected(CloudError::kPointStepTooSmall);
  }

  // time
  Field time_field;
  TimeRule time_rule = TimeRule::kNone;
  if (options.ignore_time) {
    // time_field stays absent
  } else if (options.time_field != nullptr) {
    if (!explicit_time.present) {
      return Unexpected(CloudError::kMissingTimeField);
    }
    time_field = explicit_time;
  } else {
    for (const Field& candidate : time_fields) {
      if (candidate.present) {
        time_field = candidate;
        break;
      }
    }
  }
  if (time_field.present) {
    if (datatypeSize(time_field.datatype) == 0 || time_field.count < 1) {
      return Unexpected(CloudError::kBadFieldType);
    }
    switch (options.time_unit) {
      case TimeUnit::kAuto:
        if (time_field.datatype == static_cast<std::uint8_t>(PointFieldType::kFloat32)) {
          time_rule = TimeRule::kSeconds;
        } else if (time_field.datatype == static_cast<std::uint8_t>(PointFieldType::kFloat64)) {
          time_rule = TimeRule::kFloat64ByValue;
        } else {
          time_rule = TimeRule::kNanoseconds;
        }
        break;
      case TimeUnit::kRelativeNanoseconds:
        time_rule = TimeRule::kNanoseconds;
        break;
      case TimeUnit::kRelativeSeconds:
        time_rule = TimeRule::kSeconds;
        break;
      case TimeUnit::kAbsoluteSeconds:
        time_rule = TimeRule::kAbsoluteSeconds;
        break;
    }
  }
  if (intensity.present && (datatypeSize(intensity.datatype) == 0 || intensity.count < 1)) {
    return Unexpected(CloudError::kBadFieldType);
  }

  // every used field inside the point
  for (const Field* f : {&x, &y, &z, &time_field, &intensity}) {
    if (f->present &&
        std::uint64_t{f->offset} + datatypeSize(f->datatype) > std::uint64_t{point_step}) {
      return Unexpected(CloudError::kFieldOutsidePoint);
    }
  }

  // rows and data size (64-bit products of 32-bit values cannot overflow)
  const std::uint64_t points = std::uint64_t{width} * height;
  if (points > 0 && std::uint64_t{row_step} < std::uint64_t{width} * point_step) {
    return Unexpected(CloudError::kRowStepTooSmall);
  }
  if (std::uint64_t{data_size} != (points > 0 ? std::uint64_t{row_step} * height : 0)) {
    return Unexpected(CloudError::kDataSizeMismatch);
  }
  if (points > out.size()) {
    return Unexpected(CloudError::kTooManyPoints);
  }

  CloudHeader header{};
  header.stamp_ns = nanosecondsOf(sec, nanosec);
  if (!frame_id.empty()) {  // an empty view may have a null data()
    std::memcpy(header.frame_id, frame_id.data(), frame_id.size());
  }
  header.frame_id[frame_id.size()] = '\0';
  header.width = width;
  header.height = height;
  header.points = static_cast<std::uint32_t>(points);
  header.has_time = time_field.present;
  header.has_intensity = intensity.present;

  if (points == 0) {
    // width 0 and any height (or the reverse) is an empty cloud: no row loop, whose 2^32 empty
    // rows took seconds (found by fuzz_cdr_point_cloud).
    return header;
  }

  // Absolute times are converted relative to the stamp in double: 1.7e9 s keeps ~0.2 us.
  const double stamp_s = static_cast<double>(sec) + static_cast<double>(nanosec) * 1e-9;
  const std::endian order = is_bigendian ? std::endian::big : std::endian::little;
  std::uint32_t no_return = 0;
  std::size_t n = 0;
  for (std::uint32_t row = 0; row < height; ++row) {
    const std::byte* row_bytes = data.data() + std::size_t{row} * row_step;
    for (std::uint32_t column = 0; column < width; ++column, ++n) {
      const std::byte* p = row_bytes + std::size_t{column} * point_step;
      ScanPoint& point = out[n];
      point.x = loadCoordinate(p + x.offset, x.datatype, order);
      point.y = loadCoordinate(p + y.offset, y.datatype, order);
      point.z = loadCoordinate(p + z.offset, z.datatype, order);
      point.flags = 0;
      const bool finite =
          std::isfinite(point.x) && std::isfinite(point.y) && std::isfinite(point.z);
      const bool at_origin = point.x == 0.0F && point.y == 0.0F && point.z == 0.0F;
      if (!finite || (options.origin_is_no_return && at_origin)) {
        point.flags |= kPointNoReturn;
        ++no_return;
      }
      point.intensity =
          intensity.present
              ? static_cast<float>(loadValue(p + intensity.offset, intensity.datatype, order))
              : 0.0F;
      double time_s = 0.0;
      if (time_rule != TimeRule::kNone) {
        const double value = loadValue(p + time_field.offset, time_field.datatype, order);
        switch (time_rule) {
          case TimeRule::kNone:
            break;
          case TimeRule::kNanoseconds:
            time_s = value * 1e-9;
            break;
          case TimeRule::kSeconds:
            time_s = value;
            break;
          case TimeRule::kAbsoluteSeconds:
            time_s = value - stamp_s;
            break;
          case TimeRule::kFloat64ByValue:
            if (value > 1e15) {
              time_s = (value - static_cast<double>(header.stamp_ns)) * 1e-9;
            } else if (value > 1e6) {
              time_s = value - stamp_s;
            } else {
              time_s = value;
            }
            break;
        }
      }
      point.time_s = static_cast<float>(time_s);
    }
  }
  header.no_return = no_return;
  return header;
}

}  // namespace raymap::msgs
