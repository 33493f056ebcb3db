// SPDX-License-Identifier: BSD-3-Clause
// Publishes a scene's simulated depth cameras in real time, like a ROS camera driver: each frame
// as sensor_msgs/Image (16UC1 or 32FC1, as the scene file says) with its sensor_msgs/CameraInfo,
// at the camera's rate and stamped with the wall clock; the body's pose as odometry, and each
// camera's optical frame on /tf_static (latched, as robot_state_publisher sends a URDF's).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "raymap/error.hpp"

#include "src/dds/cdr_writer.hpp"
#include "src/driver/ros_endpoints.hpp"
#include "src/sim/depth_camera.hpp"
#include "src/sim/lidar.hpp"
#include "src/sim/scene.hpp"

namespace raymap::driver {

/// @brief Where a simulated camera publishes: "rt/<name>/depth/image_rect_raw" and
/// "rt/<name>/depth/camera_info", frame "<name>_optical_frame" (a RealSense driver's layout).
struct DepthTopics {
  std::string image;
  std::string camera_info;
  std::string frame;
};
DepthTopics depthTopicsFor(const std::string& camera_name);

/// @brief The camera's optical frame in the body frame (the mount and the link -> optical turn).
io::Pose opticalInBody(const sim::CameraMount& mount);

struct DepthPlaybackOptions {
  /// The body's pose as nav_msgs/Odometry at this rate; 0 = none (a lidar playback sends it).
  double odometry_rate_hz = 50.0;
  const char* world_frame = "odom";
  const char* base_frame = "base_link";
  /// Frames per second of every camera; 0 = each camera's own rate from the scene file.
  double rate_hz = 0.0;
};

/// @brief Call publishDue() often (every few ms); it renders and publishes what is due.
/// Thread-safety: one thread. Not real-time (each frame is ray-cast when it is due).
class DepthPlayback {
 public:
  /// @brief Creates the cameras' writers and publishes their /tf_static edges through
  /// `publisher` (which also sends the odometry). Fails for an invalid camera model.
  static Result<std::unique_ptr<DepthPlayback>> create(
      const dds::Participant& participant, DriverPublisher& publisher, const sim::Scene& scene,
      const std::vector<sim::DepthCameraModel>& cameras, sim::SensorPath path, std::uint64_t seed,
      DepthPlaybackOptions options);

  /// @brief Time zero of the recording: now (monotonic) and the wall clock now.
  void start(std::int64_t monotonic_ns, std::int64_t wall_ns);
  /// @brief Publishes the odometry and frames due at `monotonic_ns`; returns when the next is.
  std::int64_t publishDue(std::int64_t monotonic_ns);
  /// @brief Readers matched by every camera's image writer (discovery).
  bool matched() const noexcept;
  std::uint64_t framesPublished() const noexcept { return frames_; }
  std::uint64_t pixelsPublished() const noexcept { return pixels_; }

 private:
  struct Camera {
    sim::DepthCamera camera;
    DepthTopics topics;
    std::unique_ptr<dds::CdrWriter> image;
    std::unique_ptr<dds::CdrWriter> info;
    std::int64_t period_ns = 0;
    std::int64_t next_ns = 0;
    std::uint32_t frame = 0;
  };
  DepthPlayback(DriverPublisher& publisher, const sim::Scene& scene, sim::SensorPath path,
                std::uint64_t seed, DepthPlaybackOptions options)
      : publisher_(publisher),
        scene_(scene),
        path_(std::move(path)),
        seed_(seed),
        options_(options) {}
  void publishFrame(Camera& camera, std::uint32_t index, std::int64_t due_ns);

  DriverPublisher& publisher_;
  const sim::Scene& scene_;
  sim::SensorPath path_;
  std::uint64_t seed_;
  DepthPlaybackOptions options_;
  std::vector<Camera> cameras_;
  std::vector<float> depth_;
  std::vector<std::byte> image_cdr_, info_cdr_;
  std::int64_t t0_ = 0, stamp0_ = 0, odometry_period_ = 0, next_odometry_ = 0;
  std::uint64_t frames_ = 0, pixels_ = 0;
};

}  // namespace raymap::driver
