// SPDX-License-Identifier: BSD-3-Clause
// DepthPlayback: simulated depth cameras published as a ROS camera driver publishes them.
#include "src/driver/depth_playback.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "src/core/eigen_conversions.hpp"
#include "src/dds/topic_types.hpp"
#include "src/msgs/depth_image_writer.hpp"

namespace raymap::driver {
namespace {

constexpr std::int32_t kWriterDepth = 2;

io::Pose bodyPose(const sim::SensorPose& body) {
  return io::Pose{toEigen(body.position),
                  Eigen::Quaterniond(Eigen::AngleAxisd(body.yaw_rad, Eigen::Vector3d::UnitZ()))};
}

}  // namespace

DepthTopics depthTopicsFor(const std::string& camera_name) {
  return {"rt/" + camera_name + "/depth/image_rect_raw", "rt/" + camera_name + "/depth/camera_info",
          camera_name + "_optical_frame"};
}

io::Pose opticalInBody(const sim::CameraMount& mount) {
  const sim::CameraPose optical = sim::cameraPose(mount, sim::SensorPose{});
  Eigen::Matrix3d rotation;
  rotation.col(0) = toEigen(optical.x_axis);
  rotation.col(1) = toEigen(optical.y_axis);
  rotation.col(2) = toEigen(optical.z_axis);
  return io::Pose{toEigen(optical.origin), Eigen::Quaterniond(rotation).normalized()};
}

Result<std::unique_ptr<DepthPlayback>> DepthPlayback::create(
    const dds::Participant& participant, DriverPublisher& publisher, const sim::Scene& scene,
    const std::vector<sim::DepthCameraModel>& cameras, sim::SensorPath path, std::uint64_t seed,
    DepthPlaybackOptions options) {
  std::unique_ptr<DepthPlayback> p(
      new DepthPlayback(publisher, scene, std::move(path), seed, options));
  std::vector<DriverPublisher::StaticEdge> edges;
  std::size_t largest = 0;
  for (const sim::DepthCameraModel& model : cameras) {
    auto camera = sim::DepthCamera::create(model);
    if (!camera) {
      return fail(camera.error().code,
                  "depth camera " + model.name + ": " + camera.error().message);
    }
    Camera c{std::move(camera).value(), depthTopicsFor(model.name), nullptr, nullptr, 0, 0, 0};
    // Best effort, as camera drivers publish (SensorDataQoS).
    auto image = dds::CdrWriter::create(participant, c.topics.image.c_str(), dds::imageType(),
                                        dds::Reliability::kBestEffort, kWriterDepth);
    auto info =
        dds::CdrWriter::create(participant, c.topics.camera_info.c_str(), dds::cameraInfoType(),
                               dds::Reliability::kBestEffort, kWriterDepth);
    if (!image || !info) {
      return fail(ErrorCode::kIo, "depth camera " + model.name + ": cannot create its writers: " +
                                      (!image ? image.error().message : info.error().message));
    }
    c.image = std::make_unique<dds::CdrWriter>(std::move(image).value());
    c.info = std::make_unique<dds::CdrWriter>(std::move(info).value());
    const double rate = options.rate_hz > 0.0 ? options.rate_hz : model.rate_hz;
    c.period_ns = static_cast<std::int64_t>(std::llround(1e9 / rate));
    largest = std::max(largest, c.camera.pixels());
    p->cameras_.push_back(std::move(c));
  }
  // The frames' names must outlive publishTfStatic(): they live in cameras_.
  for (const Camera& c : p->cameras_) {
    edges.push_back(
        {opticalInBody(c.camera.model().mount), options.base_frame, c.topics.frame.c_str()});
  }
  if (!edges.empty()) {
    publisher.publishTfStatic(edges);
  }
  p->depth_.resize(largest);
  p->odometry_period_ =
      options.odometry_rate_hz > 0.0
          ? static_cast<std::int64_t>(std::llround(1e9 / options.odometry_rate_hz))
          : 20000000;  // the lead frames keep over the poses another playback sends
  return p;
}

bool DepthPlayback::matched() const noexcept {
  return std::all_of(cameras_.begin(), cameras_.end(),
                     [](const Camera& c) { return c.image->matchedReaders() > 0; });
}

void DepthPlayback::start(std::int64_t monotonic_ns, std::int64_t wall_ns) {
  t0_ = monotonic_ns;
  stamp0_ = wall_ns;
  next_odometry_ = monotonic_ns;
  for (Camera& c : cameras_) {
    c.next_ns = monotonic_ns + c.period_ns;  // the first frame after a pose or two
    c.frame = 0;
  }
}

void DepthPlayback::publishFrame(Camera& camera, std::uint32_t index, std::int64_t due_ns) {
  const double t = path_.startTime() + static_cast<double>(due_ns - t0_) * 1e-9;
  const sim::CameraPose pose = sim::cameraPose(camera.camera.model().mount, path_.at(t));
  const std::span<float> depth(depth_.data(), camera.camera.pixels());
  camera.camera.render(
      scene_, pose,
      sim::frameSeed(seed_, static_cast<std::uint32_t>(&camera - cameras_.data()), index), depth);
  const sim::DepthCameraModel& m = camera.camera.model();
  const std::int64_t stamp = stamp0_ + (due_ns - t0_);
  msgs::serializeCameraInfo(stamp, camera.topics.frame, camera.camera.intrinsics(), info_cdr_);
  msgs::serializeDepthImage(stamp, camera.topics.frame, m.width, m.height,
                            m.encoding == sim::DepthEncoding::k16UC1 ? msgs::DepthEncoding::k16UC1
                                                                     : msgs::DepthEncoding::k32FC1,
                            false, depth, image_cdr_);
  // CameraInfo first, as drivers publish it (an image never waits for its intrinsics).
  (void)camera.info->write(info_cdr_);
  (void)camera.image->write(image_cdr_);
  ++frames_;
  pixels_ += camera.camera.pixels();
}

std::int64_t DepthPlayback::publishDue(std::int64_t monotonic_ns) {
  while (options_.odometry_rate_hz > 0.0 && next_odometry_ <= monotonic_ns) {
    const double t = path_.startTime() + static_cast<double>(next_odometry_ - t0_) * 1e-9;
    publisher_.publishOdometry(stamp0_ + (next_odometry_ - t0_), bodyPose(path_.at(t)),
                               options_.world_frame, options_.base_frame);
    next_odometry_ += odometry_period_;
  }
  std::int64_t next = options_.odometry_rate_hz > 0.0 ? next_odometry_ : monotonic_ns + 100000000;
  for (Camera& c : cameras_) {
    // A frame is due once the poses around it are out: odometry leads by a period.
    if (c.next_ns + odometry_period_ <= monotonic_ns) {
      publishFrame(c, c.frame++, c.next_ns);
      c.next_ns += c.period_ns;
      // Rendering late (a slow machine) skips frames rather than bursting them.
      while (c.next_ns + odometry_period_ <= monotonic_ns) {
        c.next_ns += c.period_ns;
        ++c.frame;
      }
    }
    next = std::min(next, c.next_ns + odometry_period_);
  }
  return next;
}

}  // namespace raymap::driver
