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

namespace {

/// What a PointCloud2 says about itself: its header, the fields raymap uses and where its data is.
struct CloudLayout {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  std::string_view frame_id;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  Field x, y, z, intensity;
  Field time_candidates[kAutoTimeFieldCount];  // auto mode: one per candidate name
  Field explicit_time;
  bool is_bigendian = false;
  std::uint32_t point_step = 0;
  std::uint32_t row_step = 0;
  std::uint32_t data_size = 0;
  std::span<const std::byte> data;
  bool is_dense = false;
};

/// The field a name fills (the first of each name wins), or nullptr for one raymap does not use.
Field* slotFor(std::string_view name, const CloudDecodeOptions& options, CloudLayout& layout) {
  if (name == "x") {
    return &layout.x;
  }
  if (name == "y") {
    return &layout.y;
  }
  if (name == "z") {
    return &layout.z;
  }
  if (nameIs(name, options.intensity_field)) {
    return &layout.intensity;
  }
  if (options.ignore_time) {
    return nullptr;  // every point at the header stamp
  }
  if (options.time_field != nullptr) {
    return nameIs(name, options.time_field) ? &layout.explicit_time : nullptr;
  }
  for (int k = 0; k < kAutoTimeFieldCount; ++k) {
    if (name == kAutoTimeFields[k]) {
      return &layout.time_candidates[k];
    }
  }
  return nullptr;
}

/// Reads the message's fields in order, checking only that they are there.
Expected<void, CloudError> readLayout(CdrReader& reader, const CloudDecodeOptions& options,
                                      CloudLayout& layout) noexcept {
  const auto truncatedOrMalformed = [&reader]() {
    return Unexpected(reader.malformed() ? CloudError::kMalformed : CloudError::kTruncated);
  };
  std::uint32_t field_count = 0;
  if (!reader.readI32(layout.sec) || !reader.readU32(layout.nanosec) ||
      !reader.readString(layout.frame_id) || !reader.readU32(layout.height) ||
      !reader.readU32(layout.width) ||
      // A PointField takes at least 16 bytes: name length, offset, datatype (+3 padding), count.
      !reader.readSequenceLength(field_count, 16)) {
    return truncatedOrMalformed();
  }
  for (std::uint32_t i = 0; i < field_count; ++i) {
    std::string_view name;
    Field field;
    field.present = true;
    if (!reader.readString(name) || !reader.readU32(field.offset) ||
        !reader.readU8(field.datatype) || !reader.readU32(field.count)) {
      return truncatedOrMalformed();
    }
    Field* slot = slotFor(name, options, layout);
    if (slot != nullptr && !slot->present) {
      *slot = field;
    }
  }
  if (!reader.readBool(layout.is_bigendian) || !reader.readU32(layout.point_step) ||
      !reader.readU32(layout.row_step) || !reader.readSequenceLength(layout.data_size, 1) ||
      !reader.readBytes(layout.data_size, layout.data) || !reader.readBool(layout.is_dense)) {
    return truncatedOrMalformed();
  }
  return {};
}

/// The per-point time field the options ask for, and how its values become seconds.
Expected<void, CloudError> chooseTime(const CloudLayout& layout, const CloudDecodeOptions& options,
                                      Field& time_field, TimeRule& rule) noexcept {
  rule = TimeRule::kNone;
  if (options.ignore_time) {
    return {};  // time_field stays absent
  }
  if (options.time_field != nullptr) {
    if (!layout.explicit_time.present) {
      return Unexpected(CloudError::kMissingTimeField);
    }
    time_field = layout.explicit_time;
  } else {
    for (const Field& candidate : layout.time_candidates) {
      if (candidate.present) {
        time_field = candidate;
        break;
      }
    }
  }
  if (!time_field.present) {
    return {};
  }
  if (datatypeSize(time_field.datatype) == 0 || time_field.count < 1) {
    return Unexpected(CloudError::kBadFieldType);
  }
  switch (options.time_unit) {
    case TimeUnit::kAuto:
      if (time_field.datatype == static_cast<std::uint8_t>(PointFieldType::kFloat32)) {
        rule = TimeRule::kSeconds;
      } else if (time_field.datatype == static_cast<std::uint8_t>(PointFieldType::kFloat64)) {
        rule = TimeRule::kFloat64ByValue;
      } else {
        rule = TimeRule::kNanoseconds;
      }
      break;
    case TimeUnit::kRelativeNanoseconds:
      rule = TimeRule::kNanoseconds;
      break;
    case TimeUnit::kRelativeSeconds:
      rule = TimeRule::kSeconds;
      break;
    case TimeUnit::kAbsoluteSeconds:
      rule = TimeRule::kAbsoluteSeconds;
      break;
  }
  return {};
}

/// The first checks of a layout: a frame that fits, float x, y and z, a point that holds them.
Expected<void, CloudError> checkCoordinates(const CloudLayout& l) noexcept {
  if (l.frame_id.size() >= sizeof(CloudHeader::frame_id)) {
    return Unexpected(CloudError::kFrameIdTooLong);
  }
  if (!l.x.present || !l.y.present || !l.z.present) {
    return Unexpected(CloudError::kMissingXyz);
  }
  for (const Field* f : {&l.x, &l.y, &l.z}) {
    if (!isFloatType(f->datatype) || f->count != 1) {
      return Unexpected(CloudError::kBadFieldType);
    }
  }
  const std::uint64_t xyz_bytes = std::uint64_t{datatypeSize(l.x.datatype)} +
                                  datatypeSize(l.y.datatype) + datatypeSize(l.z.datatype);
  if (l.point_step == 0 || l.point_step < xyz_bytes) {
    return Unexpected(CloudError::kPointStepTooSmall);
  }
  return {};
}

/// The checks after the time field is chosen: a usable intensity, every used field inside the
/// point, rows and data that add up, room for the points in `capacity`.
Expected<void, CloudError> checkExtent(const CloudLayout& l, const Field& time_field,
                                       std::size_t capacity) noexcept {
  if (l.intensity.present && (datatypeSize(l.intensity.datatype) == 0 || l.intensity.count < 1)) {
    return Unexpected(CloudError::kBadFieldType);
  }
  for (const Field* f : {&l.x, &l.y, &l.z, &time_field, &l.intensity}) {
    if (f->present &&
        std::uint64_t{f->offset} + datatypeSize(f->datatype) > std::uint64_t{l.point_step}) {
      return Unexpected(CloudError::kFieldOutsidePoint);
    }
  }
  // Rows and data size (64-bit products of 32-bit values cannot overflow).
  const std::uint64_t points = std::uint64_t{l.width} * l.height;
  if (points > 0 && std::uint64_t{l.row_step} < std::uint64_t{l.width} * l.point_step) {
    return Unexpected(CloudError::kRowStepTooSmall);
  }
  if (std::uint64_t{l.data_size} != (points > 0 ? std::uint64_t{l.row_step} * l.height : 0)) {
    return Unexpected(CloudError::kDataSizeMismatch);
  }
  if (points > capacity) {
    return Unexpected(CloudError::kTooManyPoints);
  }
  return {};
}

/// A point's time field as seconds after the header stamp.
double pointTime(double value, TimeRule rule, double stamp_s, std::int64_t stamp_ns) noexcept {
  switch (rule) {
    case TimeRule::kNone:
      return 0.0;
    case TimeRule::kNanoseconds:
      return value * 1e-9;
    case TimeRule::kSeconds:
      return value;
    case TimeRule::kAbsoluteSeconds:
      return value - stamp_s;
    case TimeRule::kFloat64ByValue:
      if (value > 1e15) {
        return (value - static_cast<double>(stamp_ns)) * 1e-9;
      }
      return value > 1e6 ? value - stamp_s : value;
  }
  return 0.0;
}

/// Reads every point of a checked layout into `out`; returns the no-return count.
std::uint32_t decodePoints(const CloudLayout& l, const Field& time_field, TimeRule time_rule,
                           const CloudDecodeOptions& options, std::int64_t stamp_ns,
                           std::span<ScanPoint> out) noexcept {
  // Absolute times are converted relative to the stamp in double: 1.7e9 s keeps ~0.2 us.
  const double stamp_s = static_cast<double>(l.sec) + static_cast<double>(l.nanosec) * 1e-9;
  const std::endian order = l.is_bigendian ? std::endian::big : std::endian::little;
  std::uint32_t no_return = 0;
  std::size_t n = 0;
  for (std::uint32_t row = 0; row < l.height; ++row) {
    const std::byte* row_bytes = l.data.data() + std::size_t{row} * l.row_step;
    for (std::uint32_t column = 0; column < l.width; ++column, ++n) {
      const std::byte* p = row_bytes + std::size_t{column} * l.point_step;
      ScanPoint& point = out[n];
      point.x = loadCoordinate(p + l.x.offset, l.x.datatype, order);
      point.y = loadCoordinate(p + l.y.offset, l.y.datatype, order);
      point.z = loadCoordinate(p + l.z.offset, l.z.datatype, order);
      point.flags = 0;
      const bool finite =
          std::isfinite(point.x) && std::isfinite(point.y) && std::isfinite(point.z);
      const bool at_origin = point.x == 0.0F && point.y == 0.0F && point.z == 0.0F;
      if (!finite || (options.origin_is_no_return && at_origin)) {
        point.flags |= kPointNoReturn;
        ++no_return;
      }
      point.intensity =
          l.intensity.present
              ? static_cast<float>(loadValue(p + l.intensity.offset, l.intensity.datatype, order))
              : 0.0F;
      const double time_s =
          time_rule == TimeRule::kNone
              ? 0.0
              : pointTime(loadValue(p + time_field.offset, time_field.datatype, order), time_rule,
                          stamp_s, stamp_ns);
      point.time_s = static_cast<float>(time_s);
    }
  }
  return no_return;
}

}  // namespace

Expected<CloudHeader, CloudError> decodePointCloud2(std::span<const std::byte> cdr,
                                                    std::span<ScanPoint> out,
                                                    const CloudDecodeOptions& options) noexcept {
  CdrReader reader(cdr);
  if (!reader.ok()) {
    return Unexpected(CloudError::kBadEncapsulation);
  }
  CloudLayout layout;
  if (auto read = readLayout(reader, options, layout); !read) {
    return Unexpected(read.error());
  }
  // The checks in the order that decides which error a bad cloud is counted as.
  if (auto checked = checkCoordinates(layout); !checked) {
    return Unexpected(checked.error());
  }
  Field time_field;
  TimeRule time_rule = TimeRule::kNone;
  if (auto chosen = chooseTime(layout, options, time_field, time_rule); !chosen) {
    return Unexpected(chosen.error());
  }
  if (auto checked = checkExtent(layout, time_field, out.size()); !checked) {
    return Unexpected(checked.error());
  }
  const std::uint64_t points = std::uint64_t{layout.width} * layout.height;
  CloudHeader header{};
  header.stamp_ns = nanosecondsOf(layout.sec, layout.nanosec);
  if (!layout.frame_id.empty()) {  // an empty view may have a null data()
    std::memcpy(header.frame_id, layout.frame_id.data(), layout.frame_id.size());
  }
  header.frame_id[layout.frame_id.size()] = '\0';
  header.width = layout.width;
  header.height = layout.height;
  header.points = static_cast<std::uint32_t>(points);
  header.has_time = time_field.present;
  header.has_intensity = layout.intensity.present;
  if (points == 0) {
    // width 0 and any height (or the reverse) is an empty cloud: no row loop, whose 2^32 empty
    // rows took seconds (found by fuzz_cdr_point_cloud).
    return header;
  }
  header.no_return = decodePoints(layout, time_field, time_rule, options, header.stamp_ns, out);
  return header;
}

}  // namespace raymap::msgs
