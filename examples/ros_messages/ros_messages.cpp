// SPDX-License-Identifier: BSD-3-Clause
// The glue of a ROS 2 node of one's own: serialized nav_msgs/Odometry and sensor_msgs/PointCloud2
// messages (what an rclcpp GenericSubscription or a rosbag2 reader hands over) decoded with
// raymap/ros_messages.hpp, the lidar's sweeps deskewed with a pose table of the odometry, and
// integrated into a raymap::Mapper.
//
// So that it runs without ROS, main() makes the serialized messages itself (CdrWriter, the
// stand-in for rclcpp): a robot drives along +x at 2 m/s in a room (walls at x = -3.96 m and 7.96
// m, y = +-3.96 m, a floor at z = 0); its lidar, 1 m above base_link, sweeps 720 beams in two rings
// once per 0.1 s, each point stamped with its own time; odometry comes at 50 Hz. In 0.1 s the
// robot moves 0.2 m, two voxels: without deskewing the far wall would be smeared over them.
// Prints what it decoded and the state of voxels on and before the walls; exits 1 when the
// wall is not where it is. Finally shows the error a damaged message gives.
//   ros_messages
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include <raymap/mapper.hpp>
#include <raymap/ros_messages.hpp>

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kSpeed = 2.0;                  // m/s along +x
constexpr double kSweepPeriod = 0.1;            // s
constexpr double kMountHeight = 1.0;            // lidar above base_link, m
constexpr std::int64_t kStartSec = 1765000000;  // the first message's stamp, s since the epoch
constexpr int kBeams = 720;

// ---- The stand-in for rclcpp: XCDR1 little-endian, as ROS 2's rmw layers serialize. ----
class CdrWriter {
 public:
  CdrWriter() : bytes_{std::byte{0}, std::byte{1}, std::byte{0}, std::byte{0}} {}  // CDR_LE
  void u8(std::uint8_t v) { raw(&v, 1, 1); }
  void u32(std::uint32_t v) { raw(&v, 4, 4); }
  void i32(std::int32_t v) { raw(&v, 4, 4); }
  void f64(double v) { raw(&v, 8, 8); }
  void string(const std::string& s) {
    u32(static_cast<std::uint32_t>(s.size() + 1));
    raw(s.c_str(), s.size() + 1, 1);
  }
  void header(double stamp_s, const std::string& frame) {
    const double sec = std::floor(stamp_s);
    i32(static_cast<std::int32_t>(sec));
    u32(static_cast<std::uint32_t>(std::lround((stamp_s - sec) * 1e9)));
    string(frame);
  }
  void blob(const std::vector<std::byte>& data) {
    u32(static_cast<std::uint32_t>(data.size()));
    raw(data.data(), data.size(), 1);
  }
  const std::vector<std::byte>& bytes() const { return bytes_; }

 private:
  // Alignment counts from the end of the 4-byte encapsulation header.
  void raw(const void* data, std::size_t size, std::size_t align) {
    while ((bytes_.size() - 4) % align != 0) {
      bytes_.push_back(std::byte{0});
    }
    const auto* p = static_cast<const std::byte*>(data);
    bytes_.insert(bytes_.end(), p, p + size);
  }
  std::vector<std::byte> bytes_;
};

/// base_link in odom at time t (seconds since the start).
Eigen::Vector3d basePosition(double t) { return {kSpeed * t, 0.0, 0.0}; }

std::vector<std::byte> odometryMessage(double t) {
  CdrWriter w;
  w.header(static_cast<double>(kStartSec) + t, "odom");
  w.string("base_link");
  const Eigen::Vector3d p = basePosition(t);
  for (double v : {p.x(), p.y(), p.z(), 0.0, 0.0, 0.0, 1.0}) {  // position, quaternion x y z w
    w.f64(v);
  }
  for (int i = 0; i < 36 + 6 + 36; ++i) {  // pose covariance, twist, twist covariance
    w.f64(i == 36 ? kSpeed : 0.0);
  }
  return w.bytes();
}

/// Distance from `origin` along the unit `direction` to the room's walls or floor.
double castRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) {
  double nearest = 30.0;
  const auto plane = [&](int axis, double at) {
    const double d = (at - origin[axis]) / direction[axis];
    if (std::isfinite(d) && d > 0.0) {
      nearest = std::min(nearest, d);
    }
  };
  plane(0, 7.96);
  plane(0, -3.96);
  plane(1, 3.96);
  plane(1, -3.96);
  plane(2, 0.0);
  return nearest;
}

/// One sweep starting at time t: x y z float32 in the lidar's frame, t uint32 nanoseconds after
/// the stamp (the Ouster driver's layout, cut down).
std::vector<std::byte> cloudMessage(double t) {
  std::vector<std::byte> data;
  for (int ring = 0; ring < 2; ++ring) {
    const double elevation = ring == 0 ? 0.0 : -15.0 * kPi / 180.0;
    for (int beam = 0; beam < kBeams; ++beam) {
      const double offset = kSweepPeriod * beam / kBeams;
      const double azimuth = 2.0 * kPi * beam / kBeams;
      const Eigen::Vector3d direction(std::cos(azimuth) * std::cos(elevation),
                                      std::sin(azimuth) * std::cos(elevation), std::sin(elevation));
      // The lidar is where the robot is at the point's own time, not at the sweep's stamp.
      const Eigen::Vector3d origin = basePosition(t + offset) + Eigen::Vector3d(0, 0, kMountHeight);
      const Eigen::Vector3d point = direction * castRay(origin, direction);
      const float xyz[3] = {static_cast<float>(point.x()), static_cast<float>(point.y()),
                            static_cast<float>(point.z())};
      const auto ns = static_cast<std::uint32_t>(std::lround(offset * 1e9));
      std::byte bytes[16];
      std::memcpy(bytes, xyz, 12);
      std::memcpy(bytes + 12, &ns, 4);
      data.insert(data.end(), bytes, bytes + 16);
    }
  }
  CdrWriter w;
  w.header(static_cast<double>(kStartSec) + t, "os_lidar");
  w.u32(2);       // height: rings
  w.u32(kBeams);  // width
  w.u32(4);       // fields
  const char* names[] = {"x", "y", "z", "t"};
  for (std::uint32_t i = 0; i < 4; ++i) {
    w.string(names[i]);
    w.u32(4 * i);         // offset
    w.u8(i < 3 ? 7 : 6);  // FLOAT32, UINT32
    w.u32(1);             // count
  }
  w.u8(0);             // is_bigendian
  w.u32(16);           // point_step
  w.u32(16 * kBeams);  // row_step
  w.blob(data);
  w.u8(1);  // is_dense
  return w.bytes();
}

// ---- The node: what its subscription callbacks do with the bytes. ----
struct Node {
  raymap::Mapper* mapper = nullptr;
  std::vector<raymap::TimedPose> lidar_poses;  // odometry composed with the mounting, increasing
  Eigen::Isometry3d lidar_on_base = Eigen::Isometry3d::Identity();
  std::uint64_t clouds = 0;
  std::uint64_t points = 0;

  bool onOdometry(std::span<const std::byte> cdr) {
    const raymap::Result<raymap::ros::StampedTransform> odom = raymap::ros::decodeOdometry(cdr);
    if (!odom) {
      std::fprintf(stderr, "ros_messages: /odom: %s\n", odom.error().message.c_str());
      return false;
    }
    lidar_poses.push_back(raymap::TimedPose{static_cast<double>(odom->stamp_ns) * 1e-9,
                                            odom->transform * lidar_on_base});
    return true;
  }

  bool onCloud(std::span<const std::byte> cdr) {
    const raymap::Result<raymap::ros::PointCloud> cloud = raymap::ros::decodePointCloud2(cdr);
    if (!cloud) {
      std::fprintf(stderr, "ros_messages: /points: %s\n", cloud.error().message.c_str());
      return false;
    }
    ++clouds;
    points += cloud->points.size();
    // Each point's time_s is absolute, the odometry stamps' time base: the table deskews.
    if (auto ok = mapper->integrate(cloud->points, lidar_poses); !ok) {
      std::fprintf(stderr, "ros_messages: %s\n", ok.error().message.c_str());
      return false;
    }
    return true;
  }
};

}  // namespace

int main(int argc, char** /*argv*/) {
  if (argc != 1) {
    std::fprintf(stderr, "usage: ros_messages\n");
    return 2;
  }
  raymap::MapperConfig config;
  config.map.resolution = 0.1;
  config.map.max_memory_bytes = std::uint64_t{256} << 20;
  auto mapper = raymap::Mapper::create(config);
  if (!mapper) {
    std::fprintf(stderr, "ros_messages: %s\n", mapper.error().message.c_str());
    return 1;
  }
  Node node;
  node.mapper = &*mapper;
  node.lidar_on_base.translation() = Eigen::Vector3d(0, 0, kMountHeight);  // from /tf_static
  // Odometry first (a node keeps a short history), then ten sweeps.
  for (int i = 0; i <= 55; ++i) {
    if (!node.onOdometry(odometryMessage(0.02 * i))) {
      return 1;
    }
  }
  for (int sweep = 0; sweep < 10; ++sweep) {
    if (!node.onCloud(cloudMessage(kSweepPeriod * sweep))) {
      return 1;
    }
  }
  if (auto ok = mapper->flush(); !ok) {
    std::fprintf(stderr, "ros_messages: %s\n", ok.error().message.c_str());
    return 1;
  }
  const raymap::MapperCounters counters = mapper->counters();
  std::printf("clouds %llu\npoints %llu\npoints_no_pose %llu\n",
              static_cast<unsigned long long>(node.clouds),
              static_cast<unsigned long long>(node.points),
              static_cast<unsigned long long>(counters.points_no_pose));
  // The far wall's face (x = 7.96 m) ahead of the lidar; just before it, where the last beams of
  // each sweep (azimuth -0.5 degrees, 0.1 s after the stamp) would end without deskewing; the
  // room; the side wall.
  const char* names[] = {"unobserved", "free", "occupied"};
  struct Probe {
    Eigen::Vector3d at;
    raymap::VoxelState expected;
  };
  bool as_expected = true;
  for (const Probe& probe : {Probe{{7.95, 0.05, 1.05}, raymap::VoxelState::kOccupied},
                             Probe{{7.75, -0.05, 1.05}, raymap::VoxelState::kFree},
                             Probe{{4.05, 0.05, 1.05}, raymap::VoxelState::kFree},
                             Probe{{1.05, 3.95, 1.05}, raymap::VoxelState::kOccupied}}) {
    const raymap::VoxelState state = mapper->occupancy(probe.at);
    std::printf("voxel at (%.2f, %.2f, %.2f): %s\n", probe.at.x(), probe.at.y(), probe.at.z(),
                names[static_cast<int>(state)]);
    as_expected = as_expected && state == probe.expected;
  }
  // A message cut short (a broken recording) is an error naming the type, never a crash.
  std::vector<std::byte> damaged = cloudMessage(0.0);
  damaged.resize(damaged.size() / 2);
  const auto refused = raymap::ros::decodePointCloud2(damaged);
  std::printf("damaged cloud: %s\n", refused ? "decoded?!" : refused.error().message.c_str());
  std::printf("walls %s\n", as_expected ? "where they are" : "NOT where they are");
  return as_expected && !refused ? 0 : 1;
}
