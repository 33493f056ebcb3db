// SPDX-License-Identifier: BSD-3-Clause
// The scene-file reader: yaml-cpp parses, a small checked reader turns mappings into the scene
// and its simulation. The first problem found becomes the error; yaml-cpp's exceptions stay here.
#include "src/sim/scene_file.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <numbers>
#include <optional>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "platform/errno_text.hpp"
#include "src/config/yaml_reader.hpp"

namespace raymap::sim {
namespace {

using config::child;
using config::Context;
using config::Fields;
using config::formatNumber;
using config::item;
using config::toInteger;
using config::toNumber;
using config::toNumbers;

// ---- objects ----

const std::vector<std::string> kDirections = {"+x", "-x", "+y", "-y"};

constexpr RampAxis kAxisOfDirection[] = {RampAxis::kPlusX, RampAxis::kMinusX, RampAxis::kPlusY,
                                         RampAxis::kMinusY};

/// A box's max must exceed its min on every axis.
void checkOrdered(Fields& f, Vec3d min, Vec3d max) {
  f.check(max.x > min.x && max.y > min.y && max.z > min.z, "max", "must exceed min on every axis");
}

void readBox(Fields& f, Scene& scene) {
  const Vec3d min = f.vec3("min");
  const Vec3d max = f.vec3("max");
  checkOrdered(f, min, max);
  scene.boxes.push_back({min, max});
}

/// A wall along x or y: the box around the segment from -> to, `thickness` across it, extended
/// by half the thickness at both ends (so walls meeting at a corner close it).
void readWall(Fields& f, Scene& scene, double base_default) {
  const auto from = f.vec2("from");
  const auto to = f.vec2("to");
  const double height = f.positive("height");
  const double thickness = f.positive("thickness");
  const double base = f.number("base", base_default);
  const bool along_x = from[1] == to[1] && from[0] != to[0];
  const bool along_y = from[0] == to[0] && from[1] != to[1];
  f.check(along_x || along_y, "to",
          "a wall runs along x or y: from and to must differ in exactly one coordinate");
  const double h = thickness / 2.0;
  Box box{{std::min(from[0], to[0]) - h, std::min(from[1], to[1]) - h, base},
          {std::max(from[0], to[0]) + h, std::max(from[1], to[1]) + h, base + height}};
  scene.boxes.push_back(box);
}

void readRamp(Fields& f, Scene& scene) {
  const Vec3d min = f.vec3("min");
  const Vec3d max = f.vec3("max");
  checkOrdered(f, min, max);
  const RampAxis axis = kAxisOfDirection[f.choice("rises", kDirections)];
  scene.ramps.push_back({min, max, axis});
}

/// Steps k = 1..steps: solid boxes from the floor (start.z) up to start.z + k rise, each `run`
/// deep along `direction` and `width` wide, centred on start across it.
void readStairs(Fields& f, Scene& scene) {
  const Vec3d start = f.vec3("start");
  const std::size_t direction = f.choice("direction", kDirections);
  const int steps = f.integer<int>("steps", 1, 1000);
  const double rise = f.positive("rise");
  const double run = f.positive("run");
  const double width = f.positive("width");
  const int along = direction < 2 ? 0 : 1;  // x or y
  const int across = 1 - along;
  const double sign = direction % 2 == 0 ? 1.0 : -1.0;
  for (int k = 1; k <= steps; ++k) {
    const double near = start[along] + sign * (k - 1) * run;
    const double far = start[along] + sign * k * run;
    Box step{start, start};
    step.min[along] = std::min(near, far);
    step.max[along] = std::max(near, far);
    step.min[across] = start[across] - width / 2.0;
    step.max[across] = start[across] + width / 2.0;
    step.max.z = start.z + k * rise;
    scene.boxes.push_back(step);
  }
}

/// A top of `size` whose upper face is at base + height, on four square legs in its corners.
void readTable(Fields& f, Scene& scene, double base_default) {
  const auto centre = f.vec2("centre");
  const auto size = f.vec2("size");
  const double height = f.positive("height");
  const double top = f.positive("top_thickness");
  const double leg = f.positive("leg_size");
  const double base = f.number("base", base_default);
  f.check(size[0] > 0.0 && size[1] > 0.0, "size", "must be > 0 in x and y");
  f.check(top < height, "top_thickness", "must be less than the height");
  f.check(2.0 * leg <= std::min(size[0], size[1]), "leg_size",
          "two legs must fit across the top (2 leg_size <= size)");
  const Vec3d lo{centre[0] - size[0] / 2.0, centre[1] - size[1] / 2.0, base};
  const Vec3d hi{centre[0] + size[0] / 2.0, centre[1] + size[1] / 2.0, base + height};
  scene.boxes.push_back({{lo.x, lo.y, hi.z - top}, hi});
  for (const double x : {lo.x, hi.x - leg}) {
    for (const double y : {lo.y, hi.y - leg}) {
      scene.boxes.push_back({{x, y, base}, {x + leg, y + leg, hi.z - top}});
    }
  }
}

void readPole(Fields& f, Scene& scene, double base_default) {
  const auto at = f.vec2("at");
  const double radius = f.positive("radius");
  const double height = f.positive("height");
  const double base = f.number("base", base_default);
  scene.poles.push_back({at[0], at[1], radius, base, base + height});
}

void readDitch(Fields& f, Scene& scene, std::vector<std::size_t>& ditch_objects,
               std::size_t index) {
  const auto min = f.vec2("min");
  const auto max = f.vec2("max");
  const double depth = f.positive("depth");
  f.check(max[0] > min[0] && max[1] > min[1], "max", "must exceed min in x and y");
  f.check(scene.has_ground, "type", "a ditch is a hole in the ground, and the scene has none");
  const Ditch ditch{min[0], min[1], max[0], max[1], depth};
  for (std::size_t i = 0; i < scene.ditches.size(); ++i) {
    const Ditch& other = scene.ditches[i];
    const bool overlap = ditch.x_min < other.x_max && other.x_min < ditch.x_max &&
                         ditch.y_min < other.y_max && other.y_min < ditch.y_max;
    f.check(!overlap, "min",
            "overlaps the ditch objects[" + std::to_string(ditch_objects[i]) +
                "] (ditches must not overlap)");
  }
  scene.ditches.push_back(ditch);
  ditch_objects.push_back(index);
}

void readObjects(Context& ctx, const YAML::Node& node, Scene& scene) {
  if (!node.IsSequence()) {
    ctx.fail(node, "objects", "expected a list of objects (lines starting with '- ')");
    return;
  }
  const double base = scene.has_ground ? scene.ground_height : 0.0;
  std::vector<std::size_t> ditch_objects;
  for (std::size_t i = 0; i < node.size() && !ctx.failed(); ++i) {
    Fields f(ctx, node[i], item("objects", i));
    if (ctx.failed()) {
      return;
    }
    switch (f.choice("type", {"box", "wall", "ramp", "stairs", "table", "pole", "ditch"})) {
      case 0:
        readBox(f, scene);
        break;
      case 1:
        readWall(f, scene, base);
        break;
      case 2:
        readRamp(f, scene);
        break;
      case 3:
        readStairs(f, scene);
        break;
      case 4:
        readTable(f, scene, base);
        break;
      case 5:
        readPole(f, scene, base);
        break;
      default:
        readDitch(f, scene, ditch_objects, i);
        break;
    }
    f.finish();
  }
}

// ---- ground, lidar, depth cameras, trajectory ----

void readGround(Context& ctx, const YAML::Node& node, Scene& scene) {
  if (!node.IsDefined()) {
    return;  // ground at z = 0
  }
  if (node.IsScalar() && node.Scalar() == "none") {
    scene.has_ground = false;
    return;
  }
  if (node.IsMap()) {
    Fields f(ctx, node, "ground");
    scene.ground_height = f.number("height", 0.0);
    f.finish();
    return;
  }
  if (!node.IsScalar() || !YAML::convert<double>::decode(node, scene.ground_height) ||
      !std::isfinite(scene.ground_height)) {
    ctx.fail(node, "ground", "expected a height, {height: H} or none");
  }
}

void readLidar(Context& ctx, const YAML::Node& node, LidarModel& lidar) {
  if (!node.IsDefined()) {
    return;  // the defaults
  }
  Fields f(ctx, node, "lidar");
  lidar.beams = f.integer<int>("beams", lidar.beams, 1, 4096);
  lidar.elevation_min_deg = f.number("elevation_min_deg", lidar.elevation_min_deg);
  lidar.elevation_max_deg = f.number("elevation_max_deg", lidar.elevation_max_deg);
  lidar.columns = f.integer<int>("columns", lidar.columns, 1, 1 << 20);
  const double rate_hz = f.positive("rate_hz", 1.0 / lidar.scan_period_s);
  lidar.max_range_m = f.positive("max_range", lidar.max_range_m);
  lidar.min_range_m = f.positive("min_range", lidar.min_range_m, true);
  lidar.range_noise_m = f.positive("range_noise", lidar.range_noise_m, true);
  lidar.dropout = f.number("dropout", lidar.dropout);
  f.check(lidar.elevation_min_deg >= -90.0 && lidar.elevation_min_deg <= 90.0, "elevation_min_deg",
          "must be from -90 to 90");
  f.check(lidar.elevation_max_deg >= lidar.elevation_min_deg && lidar.elevation_max_deg <= 90.0,
          "elevation_max_deg", "must be from elevation_min_deg to 90");
  f.check(lidar.min_range_m < lidar.max_range_m, "min_range", "must be less than max_range");
  f.check(lidar.dropout >= 0.0 && lidar.dropout <= 1.0, "dropout",
          "must be a probability from 0 to 1 (got " + formatNumber(lidar.dropout) + ")");
  lidar.scan_period_s = rate_hz > 0.0 ? 1.0 / rate_hz : lidar.scan_period_s;
  f.finish();
}

/// `mount: {position: [x, y, z], rpy_deg: [roll, pitch, yaw]}` of a camera, body frame.
void readMount(Context& ctx, const YAML::Node& node, const std::string& path, CameraMount& mount) {
  Fields f(ctx, node, path);
  f.knownKeys({"position", "rpy_deg"});
  mount.position_m = f.vec3("position");
  if (f.has("rpy_deg")) {
    const auto rpy = toNumbers(ctx, f.get("rpy_deg"), f.path("rpy_deg"), 3, "[roll, pitch, yaw]");
    mount.roll_deg = rpy[0];
    mount.pitch_deg = rpy[1];
    mount.yaw_deg = rpy[2];
  }
  f.finish();
}

const std::vector<std::string> kEncodings = {"16UC1", "32FC1"};

void readDepthCamera(Context& ctx, Fields& f, DepthCameraModel& camera) {
  const YAML::Node name = f.required("name");
  if (!ctx.failed() && (!name.IsScalar() || name.Scalar().empty())) {
    ctx.fail(name, f.path("name"), "expected a non-empty text");
  }
  camera.name = ctx.failed() ? std::string() : name.Scalar();
  camera.width = f.integer<std::uint32_t>("width", 1, 65535);
  camera.height = f.integer<std::uint32_t>("height", 1, 65535);
  camera.hfov_deg = f.number("hfov_deg");
  f.check(camera.hfov_deg > 0.0 && camera.hfov_deg < 180.0, "hfov_deg",
          "must be between 0 and 180 degrees (got " + formatNumber(camera.hfov_deg) + ")");
  if (f.has("cx")) {
    camera.cx = f.number("cx");
  }
  if (f.has("cy")) {
    camera.cy = f.number("cy");
  }
  if (f.has("distortion")) {
    const auto d =
        toNumbers(ctx, f.get("distortion"), f.path("distortion"), 5, "[k1, k2, p1, p2, k3]");
    std::copy(d.begin(), d.end(), camera.distortion.begin());
  }
  if (!ctx.failed()) {
    readMount(ctx, f.required("mount"), f.path("mount"), camera.mount);
  }
  camera.rate_hz = f.positive("rate_hz", camera.rate_hz);
  camera.max_range_m = f.positive("max_range", camera.max_range_m);
  camera.min_range_m = f.positive("min_range", camera.min_range_m, true);
  camera.depth_noise_m = f.positive("noise", camera.depth_noise_m, true);
  if (f.has("encoding")) {
    camera.encoding =
        f.choice("encoding", kEncodings) == 0 ? DepthEncoding::k16UC1 : DepthEncoding::k32FC1;
  }
  camera.downsample = f.integer<std::uint32_t>("downsample", 1, 1, 64);
  f.check(camera.min_range_m < camera.max_range_m, "min_range", "must be less than max_range");
  if (!ctx.failed()) {
    // The lens: what the ray table will need (finite, and no fold over the image).
    if (auto valid = intrinsics(camera).validate(); !valid) {
      ctx.fail(f.has("distortion") ? f.get("distortion") : f.get("hfov_deg"),
               f.path(f.has("distortion") ? "distortion" : "hfov_deg"), valid.error().message);
    }
  }
}

/// `depth_cameras:` a list of cameras on the robot body, each with a unique name.
void readDepthCameras(Context& ctx, const YAML::Node& node, std::vector<DepthCameraModel>& out) {
  if (!node.IsSequence() || node.size() == 0) {
    ctx.fail(node, "depth_cameras",
             "expected a non-empty list of cameras (lines starting with '- ')");
    return;
  }
  for (std::size_t i = 0; i < node.size() && !ctx.failed(); ++i) {
    Fields f(ctx, node[i], item("depth_cameras", i));
    f.knownKeys({"name", "width", "height", "hfov_deg", "cx", "cy", "distortion", "mount",
                 "rate_hz", "max_range", "min_range", "noise", "encoding", "downsample"});
    if (ctx.failed()) {
      return;
    }
    DepthCameraModel camera;
    readDepthCamera(ctx, f, camera);
    for (const DepthCameraModel& other : out) {
      f.check(other.name != camera.name, "name",
              "another camera is called '" + camera.name + "' (names must be unique)");
    }
    f.finish();
    out.push_back(std::move(camera));
  }
}

/// `waypoints` + `speed`, or `poses` ([t, x, y, z, yaw_deg] each).
void readTrajectory(Context& ctx, const YAML::Node& node, SensorPath& path) {
  if (!node.IsDefined()) {
    ctx.fail(node, "trajectory", "required key missing");
    return;
  }
  Fields f(ctx, node, "trajectory");
  f.knownKeys({"waypoints", "speed", "poses"});
  const bool has_waypoints = f.has("waypoints");
  const bool has_poses = f.has("poses");
  if (has_waypoints == has_poses) {
    ctx.fail(node, "trajectory", "give either waypoints (with speed) or poses");
    return;
  }
  const std::string key = has_waypoints ? "waypoints" : "poses";
  const YAML::Node list = f.get(key);
  if (!list.IsSequence() || list.size() == 0) {
    ctx.fail(list, f.path(key), "expected a non-empty list");
    return;
  }
  Result<SensorPath> made = SensorPath{};
  if (has_waypoints) {
    const double speed = f.positive("speed");
    std::vector<Vec3d> waypoints;
    for (std::size_t i = 0; i < list.size(); ++i) {
      const auto v = toNumbers(ctx, list[i], item(f.path(key), i), 3, "[x, y, z]");
      waypoints.push_back({v[0], v[1], v[2]});
    }
    f.finish();
    if (ctx.failed()) {
      return;
    }
    made = SensorPath::fromWaypoints(waypoints, speed);
  } else {
    f.check(!f.has("speed"), "speed", "applies to waypoints only");
    std::vector<SensorPose> poses;
    for (std::size_t i = 0; i < list.size(); ++i) {
      const auto v = toNumbers(ctx, list[i], item(f.path(key), i), 5, "[t, x, y, z, yaw_deg]");
      poses.push_back({v[0], {v[1], v[2], v[3]}, v[4] * std::numbers::pi / 180.0});
    }
    f.finish();
    if (ctx.failed()) {
      return;
    }
    made = SensorPath::fromPoses(std::move(poses));
  }
  if (!made) {
    ctx.fail(list, f.path(key), made.error().message);
    return;
  }
  path = std::move(*made);
}

Result<SceneFile> parse(const YAML::Node& root, const std::string& name) {
  Context ctx(name);
  Fields f(ctx, root, "");
  f.knownKeys({"name", "ground", "objects", "lidar", "depth_cameras", "trajectory", "seed", "scans",
               "duration"});
  if (ctx.failed()) {
    return Unexpected(ctx.error());
  }
  SceneFile file;
  const YAML::Node scene_name = f.get("name");
  file.scene.name = std::filesystem::path(name).stem().string();
  if (scene_name.IsDefined()) {
    if (!scene_name.IsScalar()) {
      ctx.fail(scene_name, "name", "expected a text");
    } else {
      file.scene.name = scene_name.Scalar();
    }
  }
  readGround(ctx, f.get("ground"), file.scene);
  if (const YAML::Node objects = f.get("objects"); objects.IsDefined() && !ctx.failed()) {
    readObjects(ctx, objects, file.scene);
  }
  SimulationConfig& sim = file.simulation;
  if (const YAML::Node cameras = f.get("depth_cameras"); cameras.IsDefined() && !ctx.failed()) {
    readDepthCameras(ctx, cameras, file.depth_cameras);
  }
  file.has_lidar = f.has("lidar") || file.depth_cameras.empty();
  if (!ctx.failed() && file.has_lidar) {
    readLidar(ctx, f.get("lidar"), sim.lidar);
  }
  if (!ctx.failed()) {
    readTrajectory(ctx, f.get("trajectory"), sim.path);
  }
  sim.seed = f.integer<std::uint64_t>("seed", 1, 0, std::numeric_limits<std::uint64_t>::max());
  const bool has_scans = f.has("scans");
  const bool has_duration = f.has("duration");
  f.check(!(has_scans && has_duration), "duration", "give scans or duration, not both");
  f.check(!has_scans || file.has_lidar, "scans",
          "counts lidar revolutions, and the scene has no lidar: give duration");
  const double rate_hz = 1.0 / sim.lidar.scan_period_s;
  const double seconds =
      has_duration ? f.positive("duration") : sim.path.endTime() - sim.path.startTime();
  if (!file.has_lidar) {
    sim.scans = 0;
    file.duration_s = seconds;
    for (const DepthCameraModel& camera : file.depth_cameras) {
      if (frameCount(seconds, camera.rate_hz) < 1 && !ctx.failed()) {
        ctx.fail(has_duration ? f.get("duration") : f.get("trajectory"),
                 has_duration ? "duration" : "trajectory",
                 "lasts " + formatNumber(seconds) + " s, less than one frame of camera '" +
                     camera.name + "' (" + formatNumber(1.0 / camera.rate_hz) +
                     " s); give a longer duration");
      }
    }
  } else if (has_scans) {
    sim.scans = f.integer<int>("scans", 1, 100000);
    file.duration_s = sim.scans / rate_hz;
  } else {
    // A hair of slack so that 2 s at 10 Hz is 20 scans despite rounding.
    const double scans = std::floor(seconds * rate_hz + 1e-6);
    if (scans < 1.0 && !ctx.failed()) {
      ctx.fail(has_duration ? f.get("duration") : f.get("trajectory"),
               has_duration ? "duration" : "trajectory",
               "lasts " + formatNumber(seconds) + " s, less than one scan (" +
                   formatNumber(1.0 / rate_hz) + " s); give scans or a longer duration");
    }
    sim.scans = static_cast<int>(std::min(scans, 100000.0));
    file.duration_s = has_duration ? seconds : sim.scans / rate_hz;
  }
  f.finish();
  if (ctx.failed()) {
    return Unexpected(ctx.error());
  }
  return file;
}

}  // namespace

Result<SceneFile> parseSceneFile(const std::string& text, const std::string& name) {
  try {
    return parse(YAML::Load(text), name);
  } catch (const YAML::Exception& e) {
    std::string where;
    if (e.mark.line >= 0) {
      where = "line " + std::to_string(e.mark.line + 1) + ", column " +
              std::to_string(e.mark.column + 1) + ": ";
    }
    return fail(ErrorCode::kFormat, name + ": " + where + "not valid YAML: " + e.msg);
  } catch (const std::exception& e) {
    return fail(ErrorCode::kFormat, name + ": cannot read the scene: " + e.what());
  }
}

Result<SceneFile> loadSceneFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    return fail(ErrorCode::kIo, "cannot open '" + path + "': " + platform::errnoText(errno));
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) {
    return fail(ErrorCode::kIo, "cannot read '" + path + "'");
  }
  return parseSceneFile(text.str(), path);
}

}  // namespace raymap::sim
