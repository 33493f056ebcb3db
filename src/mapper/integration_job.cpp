// SPDX-License-Identifier: BSD-3-Clause
// The offline mapping job (see integration_job.hpp).
#include "src/mapper/integration_job.hpp"

#include <chrono>
#include <cstdio>
#include <vector>

#include "platform/process.hpp"
#include "src/mapper/recording.hpp"

namespace raymap::mapper {
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

void addCpuSince(const CpuTimes& before, IntegrationReport* report) noexcept {
  const CpuTimes now = cpuTimes();
  report->integrate_cpu_seconds += now.process - before.process;
  report->integrate_thread_cpu_seconds += now.thread - before.thread;
}

}  // namespace

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

namespace {

/// The session's backend and batcher, made on first use.
Expected<void, Error> startSession(VoxelMap& map, const IntegrationOptions& options,
                                   IntegrationSession& session) {
  if (!session.created.backend) {
    auto made = backends::createBackend(map, options.backend);
    if (!made) {
      return Unexpected(made.error());
    }
    session.created = std::move(*made);
  }
  Backend& backend = *session.created.backend;
  if (!session.batcher) {
    session.batcher = std::make_unique<RayBatcher>(
        map, backend, options.batch_rays != 0 ? options.batch_rays : backend.preferredBatchRays());
  }
  return {};
}

/// Runs `step` (preparation, integration or the device's sync) and adds its wall and CPU time to
/// the report's integration time.
template <class Step>
auto timedIntegration(IntegrationReport& report, Step&& step) {
  const Clock::time_point start = Clock::now();
  const CpuTimes cpu_before = cpuTimes();
  auto result = step();
  report.integrate_seconds += secondsSince(start);
  addCpuSince(cpu_before, &report);
  return result;
}

/// After the last batch: the counters, the map's summaries and the tiers drained and checked.
Expected<void, Error> finishReport(VoxelMap& map, const Backend& backend,
                                   const RayPreparer& preparer, const BackendStats& stats_before,
                                   IntegrationReport& report) {
  report.rays = preparer.counters();
  report.backend = statsSince(backend.stats(), stats_before);
  report.summary = map.summarise();
  report.tsdf = summariseTsdf(map);
  report.decay = summariseDecay(map);
  if (auto ok = map.drainTiers(); !ok) {
    return ok;
  }
  if (auto ok = checkTiers(map); !ok) {
    return ok;
  }
  report.tiers = tierReport(map);
  if (report.tiers) {
    report.tiers->batches_split = report.backend.batches_split;
  }
  return {};
}

}  // namespace

Result<IntegrationReport> integrateRays(VoxelMap& map, const IntegrationOptions& options,
                                        const RayChunkReader& next_chunk,
                                        const std::function<double()>& fraction,
                                        const ProgressCallback& on_progress,
                                        IntegrationSession* reuse) {
  const Clock::time_point start = Clock::now();
  IntegrationSession owned;
  IntegrationSession& session = reuse != nullptr ? *reuse : owned;
  if (auto ok = startSession(map, options, session); !ok) {
    return Unexpected(ok.error());
  }
  Backend& backend = *session.created.backend;
  const BackendStats stats_before = backend.stats();
  RayPreparer preparer(map, options.filter);
  RayBatcher& batcher = *session.batcher;
  batcher.endStream();  // the input starts again: its first rays are a new scan
  const BatcherCounters batcher_before = batcher.counters();

  IntegrationReport report;
  report.backend_name = backend.name();
  report.device = backend.deviceName();
  report.fallback_warning = session.created.fallback_warning;
  report.startup_warning = session.created.startup_warning;
  report.threads = backend.threads();
  std::vector<Ray> chunk(std::size_t{1} << 16);
  const auto integrate_failed = [&](IntegrateError error) {
    return integrateFailure(map, backend, error, "map.max_memory");
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
    const std::span<const Ray> rays(chunk.data(), *count);
    if (auto ok = timedIntegration(report, [&] { return batcher.add(preparer, rays); }); !ok) {
      return Unexpected(integrate_failed(ok.error()));
    }
    if (on_progress) {
      const double seconds = report.integrate_seconds;
      const RayCounters& counted = preparer.counters();
      on_progress(IntegrationProgress{
          fraction(), counted.rays_in,
          seconds > 0 ? static_cast<double>(counted.rays_accepted) / seconds : 0.0});
    }
  }
  if (auto ok = timedIntegration(report, [&] { return batcher.flush(); }); !ok) {
    return Unexpected(integrate_failed(ok.error()));
  }
  report.scans = batcher.counters().scans - batcher_before.scans;
  report.scans_split = batcher.counters().scans_split - batcher_before.scans_split;
  // Device backends return before the device finishes: the wait and the download of the map
  // belong to the integration time.
  if (auto ok = timedIntegration(report, [&] { return backend.synchronise(); }); !ok) {
    return fail(ErrorCode::kIo, std::string("integration failed on the ") + backend.name() +
                                    " backend: " + toString(ok.error()));
  }
  if (auto ok = finishReport(map, backend, preparer, stats_before, report); !ok) {
    return Unexpected(ok.error());
  }
  report.total_seconds = secondsSince(start);
  report.peak_rss_bytes = platform::peakResidentBytes();
  return report;
}

Result<IntegrationReport> integrateRecording(VoxelMap& map, const std::string& input,
                                             const RecordingOptions& recording_options,
                                             const IntegrationOptions& options,
                                             const ProgressCallback& on_progress,
                                             std::string_view created_by) {
  // The reader choice and option conversion of raymap::RecordingReader.
  auto recording = openRecording(input, recording_options);
  if (!recording) {
    return Unexpected(recording.error());
  }
  io::RaySource& source = *recording->source;
  const bag::BagRaySource* bag_source = recording->bag;
  const std::string warning = inputWarning(map.mode(), source.info());
  auto report = integrateRays(
      map, options, [&](std::span<Ray> out) { return source.read(out); },
      [&] { return source.progress(); }, on_progress);
  if (!report) {
    return report;
  }
  report->input_warning = warning;
  if (bag_source != nullptr) {
    report->bag = bag_source->report();
  }
  map.setInfo("source", input);
  map.setInfo("rays_in", std::to_string(report->rays.rays_in));
  map.setInfo("rays_integrated", std::to_string(report->rays.rays_accepted));
  map.setInfo("min_range_m", number(options.filter.min_range_m));
  map.setInfo("max_range_m", number(options.filter.max_range_m));
  map.setInfo("segment_length_m", number(options.filter.segment_length_m));
  map.setInfo("walk", options.filter.reverse ? "reverse" : "forward");
  map.setInfo("created_by", std::string(created_by));
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

}  // namespace raymap::mapper
