// SPDX-License-Identifier: BSD-3-Clause
// raymap::RecordingReader for Python: a rosbag2 bag (lidar clouds with odometry or TF, depth
// images with CameraInfo) or a ray-/point-cloud PLY, scan by scan as NumPy arrays of world rays,
// or a bag cloud by cloud in the sensor's frame with its poses. Each scan's (cloud's) arrays are
// views of one buffer it owns (no copy per field).
#include <array>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "arrays.hpp"
#include "bindings.hpp"
#include "errors.hpp"
#include "raymap/recording.hpp"
#include "scan_rays.hpp"
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

namespace py = pybind11;

namespace raymap::python {

const ScanRays& scanRaysOf(const py::object& object) {
  const ScanRays* scan = inCapsule<ScanRays>(object, kScanRaysCapsule);
  if (scan == nullptr) {
    raiseInvalid("not the rays of a scan from raymap.read_recording()");
  }
  return *scan;
}

const RecordedCloud& cloudOf(const py::object& object) {
  const RecordedCloud* cloud = inCapsule<RecordedCloud>(object, kRecordedCloudCapsule);
  if (cloud == nullptr) {
    raiseInvalid("not the points of a cloud from raymap.read_clouds()");
  }
  return *cloud;
}

namespace {

/// A cloud's fields; its arrays view the cloud's own vectors (an Isometry3d is a column-major
/// 4 x 4 of doubles: element (r, c) at 8 r + 32 c bytes).
py::dict cloudArrays(RecordedCloud cloud) {
  const py::capsule owner = ownInCapsule(std::move(cloud), kRecordedCloudCapsule);
  const RecordedCloud* c = &cloudOf(owner);
  const auto rows = static_cast<py::ssize_t>(c->points.size());
  const auto stride = static_cast<py::ssize_t>(sizeof(SensorPoint));
  static const SensorPoint kNoPoint;
  const SensorPoint* first = rows > 0 ? c->points.data() : &kNoPoint;
  const auto samples = static_cast<py::ssize_t>(c->sensor_poses.size());
  const auto pose_stride = static_cast<py::ssize_t>(sizeof(TimedPose));
  static const TimedPose kNoPose;
  const TimedPose* pose = samples > 0 ? c->sensor_poses.data() : &kNoPose;
  py::dict d;
  d["topic"] = c->topic;
  d["frame_id"] = c->frame_id;
  d["stamp_ns"] = c->stamp_ns;
  d["points"] = arrayOver<double>(first->position.data(), {rows, 3}, {stride, 8}, owner);
  d["times"] = arrayOver<double>(&first->time_s, {rows}, {stride}, owner);
  d["intensities"] = arrayOver<float>(&first->intensity, {rows}, {stride}, owner);
  d["no_return"] = arrayOver<bool>(&first->no_return, {rows}, {stride}, owner);
  d["pose_times"] = arrayOver<double>(&pose->time_s, {samples}, {pose_stride}, owner);
  d["poses"] = arrayOver<double>(pose->sensor_to_world.matrix().data(), {samples, 4, 4},
                                 {pose_stride, 8, 32}, owner);
  d["sensor_to_base"] =
      arrayOver<double>(c->sensor_to_base.matrix().data(), {4, 4}, {8, 32}, owner);
  d["cloud"] = owner;
  return d;
}

py::dict scanArrays(std::vector<WorldRay> rays) {
  const py::capsule owner = ownInCapsule(ScanRays{std::move(rays)}, kScanRaysCapsule);
  const ScanRays* scan = &scanRaysOf(owner);
  const auto rows = static_cast<py::ssize_t>(scan->rays.size());
  const auto stride = static_cast<py::ssize_t>(sizeof(WorldRay));
  static const WorldRay kEmpty;
  const WorldRay* first = rows > 0 ? scan->rays.data() : &kEmpty;
  py::dict d;
  d["origins"] = arrayOver<double>(first->origin.data(), {rows, 3}, {stride, 8}, owner);
  d["ends"] = arrayOver<double>(first->end.data(), {rows, 3}, {stride, 8}, owner);
  d["intensities"] = arrayOver<float>(&first->intensity, {rows}, {stride}, owner);
  d["no_return"] = arrayOver<bool>(&first->no_return, {rows}, {stride}, owner);
  d["rays"] = owner;
  return d;
}

/// The reader's next item (`next`: nextScan or nextCloud) read with the GIL released, as
/// `arrays` makes it; None at the end.
template <class Item, class Arrays>
py::object nextAsArrays(RecordingReader& reader, Result<bool> (RecordingReader::*next)(Item&),
                        Arrays arrays) {
  Item item;
  Result<bool> more = [&] {
    py::gil_scoped_release release;
    return (reader.*next)(item);
  }();
  if (!valueOr(std::move(more))) {
    return py::none();
  }
  return arrays(std::move(item));
}

py::dict reportDict(const RecordingReport& r) {
  py::dict d;
  d["pose_source"] = r.pose_source;
  d["topics"] = r.topics;
  d["messages"] = r.messages;
  d["clouds"] = r.clouds;
  d["scans"] = r.scans;
  d["scans_no_pose"] = r.scans_no_pose;
  d["clouds_skipped"] = r.clouds_skipped;
  d["rate_limited"] = r.rate_limited;
  d["images_no_camera_info"] = r.images_no_camera_info;
  return d;
}

std::array<double, 3> toArray(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
Eigen::Vector3d toVector(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }

void bindOptions(py::module_& m) {
  py::class_<BagOptions>(m, "BagOptions", "How a rosbag2 bag is read (as raymap populate).")
      .def(py::init<>())
      .def_readwrite("topics", &BagOptions::topics)
      .def_readwrite("camera_info_topics", &BagOptions::camera_info_topics)
      .def_readwrite("pose_topic", &BagOptions::pose_topic)
      .def_property(
          "pose_source",
          [](const BagOptions& b) {
            return b.pose_source == BagOptions::PoseSource::kOdometry ? "odometry"
                   : b.pose_source == BagOptions::PoseSource::kTf     ? "tf"
                                                                      : "auto";
          },
          [](BagOptions& b, const std::string& name) {
            if (name != "auto" && name != "odometry" && name != "tf") {
              raiseInvalid("bag.pose_source: '" + name + "' is not auto, odometry or tf");
            }
            b.pose_source = name == "odometry" ? BagOptions::PoseSource::kOdometry
                            : name == "tf"     ? BagOptions::PoseSource::kTf
                                               : BagOptions::PoseSource::kAuto;
          })
      .def_readwrite("world_frame", &BagOptions::world_frame)
      .def_readwrite("base_frame", &BagOptions::base_frame)
      .def_property(
          "sensor_offset",
          [](const BagOptions& b) -> std::optional<std::array<double, 3>> {
            if (!b.sensor_offset) {
              return std::nullopt;
            }
            return toArray(*b.sensor_offset);
          },
          [](BagOptions& b, const std::optional<std::array<double, 3>>& offset) {
            b.sensor_offset.reset();
            if (offset) {
              b.sensor_offset = toVector(*offset);
            }
          },
          "the sensor in base_frame (x, y, z metres) where /tf_static has no chain, or None")
      .def_readwrite("time_field", &BagOptions::time_field)
      .def_readwrite("downsample", &BagOptions::downsample)
      .def_readwrite("depth_min_range", &BagOptions::depth_min_range)
      .def_readwrite("depth_max_range", &BagOptions::depth_max_range)
      .def_readwrite("invalid_as_free", &BagOptions::invalid_as_free)
      .def_readwrite("max_rate_hz", &BagOptions::max_rate_hz)
      .def_readwrite("skip_damaged", &BagOptions::skip_damaged);
  py::class_<RecordingOptions>(m, "RecordingOptions", "How a recording is read.")
      .def(py::init<>())
      .def_readwrite("trajectory_path", &RecordingOptions::trajectory_path)
      .def_property(
          "sensor_offset", [](const RecordingOptions& r) { return toArray(r.sensor_offset); },
          [](RecordingOptions& r, const std::array<double, 3>& offset) {
            r.sensor_offset = toVector(offset);
          },
          "the sensor in the trajectory's body frame (x, y, z metres)")
      .def_readwrite("scan_period_s", &RecordingOptions::scan_period_s)
      .def_readwrite("bag", &RecordingOptions::bag);
}

}  // namespace

void bindRecording(py::module_& m) {
  bindOptions(m);
  py::class_<RecordingReader>(m, "_RecordingReader", "raymap::RecordingReader.")
      .def_static(
          "open",
          [](const std::string& path, const RecordingOptions& options) {
            return valueOr(RecordingReader::open(path, options));
          },
          py::arg("path"), py::arg("options"))
      .def(
          "next_scan",
          [](RecordingReader& reader) {
            return nextAsArrays(reader, &RecordingReader::nextScan, scanArrays);
          },
          "The next scan as a dict of arrays (origins, ends, intensities, no_return), or None "
          "at the end.")
      .def(
          "next_cloud",
          [](RecordingReader& reader) {
            return nextAsArrays(reader, &RecordingReader::nextCloud, cloudArrays);
          },
          "A bag's next cloud or depth image in its sensor's frame, with the sensor's poses, as "
          "a dict of arrays, or None at the end.")
      .def_property_readonly("progress", &RecordingReader::progress)
      .def_property_readonly("is_bag", &RecordingReader::isBag)
      .def("report", [](const RecordingReader& r) { return reportDict(r.report()); })
      .def("warnings", &RecordingReader::warnings);
}

}  // namespace raymap::python
