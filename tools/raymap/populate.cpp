// SPDX-License-Identifier: BSD-3-Clause
// The offline mapping job.
#include "tools/raymap/populate.hpp"

#include <chrono>
#include <vector>

#include "platform/process.hpp"
#include "src/map/ray_batcher.hpp"
#include "src/mapper/recording.hpp"
#include "tools/raymap/option_names.hpp"
#include "tools/raymap/progress.hpp"

namespace raymap::cli {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

std::string number(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%g", value);
  return buffer;
}

/// CPU seconds of the process and of the calling thread.
struct CpuTimes {
  double process = 0;
  double thread = 0;
};

CpuTimes cpuTimes() noexcept {
  return CpuTimes{platform::processCpuSeconds(), platform::threadCpuSeconds()};
}

void addCpuSince(const CpuTimes& before, PopulateReport* report) noexcept {
  const CpuTimes now = cpuTimes();
  report->integrate_cpu_seconds += now.process - before.process;
  report->integrate_thread_cpu_seconds += now.thread - before.thread;
}

/// Counters of `now` minus those of `before` (a reused backend's share of one run).
BackendStats statsSince(const BackendStats& now, const BackendStats& before) {
  BackendStats d = now;
  d.batches -= before.batches;
  d.rays -= before.rays;
  d.voxels_visited -= before.voxels_visited;
  d.updates_dropped -= before.updates_dropped;
  d.spans_outside_window -= before.spans_outside_window;
  d.rays_skipped -= before.rays_skipped;
  d.bytes_to_device -= before.bytes_to_device;
  d.bytes_from_device -= before.bytes_from_device;
  d.region_bytes_to_device -= before.region_bytes_to_device;
  d.region_bytes_from_device -= before.region_bytes_from_device;
  d.cache_hits -= before.cache_hits;
  d.cache_misses -= before.cache_misses;
  d.cache_evictions -= before.cache_evictions;
  d.plans_on_host -= before.plans_on_host;
  d.rays_prepared_on_device -= before.rays_prepared_on_device;
  d.points_deskewed_on_device -= before.points_deskewed_on_device;
  d.transfer_stalls -= before.transfer_stalls;
  d.plan_seconds -= before.plan_seconds;
  d.wait_seconds -= before.wait_seconds;
  d.sync_seconds -= before.sync_seconds;
  d.survey_seconds -= before.survey_seconds;
  d.serial_seconds -= before.serial_seconds;
  d.resolve_seconds -= before.resolve_seconds;
  d.apply_seconds -= before.apply_seconds;
  d.apply_busy_seconds -= before.apply_busy_seconds;
  return d;  // cache_slots is a size, not a counter
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

Result<PopulateReport> integrateStream(
    VoxelMap& map, const PopulateOptions& options,
    const std::function<Result<std::size_t>(std::span<Ray>)>& next_chunk,
    const std::function<double()>& progress, StreamState* reuse) {
  const Clock::time_point start = Clock::now();
  StreamState owned;
  StreamState& state = reuse != nullptr ? *reuse : owned;
  CreatedBackend* created = &state.created;
  if (!created->backend) {
    auto made = createBackend(map, options.backend);
    if (!made) {
      return Unexpected(made.error());
    }
    *created = std::move(*made);
  }
  Backend& backend = *created->backend;
  const BackendStats stats_before = backend.stats();
  RayPreparer preparer(map, options.filter);
  if (!state.batcher) {
    state.batcher = std::make_unique<RayBatcher>(
        map, backend, options.batch_rays != 0 ? options.batch_rays : backend.preferredBatchRays());
  }
  RayBatcher& batcher = *state.batcher;
  batcher.endStream();  // the input starts again: its first rays are a new scan
  const BatcherCounters batcher_before = batcher.counters();

  PopulateReport report;
  report.backend_name = backend.name();
  report.device = backend.deviceName();
  report.fallback_warning = created->fallback_warning;
  report.startup_warning = created->startup_warning;
  report.threads = backend.threads();
  std::vector<Ray> chunk(std::size_t{1} << 16);
  ProgressBar bar("populate", options.progress);

  const auto integrate_failed = [&](IntegrateError error) {
    return integrateFailure(map, backend, error, "--max-memory");
  };

  for (;;) {
    const Clock::time_point t_read = Clock::now();
    auto count = next_chunk(chunk);
    report.read_seconds += secondsSince(t_read);
    if (!count) {
      return Unexpected(count.error());
    }
    if (*count == 0) {
      break;
    }
    const Clock::time_point t_integrate = Clock::now();
    const CpuTimes cpu_before = cpuTimes();
    auto ok = batcher.add(preparer, std::span<const Ray>(chunk.data(), *count));
    report.integrate_seconds += secondsSince(t_integrate);
    addCpuSince(cpu_before, &report);
    if (!ok) {
      return Unexpected(integrate_failed(ok.error()));
    }
    const double seconds = report.integrate_seconds;
    bar.update(progress(), preparer.counters().rays_in,
               seconds > 0 ? static_cast<double>(preparer.counters().rays_accepted) / seconds : 0.0,
               bar.due() ? tierProgressText(map) : std::string());
  }
  {
    const Clock::time_point t_integrate = Clock::now();
    const CpuTimes cpu_before = cpuTimes();
    auto ok = batcher.flush();
    report.integrate_seconds += secondsSince(t_integrate);
    addCpuSince(cpu_before, &report);
    if (!ok) {
      return Unexpected(integrate_failed(ok.error()));
    }
  }
  report.scans = batcher.counters().scans - batcher_before.scans;
  report.scans_split = batcher.counters().scans_split - batcher_before.scans_split;
  // Device backends return before the device finishes: the wait and the download of the map
  // belong to the integration time.
  const Clock::time_point t_sync = Clock::now();
  const CpuTimes cpu_before_sync = cpuTimes();
  if (auto ok = backend.synchronise(); !ok) {
    return fail(ErrorCode::kIo, std::string("integration failed on the ") + backend.name() +
                                    " backend: " + toString(ok.error()));
  }
  report.integrate_seconds += secondsSince(t_sync);
  addCpuSince(cpu_before_sync, &report);
  bar.finish();
  report.rays = preparer.counters();
  report.backend = statsSince(backend.stats(), stats_before);
  report.summary = map.summarise();
  report.tsdf = summariseTsdf(map);
  report.decay = summariseDecay(map);
  if (auto ok = map.drainTiers(); !ok) {
    return Unexpected(ok.error());
  }
  if (auto ok = checkTiers(map); !ok) {
    return Unexpected(ok.error());
  }
  report.tiers = tierReport(map);
  if (report.tiers) {
    report.tiers->batches_split = report.backend.batches_split;
  }
  report.total_seconds = secondsSince(start);
  report.peak_rss_bytes = platform::peakResidentBytes();
  return report;
}

Result<PopulateReport> populateFromFile(VoxelMap& map, const PopulateOptions& options) {
  // The library's reader choice and option conversion, the same as raymap::RecordingReader's.
  auto recording = mapper::openRecording(options.input, options.recording);
  if (!recording) {
    return Unexpected(recording.error());
  }
  io::RaySource& source = *recording->source;
  const bag::BagRaySource* bag_source = recording->bag;
  const std::string warning = inputWarning(map.mode(), source.info());
  auto report = integrateStream(
      map, options, [&](std::span<Ray> out) { return source.read(out); },
      [&] { return source.progress(); });
  if (!report) {
    return report;
  }
  report->input_warning = warning;
  if (bag_source != nullptr) {
    report->bag = bag_source->report();
  }
  map.setInfo("source", options.input);
  map.setInfo("rays_in", std::to_string(report->rays.rays_in));
  map.setInfo("rays_integrated", std::to_string(report->rays.rays_accepted));
  map.setInfo("min_range_m", number(options.filter.min_range_m));
  map.setInfo("max_range_m", number(options.filter.max_range_m));
  map.setInfo("segment_length_m", number(options.filter.segment_length_m));
  map.setInfo("walk", options.filter.reverse ? "reverse" : "forward");
  map.setInfo("created_by", "raymap populate");
  return report;
}

std::string inputWarning(MapMode mode, const io::RaySourceInfo& input) {
  if (mode != MapMode::kNdtTm || input.has_intensity) {
    return {};
  }
  return input.path +
         " has no 'intensity' property: the ndt-tm intensity layer records 0 for every sample "
         "(hit/miss counts and the Gaussians are unaffected)";
}

Json statsJson(const PopulateReport& r, const PopulateOptions& options) {
  const double rate = r.integrate_seconds > 0
                          ? static_cast<double>(r.rays.rays_accepted) / r.integrate_seconds
                          : 0.0;
  Json j = {
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
  if (r.backend_name == "cpu" && r.threads > 1) {
    // Where the parallel integrator's time went; balance 1 = every worker walked as long.
    const BackendStats& b = r.backend;
    const double capacity = b.apply_seconds * static_cast<double>(r.threads);
    j["survey_seconds"] = b.survey_seconds;
    j["serial_seconds"] = b.serial_seconds;
    j["resolve_seconds"] = b.resolve_seconds;
    j["apply_seconds"] = b.apply_seconds;
    j["apply_balance"] = capacity > 0 ? b.apply_busy_seconds / capacity : 0.0;
  }
  if (r.backend_name != "cpu") {
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
