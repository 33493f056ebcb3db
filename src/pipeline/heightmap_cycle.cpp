// SPDX-License-Identifier: BSD-3-Clause
// HeightmapCycle: the locked part of the periodic task.
#include "src/pipeline/heightmap_cycle.hpp"

#include <mutex>

#include "platform/clock.hpp"

namespace raymap::pipeline {

const char* toString(CycleError error) noexcept {
  switch (error) {
    case CycleError::kNoPose:
      return "no pose yet";
    case CycleError::kSynchronise:
      return "device synchronise failed";
    case CycleError::kPlan:
      return "height-map request does not fit the map";
    case CycleError::kGenerate:
      return "height-map generation failed";
  }
  return "?";
}

HeightmapCycle::HeightmapCycle(VoxelMap& map, Backend& backend, platform::PiMutex& map_mutex,
                               heightmap::HeightmapGenerator& generator,
                               heightmap::HeightmapOptions options, double base_height_m,
                               const LatestPosition& latest, ArrivalQueue& integrated,
                               PipelineStats& stats)
    : map_(map),
      backend_(backend),
      map_mutex_(map_mutex),
      generator_(generator),
      options_(options),
      base_height_m_(base_height_m),
      latest_(latest),
      integrated_(integrated),
      stats_(stats) {
  // Every box of this size: cycles allocate nothing as the robot meets new regions (the walking
  // camera climbing the stairs did, twice in 4 s).
  const std::size_t regions = heightmap::maxPlanRegions(map_, options_.size);
  heightmap::reservePlan(plan_, regions);
  generator_.reserveHostScratch(map_, regions);
}

Expected<void, CycleError> HeightmapCycle::generate() noexcept {
  std::int64_t stamp = 0;
  Vec3d robot;
  if (!latest_.load(&stamp, &robot)) {
    return Unexpected(CycleError::kNoPose);
  }
  const std::int64_t started = platform::monotonicNowNs();
  std::lock_guard<platform::PiMutex> lock(map_mutex_);
  const std::int64_t locked = platform::monotonicNowNs();
  stats_.map_lock_wait_us.record(static_cast<std::uint64_t>((locked - started) / 1000));
  // Regions downloaded during the cycle: by synchronise() for a generator that reads the host
  // store, else only evictions (cache mode) when the generator brings regions onto the device.
  const std::uint64_t downloaded = backend_.stats().region_bytes_from_device;
  if (generator_.readsHostStore() && !backend_.synchronise()) {
    return Unexpected(CycleError::kSynchronise);
  }
  const std::uint64_t copied = generator_.bytesCopied();
  const std::uint64_t map_copied = generator_.mapBytesCopied();
  map_.setWindowCentre(robot);
  options_.centre = {robot.x, robot.y, robot.z - base_height_m_};
  if (!heightmap::planHeightmap(map_, options_, plan_)) {
    return Unexpected(CycleError::kPlan);
  }
  if (!generator_.generate(map_, plan_, map_out_)) {
    return Unexpected(CycleError::kGenerate);
  }
  contained_ = integrated_.read_available();
  data_stamp_ns_ = stats_.newest_scan_stamp_ns.load(std::memory_order_relaxed);
  stats_.heightmap_copy_bytes.record(generator_.mapBytesCopied() - map_copied);
  stats_.heightmap_transfer_bytes.record(generator_.bytesCopied() - copied);
  stats_.sync_copy_bytes.record(backend_.stats().region_bytes_from_device - downloaded);
  const std::int64_t done = platform::monotonicNowNs();
  stats_.generate_us.record(static_cast<std::uint64_t>((done - started) / 1000));
  stats_.heightmap_lock_hold_us.record(static_cast<std::uint64_t>((done - locked) / 1000));
  return {};
}

void HeightmapCycle::recordPublished(std::int64_t now_ns) noexcept {
  std::int64_t arrival = 0;
  for (; contained_ > 0 && integrated_.pop(arrival); --contained_) {
    stats_.latency_us.record(static_cast<std::uint64_t>((now_ns - arrival) / 1000));
  }
  contained_ = 0;
}

}  // namespace raymap::pipeline
