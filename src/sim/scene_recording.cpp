// SPDX-License-Identifier: BSD-3-Clause
#include "src/sim/scene_recording.hpp"

#include <algorithm>

#include "src/sim/depth_camera.hpp"
#include "src/sim/depth_frame_rays.hpp"
#include "src/sim/lidar.hpp"

namespace raymap::sim {
namespace {

/// One sweep of the recording: a lidar revolution or a camera frame, at its start time.
struct Sweep {
  double time_s = 0.0;
  int camera = -1;  ///< -1: the lidar's scan `index`; else depth_cameras[camera]'s frame `index`
  int index = 0;
};

}  // namespace

Expected<void, Error> recordScene(const SceneFile& file, const RecordedSensors& sensors,
                                  double duration_s, std::vector<Ray>& rays,
                                  std::uint64_t& depth_frames) {
  const SimulationConfig& simulation = file.simulation;
  const double start = simulation.path.startTime();
  std::vector<Sweep> sweeps;
  std::vector<Ray> lidar;
  if (sensors.lidar) {
    lidar = simulateScans(file.scene, simulation);
    for (int s = 0; s < simulation.scans; ++s) {
      sweeps.push_back({start + s * simulation.lidar.scan_period_s, -1, s});
    }
  }
  std::vector<DepthCamera> cameras;
  if (sensors.depth) {
    for (std::size_t c = 0; c < file.depth_cameras.size(); ++c) {
      auto camera = DepthCamera::create(file.depth_cameras[c]);
      if (!camera) {
        return Unexpected(camera.error());
      }
      const double rate = camera->model().rate_hz;
      for (int i = 0; i < frameCount(duration_s, rate); ++i) {
        sweeps.push_back({start + i / rate, static_cast<int>(c), i});
      }
      cameras.push_back(std::move(*camera));
    }
  }
  std::stable_sort(sweeps.begin(), sweeps.end(),
                   [](const Sweep& a, const Sweep& b) { return a.time_s < b.time_s; });

  rays.reserve(lidar.size());
  std::size_t next_lidar = 0;  // lidar rays come scan by scan
  std::vector<float> depth;
  DepthRayScratch scratch;
  for (std::size_t i = 0; i < sweeps.size(); ++i) {
    const Sweep& sweep = sweeps[i];
    if (sweep.camera < 0) {
      for (; next_lidar < lidar.size() &&
             lidar[next_lidar].scan == static_cast<std::uint64_t>(sweep.index);
           ++next_lidar) {
        rays.push_back(lidar[next_lidar]);
        rays.back().scan = i;
      }
      continue;
    }
    const DepthCamera& camera = cameras[static_cast<std::size_t>(sweep.camera)];
    depth.resize(camera.pixels());
    const CameraPose pose = cameraPose(camera.model().mount, simulation.path.at(sweep.time_s));
    camera.render(file.scene, pose,
                  frameSeed(simulation.seed, static_cast<std::uint32_t>(sweep.camera),
                            static_cast<std::uint32_t>(sweep.index)),
                  depth);
    if (auto ok = appendDepthFrameRays(camera, pose, sweep.time_s, i, depth, scratch, rays); !ok) {
      return ok;
    }
    ++depth_frames;
  }
  return {};
}

}  // namespace raymap::sim
