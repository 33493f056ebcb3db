// SPDX-License-Identifier: BSD-3-Clause
// raymap::RecordingReader: the ray source of `raymap populate` (a PLY reader or the bag reader),
// cut into scans.
#include <utility>

#include "raymap/recording.hpp"

#include "src/bag/bag_ray_source.hpp"
#include "src/bag/bag_reader.hpp"
#include "src/core/eigen_conversions.hpp"
#include "src/mapper/recording.hpp"
#include "src/msgs/point_cloud.hpp"
#include "src/record/record_log.hpp"

namespace raymap {
namespace mapper {

io::RaySourceOptions toRaySourceOptions(const RecordingOptions& options) {
  io::RaySourceOptions source;
  source.trajectory_path = options.trajectory_path;
  source.sensor_offset = toVec3(options.sensor_offset);
  source.scan_period_s = options.scan_period_s;
  return source;
}

bag::BagRaysOptions toBagRaysOptions(const RecordingOptions& options) {
  const BagOptions& in = options.bag;
  bag::BagRaysOptions out;
  out.cloud_topics = in.topics;
  out.camera_info_topics = in.camera_info_topics;
  out.pose_topic = in.pose_topic;
  out.pose_source = in.pose_source == BagOptions::PoseSource::kOdometry
                        ? bag::BagRaysOptions::PoseSource::kOdometry
                    : in.pose_source == BagOptions::PoseSource::kTf
                        ? bag::BagRaysOptions::PoseSource::kTf
                        : bag::BagRaysOptions::PoseSource::kAuto;
  out.world_frame = in.world_frame;
  out.base_frame = in.base_frame;
  out.extrinsic_given = in.sensor_offset.has_value();
  out.extrinsic.position = in.sensor_offset.value_or(Eigen::Vector3d::Zero());
  out.time_field = in.time_field;
  out.depth.downsample = in.downsample;
  out.depth.min_range_m = static_cast<float>(in.depth_min_range);
  out.depth.max_range_m = static_cast<float>(in.depth_max_range);
  out.depth.invalid_as_free = in.invalid_as_free;
  out.max_rate_hz = in.max_rate_hz;
  out.skip_damaged = in.skip_damaged;
  return out;
}

Result<OpenedRecording> openRecording(const std::string& path, const RecordingOptions& options) {
  if (record::isRecordLogInput(path)) {
    return fail(ErrorCode::kFormat, path +
                                        " is a raymap record log: populate maps PLY files and "
                                        "rosbag2 bags (raymap replay plays a log to raymapd)");
  }
  OpenedRecording opened;
  if (bag::isBag(path)) {
    auto source = bag::openBagRaySource(path, toBagRaysOptions(options));
    if (!source) {
      return Unexpected(source.error());
    }
    opened.bag = source->get();
    opened.source = std::move(*source);
    return opened;
  }
  auto source = io::openRaySource(path, toRaySourceOptions(options));
  if (!source) {
    return Unexpected(source.error());
  }
  opened.source = std::move(*source);
  return opened;
}

}  // namespace mapper

struct RecordingReader::State {
  mapper::OpenedRecording recording;
  std::vector<Ray> buffer = std::vector<Ray>(std::size_t{1} << 16);
  std::size_t next = 0;    // first unread ray in buffer
  std::size_t fill = 0;    // rays in buffer
  bag::SensorCloud cloud;  // nextCloud()'s, its buffers reused
  bool reading_clouds = false;
};

RecordingReader::RecordingReader(std::unique_ptr<State> state) noexcept
    : state_(std::move(state)) {}
RecordingReader::RecordingReader(RecordingReader&&) noexcept = default;
RecordingReader& RecordingReader::operator=(RecordingReader&&) noexcept = default;
RecordingReader::~RecordingReader() = default;

Result<RecordingReader> RecordingReader::open(const std::string& path,
                                              const RecordingOptions& options) {
  auto opened = mapper::openRecording(path, options);
  if (!opened) {
    return Unexpected(opened.error());
  }
  auto state = std::make_unique<State>();
  state->recording = std::move(*opened);
  return RecordingReader(std::move(state));
}

Result<bool> RecordingReader::nextScan(std::vector<WorldRay>& scan) {
  State& s = *state_;
  scan.clear();
  if (s.reading_clouds) {
    return fail(ErrorCode::kInvalidArgument,
                s.recording.source->info().path +
                    ": this reader has read clouds; open another to read scans");
  }
  bool have_scan = false;
  std::uint64_t scan_number = 0;
  for (;;) {
    if (s.next == s.fill) {
      auto count = s.recording.source->read(s.buffer);
      if (!count) {
        return Unexpected(count.error());
      }
      s.next = 0;
      s.fill = *count;
      if (s.fill == 0) {
        return have_scan;
      }
    }
    const Ray& ray = s.buffer[s.next];
    if (have_scan && ray.scan != scan_number) {
      return true;  // the next scan starts here
    }
    have_scan = true;
    scan_number = ray.scan;
    WorldRay out;
    out.origin = toEigen(ray.origin);
    out.end = toEigen(ray.sample);
    out.intensity = ray.intensity;
    out.no_return = (ray.flags & kRayNoReturn) != 0u;
    scan.push_back(out);
    ++s.next;
  }
}

Result<bool> RecordingReader::nextCloud(RecordedCloud& cloud) {
  State& s = *state_;
  bag::BagRaySource* bag = s.recording.bag;
  if (bag == nullptr) {
    return fail(ErrorCode::kUnsupported,
                s.recording.source->info().path +
                    ": a file's rays are in the world frame already; read it scan by scan");
  }
  if (s.fill != 0) {
    return fail(ErrorCode::kInvalidArgument,
                s.recording.source->info().path +
                    ": this reader has read scans; open another to read clouds");
  }
  s.reading_clouds = true;
  auto more = bag->nextCloud(s.cloud);
  if (!more || !more.value()) {
    cloud.points.clear();
    cloud.sensor_poses.clear();
    return more;
  }
  const bag::SensorCloud& in = s.cloud;
  cloud.topic = bag->report().cloud_topics.at(in.sensor);
  cloud.frame_id = in.frame_id;
  cloud.stamp_ns = in.stamp_ns;
  cloud.sensor_to_base = in.extrinsic.toIsometry();
  cloud.points.resize(in.points.size());
  for (std::size_t i = 0; i < in.points.size(); ++i) {
    const msgs::ScanPoint& p = in.points[i];
    SensorPoint& out = cloud.points[i];
    out.position = Eigen::Vector3d(static_cast<double>(p.x), static_cast<double>(p.y),
                                   static_cast<double>(p.z));
    out.time_s = static_cast<double>(in.point_offsets_ns[i]) * 1e-9;
    out.intensity = p.intensity;
    out.no_return = (p.flags & msgs::kPointFreeOnly) != 0u;
  }
  cloud.sensor_poses.resize(in.poses.size());
  for (std::size_t i = 0; i < in.poses.size(); ++i) {
    cloud.sensor_poses[i] =
        TimedPose{static_cast<double>(in.pose_offsets_ns[i]) * 1e-9, in.poses[i].toIsometry()};
  }
  return true;
}

double RecordingReader::progress() const noexcept { return state_->recording.source->progress(); }

bool RecordingReader::isBag() const noexcept { return state_->recording.bag != nullptr; }

RecordingReport RecordingReader::report() const {
  RecordingReport out;
  const bag::BagRaySource* bag = state_->recording.bag;
  if (bag == nullptr) {
    return out;
  }
  const bag::BagRaysReport& r = bag->report();
  out.pose_source = r.pose_source;
  out.topics = r.cloud_topics;
  out.messages = r.messages;
  out.clouds = r.clouds;
  out.scans = r.scans_integrated;
  out.scans_no_pose = r.scans_no_pose;
  out.clouds_skipped = r.clouds_skipped;
  out.rate_limited = r.rate_limited;
  out.images_no_camera_info = r.images_no_camera_info;
  return out;
}

std::vector<std::string> RecordingReader::warnings() const {
  std::vector<std::string> out;
  const bag::BagRaySource* bag = state_->recording.bag;
  if (bag == nullptr) {
    return out;
  }
  const bag::BagRaysReport& r = bag->report();
  if (!r.pose_note.empty()) {
    out.push_back(r.pose_note);
  }
  for (const auto* list : {&r.read_warnings, &r.damage, &r.skips}) {
    out.insert(out.end(), list->begin(), list->end());
  }
  return out;
}

}  // namespace raymap
