// SPDX-License-Identifier: BSD-3-Clause
// Per-type rendering for `raymap echo`: GridMap, OccupancyGrid, PointCloud2, DiagnosticArray,
// Odometry and TFMessage, each decoded from its CDR bytes with the decoders of src/dds.
#include "tools/raymap/echo_printers.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <utility>
#include <vector>

#include "src/core/pinhole_camera.hpp"
#include "src/dds/ros_time.hpp"
#include "src/msgs/camera_info.hpp"
#include "src/msgs/cdr_reader.hpp"
#include "src/msgs/depth_image.hpp"
#include "src/msgs/diagnostics_decode.hpp"
#include "src/msgs/grid_map_decode.hpp"
#include "src/msgs/occupancy_grid_decode.hpp"
#include "src/msgs/point_cloud.hpp"
#include "src/msgs/pose.hpp"
#include "tools/raymap/dds_cli.hpp"
#include "tools/raymap/json_output.hpp"

namespace raymap::cli {
namespace {

void appendFormat(std::string& out, const char* format, ...) __attribute__((format(printf, 2, 3)));

/// printf onto the end of `out`, whatever the length (wire strings may be long).
void appendFormat(std::string& out, const char* format, ...) {
  va_list args;
  va_start(args, format);
  va_list again;
  va_copy(again, args);
  const int n = std::vsnprintf(nullptr, 0, format, args);
  va_end(args);
  if (n > 0) {
    const std::size_t start = out.size();
    out.resize(start + static_cast<std::size_t>(n) + 1);
    std::vsnprintf(out.data() + start, static_cast<std::size_t>(n) + 1, format, again);
    out.resize(start + static_cast<std::size_t>(n));  // drop vsnprintf's NUL
  }
  va_end(again);
}

/// A wire string for the human form: quoted when empty or when it holds spaces, so that the
/// fields of a line stay apart.
std::string humanText(std::string_view text) {
  std::string safe = printableText(text, true);
  if (safe.empty() || safe.find(' ') != std::string::npos) {
    return "\"" + safe + "\"";
  }
  return safe;
}

/// A wire string as a JSON string: valid UTF-8 (bad bytes become U+FFFD); control characters
/// stay, JSON escapes them.
std::string jsonText(std::string_view text) { return printableText(text, false); }

/// One object of the JSON Lines stream: compact, so that it is one line.
std::string jsonLine(const Json& j) { return dumpJson(j, JsonStyle::kCompact) + "\n"; }

/// The keys every JSON line has, in this order.
Json jsonCommon(const EchoSample& sample, std::int64_t stamp_ns) {
  return {
      {"topic", sample.topic},
      {"type", sample.type->ros_name},
      {"index", sample.index},
      {"arrival_unix_ns", sample.arrival_unix_ns},
      {"arrival_monotonic_ns", sample.arrival_monotonic_ns},
      {"source_timestamp_ns", sample.source_timestamp_ns},
      {"stamp_ns", stamp_ns},
      {"bytes", sample.cdr.size()},
  };
}

/// "#3 rt/height_map grid_map_msgs/msg/GridMap stamp 1700000000.250000000"
std::string humanFirstLine(const EchoSample& sample, std::int64_t stamp_ns) {
  std::string out;
  appendFormat(out, "#%llu %s %s stamp %s", static_cast<unsigned long long>(sample.index),
               printableText(sample.topic, true).c_str(), sample.type->ros_name,
               stampText(stamp_ns).c_str());
  return out;
}

Json jsonXyz(double x, double y, double z) { return {{"x", x}, {"y", y}, {"z", z}}; }

Json jsonQuaternion(double w, double x, double y, double z) {
  return {{"w", w}, {"x", x}, {"y", y}, {"z", z}};
}

// ---------------------------------------------------------------- GridMap

const char* describe(msgs::GridMapError error) {
  switch (error) {
    case msgs::GridMapError::kTruncated:
      return "the bytes end before the message does";
    case msgs::GridMapError::kBadEncapsulation:
      return "not XCDR1 (the encapsulation header is not CDR_LE or CDR_BE)";
    case msgs::GridMapError::kMalformed:
      return "a string without its terminating NUL";
    case msgs::GridMapError::kLayerCountMismatch:
      return "data does not hold one array per layer name";
    case msgs::GridMapError::kLayoutMismatch:
      return "a layer's array does not have two dimensions whose sizes match its data";
  }
  return "unknown error";
}

/// A GridMap's layers as JSON: name, cells, finite cells, min and max (null when the layer has
/// no finite cell: they are then not finite).
Json layersJson(const msgs::DecodedGridMap& map, const std::vector<msgs::LayerStats>& stats) {
  Json layers = Json::array();
  for (std::size_t i = 0; i < map.layers.size(); ++i) {
    layers.push_back(Json{
        {"name", jsonText(map.layers[i])},
        {"cells", stats[i].cells},
        {"finite", stats[i].finite},
        {"min", stats[i].min},
        {"max", stats[i].max},
    });
  }
  return layers;
}

Result<std::string> formatGridMap(const EchoSample& sample, EchoFormat format) {
  auto decoded = msgs::decodeGridMap(sample.cdr);
  if (!decoded) {
    return fail(ErrorCode::kFormat,
                std::string(msgs::toString(decoded.error())) + ": " + describe(decoded.error()));
  }
  const msgs::DecodedGridMap& map = *decoded;
  std::vector<msgs::LayerStats> stats;
  stats.reserve(map.data.size());
  for (const msgs::GridMapLayerData& array : map.data) {
    // decodeGridMap checked data_offset + cells == data.size()
    stats.push_back(
        msgs::layerStats(std::span<const float>(array.data).subspan(array.data_offset)));
  }
  const long cells_x = map.resolution > 0.0 ? std::lround(map.length_x / map.resolution) : 0;
  const long cells_y = map.resolution > 0.0 ? std::lround(map.length_y / map.resolution) : 0;
  if (format == EchoFormat::kJsonLines) {
    Json j = jsonCommon(sample, map.stamp_ns);
    j["frame"] = jsonText(map.frame_id);
    j["resolution"] = map.resolution;
    j["length_x"] = map.length_x;
    j["length_y"] = map.length_y;
    j["cells_x"] = cells_x;
    j["cells_y"] = cells_y;
    j["centre_x"] = map.centre_x;
    j["centre_y"] = map.centre_y;
    j["centre_z"] = map.centre_z;
    j["layers"] = layersJson(map, stats);
    j["basic_layers"] = Json::array();
    for (const std::string& name : map.basic_layers) {
      j["basic_layers"].push_back(jsonText(name));
    }
    j["outer_start_index"] = map.outer_start_index;
    j["inner_start_index"] = map.inner_start_index;
    return jsonLine(j);
  }
  std::string out = humanFirstLine(sample, map.stamp_ns);
  appendFormat(out, " frame %s\n", humanText(map.frame_id).c_str());
  appendFormat(out, "  resolution %g m, %g x %g m (%ld x %ld cells), centre (%g, %g, %g) m\n",
               map.resolution, map.length_x, map.length_y, cells_x, cells_y, map.centre_x,
               map.centre_y, map.centre_z);
  std::string names;
  for (const std::string& name : map.layers) {
    names += names.empty() ? "" : ", ";
    names += humanText(name);
  }
  std::string basic;
  for (const std::string& name : map.basic_layers) {
    basic += basic.empty() ? "" : ", ";
    basic += humanText(name);
  }
  appendFormat(out, "  layers %s (basic: %s)\n", names.empty() ? "none" : names.c_str(),
               basic.empty() ? "none" : basic.c_str());
  std::size_t width = 0;
  for (const std::string& name : map.layers) {
    width = std::max(width, humanText(name).size());
  }
  for (std::size_t i = 0; i < map.layers.size(); ++i) {
    const msgs::LayerStats& s = stats[i];
    appendFormat(out, "    %-*s %llu / %llu finite", static_cast<int>(width),
                 humanText(map.layers[i]).c_str(), static_cast<unsigned long long>(s.finite),
                 static_cast<unsigned long long>(s.cells));
    if (s.finite > 0) {
      appendFormat(out, ", min %.6g, max %.6g", static_cast<double>(s.min),
                   static_cast<double>(s.max));
    }
    out += "\n";
  }
  return out;
}

// ---------------------------------------------------------------- OccupancyGrid

const char* describe(msgs::OccupancyGridError error) {
  switch (error) {
    case msgs::OccupancyGridError::kTruncated:
      return "the bytes end before the message does";
    case msgs::OccupancyGridError::kBadEncapsulation:
      return "not XCDR1 (the encapsulation header is not CDR_LE or CDR_BE)";
    case msgs::OccupancyGridError::kMalformed:
      return "a string without its terminating NUL";
    case msgs::OccupancyGridError::kSizeMismatch:
      return "data does not hold width x height cells";
  }
  return "unknown error";
}

/// Cells of an OccupancyGrid by what they say: unknown (-1), free (0), costed (1..99), lethal
/// (100), and values no costmap uses.
struct OccupancyCounts {
  std::uint64_t unknown = 0, free = 0, costed = 0, lethal = 0, invalid = 0;
};

OccupancyCounts countCells(const std::vector<std::int8_t>& data) {
  OccupancyCounts c;
  for (const std::int8_t v : data) {
    if (v == -1) {
      ++c.unknown;
    } else if (v == 0) {
      ++c.free;
    } else if (v > 0 && v < 100) {
      ++c.costed;
    } else if (v == 100) {
      ++c.lethal;
    } else {
      ++c.invalid;
    }
  }
  return c;
}

Result<std::string> formatOccupancyGrid(const EchoSample& sample, EchoFormat format) {
  auto decoded = msgs::decodeOccupancyGrid(sample.cdr);
  if (!decoded) {
    return fail(ErrorCode::kFormat,
                std::string(msgs::toString(decoded.error())) + ": " + describe(decoded.error()));
  }
  const msgs::DecodedOccupancyGrid& grid = *decoded;
  const OccupancyCounts c = countCells(grid.data);
  if (format == EchoFormat::kJsonLines) {
    Json j = jsonCommon(sample, grid.stamp_ns);
    j["frame"] = jsonText(grid.frame_id);
    j["resolution"] = grid.resolution;
    j["width"] = grid.width;
    j["height"] = grid.height;
    j["origin_x"] = grid.origin_x;
    j["origin_y"] = grid.origin_y;
    j["origin_z"] = grid.origin_z;
    j["unknown"] = c.unknown;
    j["free"] = c.free;
    j["costed"] = c.costed;
    j["lethal"] = c.lethal;
    j["invalid"] = c.invalid;
    return jsonLine(j);
  }
  std::string out = humanFirstLine(sample, grid.stamp_ns);
  appendFormat(out, " frame %s\n", humanText(grid.frame_id).c_str());
  appendFormat(out, "  resolution %g m, %u x %u cells, origin (%g, %g, %g) m\n",
               static_cast<double>(grid.resolution), grid.width, grid.height, grid.origin_x,
               grid.origin_y, grid.origin_z);
  appendFormat(out,
               "  cells: %llu unknown, %llu free, %llu costed (1-99), %llu lethal, %llu invalid\n",
               static_cast<unsigned long long>(c.unknown), static_cast<unsigned long long>(c.free),
               static_cast<unsigned long long>(c.costed), static_cast<unsigned long long>(c.lethal),
               static_cast<unsigned long long>(c.invalid));
  return out;
}

// ---------------------------------------------------------------- depth Image, CameraInfo

Result<std::string> formatDepthImage(const EchoSample& sample, EchoFormat format) {
  const auto info = msgs::inspectDepthImage(sample.cdr);
  if (!info) {
    return fail(ErrorCode::kFormat, std::string(msgs::toString(info.error())) +
                                        ": not a depth image raymap reads (16UC1, mono16 or "
                                        "32FC1 with a step and data that fit its size)");
  }
  const msgs::DepthImageInfo& image = *info;
  // The depths themselves: decoded through a unit camera (fx = fy = 1 at the top-left pixel),
  // whose points' z is each pixel's depth in metres.
  std::uint64_t valid = 0;
  std::vector<float> depths;
  if (image.width > 0 && image.height > 0 && image.width <= 65535 && image.height <= 65535) {
    CameraIntrinsics unit;
    unit.width = image.width;
    unit.height = image.height;
    unit.fx = 1.0;
    unit.fy = 1.0;
    PixelRayTable rays;
    std::vector<msgs::ScanPoint> points(std::size_t{image.width} * image.height);
    if (rays.build(unit)) {
      const auto decoded = msgs::decodeDepthImage(sample.cdr, rays, {}, points);
      if (decoded) {
        for (std::uint32_t i = 0; i < decoded->points; ++i) {
          depths.push_back(points[i].z);
        }
        valid = decoded->points;
      }
    }
  }
  std::sort(depths.begin(), depths.end());
  const double lo = depths.empty() ? 0.0 : static_cast<double>(depths.front());
  const double hi = depths.empty() ? 0.0 : static_cast<double>(depths.back());
  const double median = depths.empty() ? 0.0 : static_cast<double>(depths[depths.size() / 2]);
  const std::uint64_t pixels = std::uint64_t{image.width} * image.height;
  if (format == EchoFormat::kJsonLines) {
    Json j = jsonCommon(sample, image.stamp_ns);
    j["frame"] = jsonText(image.frame_id);
    j["encoding"] = jsonText(image.encoding);
    j["width"] = image.width;
    j["height"] = image.height;
    j["step"] = image.step;
    j["big_endian"] = image.big_endian;
    j["pixels_with_depth"] = valid;
    j["depth_min_m"] = lo;
    j["depth_median_m"] = median;
    j["depth_max_m"] = hi;
    return jsonLine(j);
  }
  std::string out = humanFirstLine(sample, image.stamp_ns);
  appendFormat(out, " frame %s\n", humanText(image.frame_id).c_str());
  appendFormat(out, "  %s, %u x %u, step %u, %s-endian\n", image.encoding, image.width,
               image.height, image.step, image.big_endian ? "big" : "little");
  appendFormat(out, "  %llu of %llu pixels with a depth", static_cast<unsigned long long>(valid),
               static_cast<unsigned long long>(pixels));
  if (!depths.empty()) {
    appendFormat(out, ": %.3f .. %.3f m (median %.3f m)", lo, hi, median);
  }
  out += "\n";
  return out;
}

Result<std::string> formatCameraInfo(const EchoSample& sample, EchoFormat format) {
  const auto decoded = msgs::decodeCameraInfo(sample.cdr);
  if (!decoded) {
    return fail(ErrorCode::kFormat,
                std::string(msgs::toString(decoded.error())) + ": not a usable camera model");
  }
  const msgs::CameraInfoHeader& info = *decoded;
  const CameraIntrinsics& c = info.camera;
  const bool distorted = c.distortion == DistortionModel::kPlumbBob;
  if (format == EchoFormat::kJsonLines) {
    Json j = jsonCommon(sample, info.stamp_ns);
    j["frame"] = jsonText(info.frame_id);
    j["width"] = c.width;
    j["height"] = c.height;
    j["fx"] = c.fx;
    j["fy"] = c.fy;
    j["cx"] = c.cx;
    j["cy"] = c.cy;
    j["distortion"] = distorted ? "plumb_bob" : "none";
    j["k1"] = c.k1;
    j["k2"] = c.k2;
    j["p1"] = c.p1;
    j["p2"] = c.p2;
    j["k3"] = c.k3;
    return jsonLine(j);
  }
  std::string out = humanFirstLine(sample, info.stamp_ns);
  appendFormat(out, " frame %s\n", humanText(info.frame_id).c_str());
  appendFormat(out, "  %u x %u, fx %g fy %g, cx %g cy %g, ", c.width, c.height, c.fx, c.fy, c.cx,
               c.cy);
  if (distorted) {
    appendFormat(out, "plumb_bob k1 %g k2 %g p1 %g p2 %g k3 %g\n", c.k1, c.k2, c.p1, c.p2, c.k3);
  } else {
    out += "no distortion\n";
  }
  return out;
}

// ---------------------------------------------------------------- PointCloud2

struct CloudField {
  std::string name;
  std::uint32_t offset = 0;
  std::uint8_t datatype = 0;
  std::uint32_t count = 0;
};

/// Everything of a PointCloud2 but its point data, which is only sized.
struct CloudInfo {
  std::int64_t stamp_ns = 0;
  std::string frame_id;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::vector<CloudField> fields;
  bool is_bigendian = false;
  std::uint32_t point_step = 0;
  std::uint32_t row_step = 0;
  std::uint32_t data_bytes = 0;
  bool is_dense = false;
};

/// Reads the header and layout of a PointCloud2 (decodePointCloud2 needs x/y/z; echo shows any
/// cloud). false: truncated or malformed (`malformed` tells which).
bool readCloudInfo(std::span<const std::byte> cdr, CloudInfo& info, bool& malformed) {
  msgs::CdrReader reader(cdr);
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  std::string_view frame;
  std::uint32_t field_count = 0;
  // A PointField takes at least 16 bytes: name length, offset, datatype (+3 padding), count.
  constexpr std::size_t kMinFieldBytes = 16;
  bool read = reader.readI32(sec) && reader.readU32(nanosec) && reader.readString(frame) &&
              reader.readU32(info.height) && reader.readU32(info.width) &&
              reader.readSequenceLength(field_count, kMinFieldBytes);
  if (read) {
    info.fields.resize(field_count);
    for (CloudField& field : info.fields) {
      std::string_view name;
      if (!reader.readString(name) || !reader.readU32(field.offset) ||
          !reader.readU8(field.datatype) || !reader.readU32(field.count)) {
        read = false;
        break;
      }
      field.name.assign(name);
    }
  }
  std::span<const std::byte> data;
  read = read && reader.readBool(info.is_bigendian) && reader.readU32(info.point_step) &&
         reader.readU32(info.row_step) && reader.readSequenceLength(info.data_bytes, 1) &&
         reader.readBytes(info.data_bytes, data) && reader.readBool(info.is_dense);
  malformed = reader.malformed();
  if (!read) {
    return false;
  }
  info.frame_id.assign(frame);
  info.stamp_ns = msgs::nanosecondsOf(sec, nanosec);
  return true;
}

const char* datatypeName(std::uint8_t datatype) {
  switch (static_cast<msgs::PointFieldType>(datatype)) {
    case msgs::PointFieldType::kInt8:
      return "int8";
    case msgs::PointFieldType::kUInt8:
      return "uint8";
    case msgs::PointFieldType::kInt16:
      return "int16";
    case msgs::PointFieldType::kUInt16:
      return "uint16";
    case msgs::PointFieldType::kInt32:
      return "int32";
    case msgs::PointFieldType::kUInt32:
      return "uint32";
    case msgs::PointFieldType::kFloat32:
      return "float32";
    case msgs::PointFieldType::kFloat64:
      return "float64";
  }
  return "unknown";
}

/// Errors after which the cloud is still worth showing (its header and layout are sound); the
/// points are then not counted, and the reason is shown instead.
bool layoutOnlyError(msgs::CloudError error) {
  return error == msgs::CloudError::kMissingXyz || error == msgs::CloudError::kBadFieldType ||
         error == msgs::CloudError::kFrameIdTooLong || error == msgs::CloudError::kMissingTimeField;
}

/// A cloud's PointFields as JSON objects: name, datatype name, offset, count.
Json fieldsJson(const std::vector<CloudField>& fields) {
  Json out = Json::array();
  for (const CloudField& field : fields) {
    out.push_back(Json{
        {"name", jsonText(field.name)},
        {"type", datatypeName(field.datatype)},
        {"offset", field.offset},
        {"count", field.count},
    });
  }
  return out;
}

Result<std::string> formatPointCloud(const EchoSample& sample, EchoFormat format) {
  if (sample.cdr.size() < 4 || !msgs::CdrReader(sample.cdr).ok()) {
    return fail(ErrorCode::kFormat,
                "bad_encapsulation: not XCDR1 (the encapsulation header is not CDR_LE or CDR_BE)");
  }
  CloudInfo info;
  bool malformed = false;
  if (!readCloudInfo(sample.cdr, info, malformed)) {
    return fail(ErrorCode::kFormat, malformed ? "malformed: a string without its terminating NUL"
                                              : "truncated: the bytes end before the message does");
  }
  // Count valid and no-return points with raymapd's own decoder (NaN or (0, 0, 0) = no return).
  // Room only for a cloud whose data really holds width x height points: anything else is
  // refused by the decoder before it would need the room.
  const std::uint64_t points = std::uint64_t{info.width} * info.height;
  const bool consistent =
      info.point_step > 0 && points * info.point_step <= std::uint64_t{info.data_bytes};
  std::vector<msgs::ScanPoint> scratch(consistent ? points : 0);
  msgs::CloudDecodeOptions options;
  options.intensity_field = nullptr;  // not shown; a strange intensity type must not hide points
  const auto decoded = msgs::decodePointCloud2(sample.cdr, scratch, options);
  std::string points_note;
  if (!decoded) {
    if (!layoutOnlyError(decoded.error())) {
      return fail(ErrorCode::kFormat, std::string(msgs::toString(decoded.error())) +
                                          ": the cloud's layout does not match its data");
    }
    points_note = msgs::toString(decoded.error());
  }
  if (format == EchoFormat::kJsonLines) {
    Json j = jsonCommon(sample, info.stamp_ns);
    j["frame"] = jsonText(info.frame_id);
    j["width"] = info.width;
    j["height"] = info.height;
    j["point_step"] = info.point_step;
    j["row_step"] = info.row_step;
    j["is_bigendian"] = info.is_bigendian;
    j["is_dense"] = info.is_dense;
    j["fields"] = fieldsJson(info.fields);
    j["points"] = points;
    if (decoded) {
      j["valid_points"] = decoded->points - decoded->no_return;
      j["no_return"] = decoded->no_return;
    } else {
      j["valid_points"] = nullptr;
      j["no_return"] = nullptr;
      j["points_error"] = points_note;
    }
    return jsonLine(j);
  }
  std::string out = humanFirstLine(sample, info.stamp_ns);
  appendFormat(out, " frame %s\n", humanText(info.frame_id).c_str());
  appendFormat(out, "  %u x %u points, point_step %u, row_step %u%s%s\n", info.width, info.height,
               info.point_step, info.row_step, info.is_bigendian ? ", big endian" : "",
               info.is_dense ? ", dense" : "");
  std::string fields;
  for (const CloudField& field : info.fields) {
    fields += fields.empty() ? "" : " ";
    fields += humanText(field.name) + ":" + datatypeName(field.datatype);
    if (field.count != 1) {
      fields += "[" + std::to_string(field.count) + "]";
    }
  }
  appendFormat(out, "  fields %s\n", fields.empty() ? "none" : fields.c_str());
  if (decoded) {
    appendFormat(out, "  %u valid points, %u no return\n", decoded->points - decoded->no_return,
                 decoded->no_return);
  } else {
    appendFormat(out, "  points not counted: %s\n", points_note.c_str());
  }
  return out;
}

// ---------------------------------------------------------------- DiagnosticArray

const char* describe(msgs::DiagnosticsError error) {
  switch (error) {
    case msgs::DiagnosticsError::kTruncated:
      return "the bytes end before the message does";
    case msgs::DiagnosticsError::kBadEncapsulation:
      return "not XCDR1 (the encapsulation header is not CDR_LE or CDR_BE)";
    case msgs::DiagnosticsError::kMalformed:
      return "a string without its terminating NUL";
  }
  return "unknown error";
}

Result<std::string> formatDiagnostics(const EchoSample& sample, EchoFormat format) {
  auto decoded = msgs::decodeDiagnosticArray(sample.cdr);
  if (!decoded) {
    return fail(ErrorCode::kFormat,
                std::string(msgs::toString(decoded.error())) + ": " + describe(decoded.error()));
  }
  const msgs::DecodedDiagnostics& array = *decoded;
  if (format == EchoFormat::kJsonLines) {
    Json statuses = Json::array();
    for (const msgs::DecodedDiagnosticStatus& status : array.statuses) {
      // An object of key: value strings; a key repeated in the message keeps its last value.
      Json values = Json::object();
      for (const msgs::DiagnosticKeyValue& pair : status.values) {
        values[jsonText(pair.key)] = jsonText(pair.value);
      }
      statuses.push_back(Json{
          {"level", std::uint64_t{status.level}},
          {"level_name", msgs::diagnosticLevelName(status.level)},
          {"name", jsonText(status.name)},
          {"message", jsonText(status.message)},
          {"hardware_id", jsonText(status.hardware_id)},
          {"values", values},
      });
    }
    Json j = jsonCommon(sample, array.stamp_ns);
    j["frame"] = jsonText(array.frame_id);
    j["statuses"] = statuses;
    return jsonLine(j);
  }
  std::string out = humanFirstLine(sample, array.stamp_ns);
  appendFormat(out, ", %zu status%s\n", array.statuses.size(),
               array.statuses.size() == 1 ? "" : "es");
  for (const msgs::DecodedDiagnosticStatus& status : array.statuses) {
    appendFormat(out, "  %-6s %s: %s\n", msgs::diagnosticLevelName(status.level),
                 printableText(status.name, true).c_str(),
                 printableText(status.message, true).c_str());
    if (!status.values.empty()) {
      std::string pairs;
      for (const msgs::DiagnosticKeyValue& pair : status.values) {
        pairs += pairs.empty() ? "" : " ";
        pairs += humanText(pair.key) + "=" + humanText(pair.value);
      }
      out += "         " + pairs + "\n";
    }
  }
  return out;
}

// ---------------------------------------------------------------- Odometry and TFMessage

const char* describe(msgs::PoseError error) {
  switch (error) {
    case msgs::PoseError::kTruncated:
      return "the bytes end before the message does";
    case msgs::PoseError::kBadEncapsulation:
      return "not XCDR1 (the encapsulation header is not CDR_LE or CDR_BE)";
    case msgs::PoseError::kMalformed:
      return "a string without its terminating NUL";
    case msgs::PoseError::kFrameIdTooLong:
      return "a frame id of 64 characters or more";
    case msgs::PoseError::kBadQuaternion:
      return "a rotation that is not finite or has zero norm";
    case msgs::PoseError::kBadTranslation:
      return "a translation that is not finite";
  }
  return "unknown error";
}

/// The transform's keys, appended to `j` (after the common keys, or to an empty object).
void addTransform(Json& j, const msgs::StampedTransform& t) {
  j["frame"] = jsonText(t.parent);
  j["child_frame"] = jsonText(t.child);
  j["position"] = jsonXyz(t.tx, t.ty, t.tz);
  j["orientation"] = jsonQuaternion(t.qw, t.qx, t.qy, t.qz);
}

std::string humanTransform(const msgs::StampedTransform& t) {
  std::string out;
  appendFormat(
      out, "%s -> %s position (%.6g, %.6g, %.6g) m orientation (w %.4f, x %.4f, y %.4f, z %.4f)",
      humanText(t.parent).c_str(), humanText(t.child).c_str(), t.tx, t.ty, t.tz, t.qw, t.qx, t.qy,
      t.qz);
  return out;
}

Result<std::string> formatOdometry(const EchoSample& sample, EchoFormat format) {
  const auto decoded = msgs::decodeOdometry(sample.cdr);
  if (!decoded) {
    return fail(ErrorCode::kFormat,
                std::string(msgs::toString(decoded.error())) + ": " + describe(decoded.error()));
  }
  const msgs::StampedTransform& t = *decoded;
  if (format == EchoFormat::kJsonLines) {
    Json j = jsonCommon(sample, t.stamp_ns);
    addTransform(j, t);
    return jsonLine(j);
  }
  return humanFirstLine(sample, t.stamp_ns) + "\n  " + humanTransform(t) + "\n";
}

Result<std::string> formatTfMessage(const EchoSample& sample, EchoFormat format) {
  // A TransformStamped takes at least 64 bytes (stamp, frame lengths, seven doubles), so this
  // has room for every transform of the message.
  constexpr std::size_t kMinTransformBytes = 64;
  std::vector<msgs::StampedTransform> transforms(sample.cdr.size() / kMinTransformBytes + 1);
  const auto decoded = msgs::decodeTfMessage(sample.cdr, transforms);
  if (!decoded) {
    return fail(ErrorCode::kFormat,
                std::string(msgs::toString(decoded.error())) + ": " + describe(decoded.error()));
  }
  transforms.resize(*decoded);
  // TFMessage has no header: its stamp is the first transform's (0 when empty).
  const std::int64_t stamp_ns = transforms.empty() ? 0 : transforms.front().stamp_ns;
  if (format == EchoFormat::kJsonLines) {
    Json items = Json::array();
    for (const msgs::StampedTransform& t : transforms) {
      Json item = {{"stamp_ns", t.stamp_ns}};
      addTransform(item, t);
      items.push_back(std::move(item));
    }
    Json j = jsonCommon(sample, stamp_ns);
    j["transforms"] = items;
    return jsonLine(j);
  }
  std::string out = humanFirstLine(sample, stamp_ns);
  appendFormat(out, ", %zu transform%s\n", transforms.size(), transforms.size() == 1 ? "" : "s");
  for (const msgs::StampedTransform& t : transforms) {
    out += "  " + humanTransform(t) + " stamp " + stampText(t.stamp_ns) + "\n";
  }
  return out;
}

}  // namespace

Result<std::string> formatSample(const EchoSample& sample, EchoFormat format) {
  if (sample.type == nullptr) {
    return fail(ErrorCode::kInvalidArgument, "no type to decode the message with");
  }
  const dds_topic_descriptor_t* type = sample.type->descriptor;
  if (type == dds::gridMapType()) {
    return formatGridMap(sample, format);
  }
  if (type == dds::pointCloud2Type()) {
    return formatPointCloud(sample, format);
  }
  if (type == dds::diagnosticArrayType()) {
    return formatDiagnostics(sample, format);
  }
  if (type == dds::odometryType()) {
    return formatOdometry(sample, format);
  }
  if (type == dds::tfMessageType()) {
    return formatTfMessage(sample, format);
  }
  if (type == dds::occupancyGridType()) {
    return formatOccupancyGrid(sample, format);
  }
  if (type == dds::imageType()) {
    return formatDepthImage(sample, format);
  }
  if (type == dds::cameraInfoType()) {
    return formatCameraInfo(sample, format);
  }
  return fail(ErrorCode::kUnsupported,
              std::string("no printer for ") + sample.type->ros_name + " (a raymap bug)");
}

}  // namespace raymap::cli
