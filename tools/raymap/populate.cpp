// SPDX-License-Identifier: BSD-3-Clause
// `raymap populate`'s use of the mapping job (see populate.hpp).
#include "tools/raymap/populate.hpp"

#include "tools/raymap/option_names.hpp"
#include "tools/raymap/progress.hpp"

namespace raymap::cli {
namespace {

/// Draws the job's progress on `bar`, with the tiers' pool once they move regions.
mapper::ProgressCallback progressTo(ProgressBar& bar, const VoxelMap& map) {
  return [&bar, &map](const mapper::IntegrationProgress& p) {
    bar.update(p.fraction, p.rays_in, p.rays_per_second,
               bar.due() ? tierProgressText(map) : std::string());
  };
}

/// What a bag's messages gave (the "bag" object of --stats-json).
Json bagJson(const bag::BagRaysReport& b) {
  return {
      {"cloud_topics", b.cloud_topics},
      {"pose_source", b.pose_source},
      {"messages", b.messages},
      {"clouds", b.clouds},
      {"scans_integrated", b.scans_integrated},
      {"scans_no_pose", b.scans_no_pose},
      {"clouds_skipped", b.clouds_skipped},
      {"images_no_camera_info", b.images_no_camera_info},
      {"camera_infos", b.camera_infos},
      {"camera_infos_skipped", b.camera_infos_skipped},
      {"rate_limited", b.rate_limited},
      {"poses", b.poses},
      {"poses_skipped", b.poses_skipped},
      {"poses_out_of_order", b.poses_out_of_order},
      {"points_no_return", b.points_no_return},
      {"points_bad_time", b.points_bad_time},
      {"tf_ignored", b.tf_ignored},
      {"tf_unresolved", b.tf_unresolved},
      {"extrinsics_from_tf", b.extrinsics_from_tf},
      {"truncated", b.truncated},
      {"damage", b.damage},
  };
}

}  // namespace

Result<PopulateReport> integrateStream(VoxelMap& map, const PopulateOptions& options,
                                       const mapper::RayChunkReader& next_chunk,
                                       const std::function<double()>& fraction,
                                       StreamState* reuse) {
  ProgressBar bar("populate", options.progress);
  auto report =
      mapper::integrateRays(map, options, next_chunk, fraction, progressTo(bar, map), reuse);
  bar.finish();
  return report;
}

Result<PopulateReport> populateFromFile(VoxelMap& map, const PopulateOptions& options) {
  ProgressBar bar("populate", options.progress);
  auto report = mapper::integrateRecording(map, options.input, options.recording, options,
                                           progressTo(bar, map), "raymap populate");
  bar.finish();
  return report;
}

namespace {

/// The map and filter settings of the run.
Json settingsJson(const PopulateOptions& options) {
  return {
      {"input", options.input},
      {"mapper", "raymap"},
      {"semantics", toString(options.map.semantics)},
      {"mode", mapModeName(options.map)},
      {"resolution", options.map.geometry.resolution},
      {"region_voxels", options.map.geometry.region_voxels},
      {"min_range", options.filter.min_range_m},
      {"max_range", options.filter.max_range_m},
      {"walk", options.filter.reverse ? "reverse" : "forward"},
      {"hit_probability", probability(options.map.occupancy.hit)},
      {"miss_probability", probability(options.map.occupancy.miss)},
  };
}

/// The run's ray and scan counters, timings and map summary.
Json countersJson(const PopulateReport& r) {
  const double rate = r.integrate_seconds > 0
                          ? static_cast<double>(r.rays.rays_accepted) / r.integrate_seconds
                          : 0.0;
  return {
      {"rays_in", r.rays.rays_in},
      {"rays_integrated", r.rays.rays_accepted},
      {"rays_rejected", r.rays.rejected()},
      {"rays_invalid", r.rays.rays_invalid},
      {"rays_too_short", r.rays.rays_too_short},
      {"rays_out_of_bounds", r.rays.rays_out_of_bounds},
      {"rays_clipped", r.rays.rays_clipped},
      {"rays_no_return", r.rays.rays_no_return},
      {"ray_pieces", r.rays.pieces_out},
      {"scans", r.scans},
      {"scans_split", r.scans_split},
      {"integrate_seconds", r.integrate_seconds},
      {"rays_per_second", rate},
      {"integrate_cpu_seconds", r.integrate_cpu_seconds},
      {"integrate_thread_cpu_seconds", r.integrate_thread_cpu_seconds},
      {"host_cpu_ns_per_ray",
       r.rays.rays_accepted > 0
           ? r.integrate_cpu_seconds * 1e9 / static_cast<double>(r.rays.rays_accepted)
           : 0.0},
      {"read_seconds", r.read_seconds},
      {"total_seconds", r.total_seconds},
      {"voxels_free", r.summary.voxels_free},
      {"voxels_occupied", r.summary.voxels_occupied},
      {"tsdf_voxels_updated", r.tsdf.updated},
      {"tsdf_voxels_behind_surface", r.tsdf.behind},
      {"decay_voxels_crossed", r.decay.crossed},
      {"decay_voxels_with_samples", r.decay.with_samples},
      {"regions", r.summary.regions},
      {"voxels_visited", r.backend.voxels_visited},
      {"backend", r.backend_name},
      {"device", r.device},
      {"threads", r.threads},
      {"updates_dropped", r.backend.updates_dropped},
  };
}

/// Where the parallel CPU integrator's time went; balance 1 = every worker walked as long.
void addParallelCpuJson(Json& j, const PopulateReport& r) {
  const BackendStats& b = r.backend;
  const double capacity = b.apply_seconds * static_cast<double>(r.threads);
  j["survey_seconds"] = b.survey_seconds;
  j["serial_seconds"] = b.serial_seconds;
  j["resolve_seconds"] = b.resolve_seconds;
  j["apply_seconds"] = b.apply_seconds;
  j["apply_balance"] = capacity > 0 ? b.apply_busy_seconds / capacity : 0.0;
}

/// A device backend's planning, transfers and region cache.
void addDeviceJson(Json& j, const PopulateReport& r) {
  const BackendStats& b = r.backend;
  const std::uint64_t lookups = b.cache_hits + b.cache_misses;
  j["planning"] = b.planned_on_device ? "device" : "host";
  j["plans_on_host"] = b.plans_on_host;
  j["rays_prepared_on_device"] = b.rays_prepared_on_device;
  j["rays_skipped"] = b.rays_skipped;
  j["bytes_to_device"] = b.bytes_to_device;
  j["bytes_from_device"] = b.bytes_from_device;
  j["region_bytes_to_device"] = b.region_bytes_to_device;
  j["region_bytes_from_device"] = b.region_bytes_from_device;
  j["cache_slots"] = b.cache_slots;
  j["cache_hits"] = b.cache_hits;
  j["cache_misses"] = b.cache_misses;
  j["cache_evictions"] = b.cache_evictions;
  j["transfer_stalls"] = b.transfer_stalls;
  j["plan_seconds"] = b.plan_seconds;
  j["wait_seconds"] = b.wait_seconds;
  j["sync_seconds"] = b.sync_seconds;
  j["cache_hit_rate"] =
      lookups > 0 ? static_cast<double>(b.cache_hits) / static_cast<double>(lookups) : 0.0;
}

}  // namespace

Json statsJson(const PopulateReport& r, const PopulateOptions& options) {
  Json j = settingsJson(options);
  j.update(countersJson(r));
  if (r.backend_name == "cpu" && r.threads > 1) {
    addParallelCpuJson(j, r);
  }
  if (r.backend_name != "cpu") {
    addDeviceJson(j, r);
  }
  if (r.tiers) {
    j["memory_tiers"] = tierJson(*r.tiers);
  }
  if (r.bag) {
    j["bag"] = bagJson(*r.bag);
  }
  if (!r.fallback_warning.empty()) {
    j["fallback"] = withCliFlags(r.fallback_warning);
  }
  if (!r.startup_warning.empty()) {
    j["backend_warning"] = withCliFlags(r.startup_warning);
  }
  if (!r.input_warning.empty()) {
    j["input_warning"] = withCliFlags(r.input_warning);
  }
  j["peak_rss_bytes"] = r.peak_rss_bytes;
  return j;
}

}  // namespace raymap::cli
