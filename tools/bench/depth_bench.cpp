// SPDX-License-Identifier: BSD-3-Clause
// Depth-camera throughput (issue 26): a synthetic 640 × 480 depth image (a floor plus a box, seen
// from 0.6 m up, looking down and forward) decoded and back-projected, and integrated on the CPU
// backend with one thread (or the backend named) through raymapd's path (ScanPoint -> world Ray by
// PointDeskewer at a fixed pose -> RayPreparer/RayBatcher -> backend) into a 0.1 m occupancy map
// at 2 m range.
// And the simulator's render time of a 640 × 480 frame of a stairs-like scene (what the depth
// playback of raymap-load and the tests costs per frame; the unit tests only check the image).
// Prints JSON: medians of the repetitions.
// Run: build/release/tools/raymap-depth-bench [repetitions (default 7)] [--backend cpu|opencl|cuda]
//        [--device-planning host|device]
// A device backend walks rays in reverse, as the tools do; its section is "integrate_<backend>".
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "src/core/pinhole_camera.hpp"
#include "src/device/backend_choice.hpp"
#include "src/map/ray_batcher.hpp"
#include "src/map/ray_preparer.hpp"
#include "src/map/voxel_map.hpp"
#include "src/msgs/depth_image.hpp"
#include "src/msgs/depth_image_writer.hpp"
#include "src/pipeline/deskew.hpp"
#include "src/pipeline/pose_history.hpp"
#include "src/sim/depth_camera.hpp"
#include "tools/raymap/json_output.hpp"

namespace raymap {
namespace {

using Clock = std::chrono::steady_clock;

constexpr std::uint32_t kWidth = 640;
constexpr std::uint32_t kHeight = 480;
constexpr double kFocalPx = 385.0;
constexpr double kHeightM = 0.6;             // camera above the floor
constexpr double kPitchDeg = 35.0;           // optical axis below the horizon
constexpr float kMaxRangeM = 2.0f;           // the range limit
constexpr double kResolutionM = 0.1;         // the voxel size
constexpr std::uint32_t kBatchRays = 16384;  // raymapd's default queues.batch_rays
constexpr std::int64_t kStampNs = 1'700'000'000'000'000'000;
constexpr int kDecodeFrames = 50;     // frames per timed decode repetition
constexpr int kIntegrateFrames = 10;  // frames per timed integration repetition
constexpr double kNoHit = std::numeric_limits<double>::infinity();

/// The camera on the robot body: optical frame (z forward, x right, y down) -> body (x forward,
/// y left, z up), pitched down, 0.6 m above the floor (the body frame is the world: fixed pose).
io::Pose cameraInBody() {
  const Eigen::Matrix3d level = (Eigen::Matrix3d() << 0, 0, 1, -1, 0, 0, 0, -1, 0).finished();
  const Eigen::Matrix3d pitch =
      Eigen::AngleAxisd(kPitchDeg * std::numbers::pi / 180.0, Eigen::Vector3d::UnitY())
          .toRotationMatrix();
  io::Pose pose;
  pose.position = {0.0, 0.0, kHeightM};
  pose.orientation = Eigen::Quaterniond(pitch * level);
  return pose;
}

/// Ray parameter of the first hit of the box [lo, hi] (slab method), or infinity.
double hitBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& lo,
              const Eigen::Vector3d& hi) {
  double t0 = 0.0;
  double t1 = kNoHit;
  for (int k = 0; k < 3; ++k) {
    const double a = (lo[k] - o[k]) / d[k];
    const double b = (hi[k] - o[k]) / d[k];
    t0 = std::max(t0, std::min(a, b));
    t1 = std::min(t1, std::max(a, b));
  }
  return t0 <= t1 ? t0 : kNoHit;
}

/// Depth (optical z, metres) of every pixel: the floor z = 0 and a 0.5 × 0.6 × 0.4 m box 1.2 m
/// ahead; rays that hit nothing (above the horizon) are NaN.
std::vector<float> renderDepth(const CameraIntrinsics& camera, const io::Pose& pose) {
  std::vector<float> depth;
  depth.reserve(std::size_t{kWidth} * kHeight);
  const Eigen::Vector3d lo(1.2, -0.3, 0.0);
  const Eigen::Vector3d hi(1.7, 0.3, 0.4);
  for (std::uint32_t v = 0; v < kHeight; ++v) {
    for (std::uint32_t u = 0; u < kWidth; ++u) {
      NormalisedPoint n;
      pixelToNormalised(camera, u, v, &n);
      // Parameter t along (x_n, y_n, 1) is the optical z.
      const Eigen::Vector3d d = pose.orientation * Eigen::Vector3d(n.x, n.y, 1.0);
      double t = d.z() < 0.0 ? -pose.position.z() / d.z() : kNoHit;
      t = std::min(t, hitBox(pose.position, d, lo, hi));
      depth.push_back(std::isfinite(t) ? static_cast<float>(t)
                                       : std::numeric_limits<float>::quiet_NaN());
    }
  }
  return depth;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

struct Frames {
  std::vector<std::byte> f32;
  std::vector<std::byte> u16;
};

[[noreturn]] void die(const std::string& what) {
  std::fprintf(stderr, "raymap-depth-bench: %s\n", what.c_str());
  std::exit(1);
}

cli::Json decodeRun(const char* encoding, const std::vector<std::byte>& bytes,
                    const PixelRayTable& rays, std::uint32_t downsample, int repetitions) {
  std::vector<msgs::ScanPoint> out(msgs::depthPointCapacity(kWidth, kHeight, downsample));
  msgs::DepthDecodeOptions options;
  options.downsample = downsample;
  options.max_range_m = kMaxRangeM;
  std::vector<double> ns;
  std::uint32_t points = 0;
  for (int r = 0; r < repetitions; ++r) {
    const auto start = Clock::now();
    for (int f = 0; f < kDecodeFrames; ++f) {
      const auto header = msgs::decodeDepthImage(bytes, rays, options, out);
      if (!header) {
        die(std::string("decode: ") + msgs::toString(header.error()));
      }
      points = header->points;
    }
    ns.push_back(secondsSince(start) * 1e9 / kDecodeFrames);
  }
  return {
      {"encoding", encoding},
      {"downsample", downsample},
      {"points", points},
      {"ns_per_frame", median(ns)},
      {"ns_per_pixel", median(ns) / (double{kWidth} * kHeight)},
  };
}

/// Seconds one frame spent in each stage.
struct FrameStages {
  double decode_s = 0.0;
  double convert_s = 0.0;
  double integrate_s = 0.0;
};

/// Medians over the repetitions of kIntegrateFrames frames each.
struct StageMedians {
  double frame_s = 0.0;
  double decode_ms = 0.0;
  double convert_ms = 0.0;
  double integrate_ms = 0.0;
};

/// Runs `frame` (returning its FrameStages) kIntegrateFrames times per repetition.
template <typename Frame>
StageMedians timeFrames(Frame& frame, int repetitions) {
  std::vector<double> frame_s;
  std::vector<double> decode_ms;
  std::vector<double> convert_ms;
  std::vector<double> integrate_ms;
  for (int r = 0; r < repetitions; ++r) {
    FrameStages sum;
    const auto start = Clock::now();
    for (int f = 0; f < kIntegrateFrames; ++f) {
      const FrameStages one = frame();
      sum.decode_s += one.decode_s;
      sum.convert_s += one.convert_s;
      sum.integrate_s += one.integrate_s;
    }
    frame_s.push_back(secondsSince(start) / kIntegrateFrames);
    decode_ms.push_back(sum.decode_s * 1e3 / kIntegrateFrames);
    convert_ms.push_back(sum.convert_s * 1e3 / kIntegrateFrames);
    integrate_ms.push_back(sum.integrate_s * 1e3 / kIntegrateFrames);
  }
  return {median(frame_s), median(decode_ms), median(convert_ms), median(integrate_ms)};
}

cli::Json integrateRun(const std::vector<std::byte>& bytes, const PixelRayTable& rays,
                       std::uint32_t downsample, Semantics semantics, int repetitions,
                       const backends::BackendChoice& choice) {
  MapConfig config;
  config.geometry.resolution = kResolutionM;
  config.semantics = semantics;
  auto map = VoxelMap::create(config);
  if (!map) {
    die(map.error().message);
  }
  auto created = backends::createBackend(*map, choice);
  if (!created) {
    die(created.error().message);
  }
  RayFilter filter;
  filter.max_range_m = kMaxRangeM;
  filter.reverse = choice.name != "cpu";  // devices walk from the sample back (fewer collisions)
  RayPreparer preparer(*map, filter);
  RayBatcher batcher(*map, *created->backend, kBatchRays);
  pipeline::PoseHistory history(16);
  const io::Pose identity;
  history.push(kStampNs - 1'000'000'000, identity);
  history.push(kStampNs + 1'000'000'000, identity);
  const io::Pose extrinsic = cameraInBody();
  pipeline::PointDeskewer deskewer;
  std::vector<msgs::ScanPoint> points(msgs::depthPointCapacity(kWidth, kHeight, downsample));
  std::vector<Ray> world(points.size());
  msgs::DepthDecodeOptions options;
  options.downsample = downsample;
  options.max_range_m = kMaxRangeM;

  std::uint64_t scan = 0;
  std::size_t rays_per_frame = 0;
  const auto frame = [&] {
    FrameStages stages;
    auto t0 = Clock::now();
    const auto header = msgs::decodeDepthImage(bytes, rays, options, points);
    if (!header) {
      die(std::string("decode: ") + msgs::toString(header.error()));
    }
    auto t1 = Clock::now();
    std::size_t n = 0;
    for (std::uint32_t i = 0; i < header->points; ++i) {
      n += deskewer.toRay(points[i], kStampNs, history, 0, extrinsic, scan, world[n]) ? 1U : 0U;
    }
    auto t2 = Clock::now();
    if (!batcher.add(preparer, std::span<const Ray>(world.data(), n)) || !batcher.flush()) {
      die("integration failed");
    }
    auto t3 = Clock::now();
    ++scan;
    stages.decode_s = std::chrono::duration<double>(t1 - t0).count();
    stages.convert_s = std::chrono::duration<double>(t2 - t1).count();
    stages.integrate_s = std::chrono::duration<double>(t3 - t2).count();
    rays_per_frame = n;
    return stages;
  };
  frame();  // untimed: the regions are created
  const StageMedians medians = timeFrames(frame, repetitions);
  return {
      {"encoding", "16UC1"},
      {"downsample", downsample},
      {"semantics", semantics == Semantics::kPerScan ? "scan" : "ray"},
      {"rays_per_frame", rays_per_frame},
      {"frames_per_s", 1.0 / medians.frame_s},
      {"rays_per_s", static_cast<double>(rays_per_frame) / medians.frame_s},
      {"ms_per_frame", medians.frame_s * 1e3},
      {"decode_ms", medians.decode_ms},
      {"to_world_ray_ms", medians.convert_ms},
      {"prepare_and_integrate_ms", medians.integrate_ms},
      {"rays_clipped_share",
       static_cast<double>(preparer.counters().rays_clipped) /
           static_cast<double>(std::max<std::uint64_t>(preparer.counters().rays_in, 1))},
  };
}

/// The simulator (sim::DepthCamera) rendering a 640 × 480 frame of six steps between two walls,
/// the camera on a body 0.55 m up, pitched 45° down: milliseconds per frame, median of the
/// repetitions of 5 frames each.
double simulatorRenderMs(int repetitions) {
  sim::Scene scene;
  for (int k = 1; k <= 6; ++k) {
    scene.boxes.push_back({{2.0 + 0.3 * (k - 1), -0.6, 0.0}, {2.0 + 0.3 * k, 0.6, 0.17 * k}});
  }
  scene.boxes.push_back({{3.8, -0.6, 0.0}, {5.0, 0.6, 1.02}});
  scene.boxes.push_back({{1.9, -0.85, 0.0}, {5.1, -0.65, 2.5}});
  scene.boxes.push_back({{1.9, 0.65, 0.0}, {5.1, 0.85, 2.5}});
  scene.boxes.push_back({{5.0, -0.85, 0.0}, {5.2, 0.85, 2.5}});
  sim::DepthCameraModel m;
  m.width = kWidth;
  m.height = kHeight;
  m.mount = {{0.3, 0.0, 0.0}, 0.0, 45.0, 0.0};
  m.depth_noise_m = 0.002;
  const auto camera = sim::DepthCamera::create(m);
  if (!camera) {
    die("depth camera: " + camera.error().message);
  }
  const sim::SensorPose body{0.0, {1.0, 0.0, 0.55}, 0.0};
  std::vector<float> depth(camera->pixels());
  constexpr int kFrames = 5;
  std::vector<double> ms;
  std::uint64_t seed = 0;
  for (int r = 0; r < repetitions; ++r) {
    const auto start = Clock::now();
    for (int f = 0; f < kFrames; ++f) {
      camera->render(scene, sim::cameraPose(m.mount, body), seed++, depth);
    }
    ms.push_back(secondsSince(start) * 1e3 / kFrames);
  }
  return median(ms);
}

}  // namespace
}  // namespace raymap

int main(int argc, char** argv) {
  using namespace raymap;
  int repetitions = 7;
  backends::BackendChoice choice;
  choice.threads = 1;
  constexpr const char* kUsage =
      "usage: raymap-depth-bench [repetitions] [--backend cpu|opencl|cuda] "
      "[--device-planning host|device]";
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--help" || arg == "-h") {
      std::printf("%s\n", kUsage);
      return 0;
    }
    if ((arg == "--backend" || arg == "--device-planning") && a + 1 < argc) {
      (arg == "--backend" ? choice.name : choice.device_planning) = argv[++a];
    } else if (!arg.empty() && arg[0] != '-') {
      repetitions = std::max(5, std::atoi(arg.c_str()));
    } else {
      die(kUsage);
    }
  }
  CameraIntrinsics camera;
  camera.width = kWidth;
  camera.height = kHeight;
  camera.fx = kFocalPx;
  camera.fy = kFocalPx;
  camera.cx = 319.5;
  camera.cy = 239.5;
  PixelRayTable rays;
  if (auto built = rays.build(camera); !built) {
    die(built.error().message);
  }
  const std::vector<float> depth = renderDepth(camera, cameraInBody());
  Frames frames;
  msgs::serializeDepthImage(kStampNs, "camera_depth_optical_frame", kWidth, kHeight,
                            msgs::DepthEncoding::k32FC1, false, depth, frames.f32);
  msgs::serializeDepthImage(kStampNs, "camera_depth_optical_frame", kWidth, kHeight,
                            msgs::DepthEncoding::k16UC1, false, depth, frames.u16);

  char image[128];
  std::snprintf(image, sizeof(image), "%ux%u, fx=fy=%.0f, %.1f m up, %.0f deg down, floor + box",
                kWidth, kHeight, kFocalPx, kHeightM, kPitchDeg);
  cli::Json decode = cli::Json::array();
  for (const std::uint32_t n : {1U, 2U, 6U}) {
    for (const bool mm : {false, true}) {
      decode.push_back(
          decodeRun(mm ? "16UC1" : "32FC1", mm ? frames.u16 : frames.f32, rays, n, repetitions));
    }
  }
  cli::Json integrate = cli::Json::array();
  for (const std::uint32_t n : {1U, 2U, 6U}) {
    for (const Semantics s : {Semantics::kPerRay, Semantics::kPerScan}) {
      integrate.push_back(integrateRun(frames.u16, rays, n, s, repetitions, choice));
    }
  }
  const std::string integrate_key =
      "integrate_" + (choice.name == "cpu"
                          ? std::string("cpu_1_thread")
                          : choice.name + "_" + choice.device_planning + "_planning");
  const cli::Json result = {
      {"image", image},
      {"repetitions", repetitions},
      {"decode", decode},
      {integrate_key, integrate},
      {"simulator_render_640x480_ms", simulatorRenderMs(repetitions)},
  };
  std::printf("%s\n", cli::dumpJson(result).c_str());
  return 0;
}
