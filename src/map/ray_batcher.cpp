// SPDX-License-Identifier: BSD-3-Clause
// RayBatcher: see the header.
#include "src/map/ray_batcher.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <new>
#include <string>

#include "raymap/assert.hpp"

namespace raymap {
namespace {

/// Below this many rays per host thread a run is prepared on the calling thread: waking the
/// workers costs tens of microseconds, preparing a ray about 60 ns.
constexpr std::size_t kMinRaysPerHostThread = 2048;

}  // namespace

RayBatcher::RayBatcher(const VoxelMap& map, Backend& backend, std::size_t batch_rays)
    : backend_(&backend), per_scan_(map.semantics() == Semantics::kPerScan), capacity_(batch_rays) {
  RAYMAP_EXPECTS(batch_rays > 0);
  if (!batch_.reserve(batch_rays)) {
    throw std::bad_alloc();  // as a std::vector of the batch would
  }
  // Rays as they came, for a backend that can prepare them on the device (pages made resident
  // only when used).
  if (backend.preparesOnDevice(RayFilter{}) && !raw_.reserve(batch_rays)) {
    throw std::bad_alloc();
  }
  if (!deskewed_.reserve(batch_rays)) {  // pages made resident only by integratePoints()
    throw std::bad_alloc();
  }
  parts_.resize(std::max(backend.threads(), 1u));
}

RayPreparer::Progress RayBatcher::prepareOnHostThreads(RayPreparer& preparer,
                                                       std::span<const Ray> in) noexcept {
  struct Context {
    const RayPreparer* preparer;
    std::span<const Ray> in;
    PreparedRay* out;
    PartResult* results;
    std::size_t max_parts;
    unsigned parts;  // written by part 0 (the calling thread)
  };
  Context context{&preparer, in, batch_.data() + fill_, parts_.data(), parts_.size(), 1};
  backend_->runOnHostThreads(
      [](void* c, unsigned part, unsigned parts) {
        Context& ctx = *static_cast<Context*>(c);
        if (part == 0) {
          ctx.parts = parts;
        }
        if (parts > ctx.max_parts) {
          return;  // more threads than the batcher was made for: prepared below, serially
        }
        const std::size_t n = ctx.in.size();
        const std::size_t begin = n * part / parts;
        const std::size_t end = n * (part + 1u) / parts;
        RayCounters counters;  // counted per ray: a local, not a line another thread writes
        const RayPreparer::Progress p =
            ctx.preparer->prepare(ctx.in.subspan(begin, end - begin),
                                  std::span<PreparedRay>(ctx.out + begin, end - begin), counters);
        ctx.results[part] = PartResult{counters, p.written};
      },
      &context);
  if (context.parts > parts_.size()) {
    return preparer.prepare(in, std::span<PreparedRay>(context.out, in.size()));
  }
  ++counters_.parallel_prepares;
  // Each range's prepared rays follow the previous range's (rejected rays leave gaps).
  std::size_t written = 0;
  for (unsigned part = 0; part < context.parts; ++part) {
    const std::size_t begin = in.size() * part / context.parts;
    const PartResult& result = parts_[part];
    if (written != begin) {
      std::copy(context.out + begin, context.out + begin + result.written, context.out + written);
    }
    written += result.written;
    preparer.addCounters(result.counters);
  }
  return RayPreparer::Progress{in.size(), written};
}

Expected<void, IntegrateError> RayBatcher::flush() noexcept {
  auto raw = flushRaw();
  if (fill_ == 0) {
    return raw;
  }
  const std::span<const PreparedRay> rays(batch_.data(), fill_);
  fill_ = 0;
  ++counters_.batches;
  auto ok = backend_->integrate(rays);
  if (!ok) {
    ++counters_.batches_failed;
    return raw ? ok : raw;
  }
  counters_.rays_integrated += rays.size();
  return raw;
}

Expected<void, IntegrateError> RayBatcher::flushRaw() noexcept {
  if (raw_fill_ == 0) {
    return {};
  }
  const std::span<const Ray> rays(rawData(), raw_fill_);
  raw_fill_ = 0;
  return integrateOnDevice(*raw_preparer_, raw_params_, rays);
}

Expected<void, IntegrateError> RayBatcher::integrateOnDevice(RayPreparer& preparer,
                                                             const rm_prepare_params& params,
                                                             std::span<const Ray> rays) noexcept {
  ++counters_.batches;
  ++counters_.device_batches;
  RayCounters counted;
  auto integrated = backend_->integrateRays(preparer, params, rays, counted);
  preparer.addCounters(counted);
  if (!integrated) {
    ++counters_.batches_failed;
    return Unexpected(integrated.error());
  }
  counters_.rays_integrated += *integrated;
  return {};
}

namespace {

void keepFirst(Expected<void, IntegrateError>& first_error, Expected<void, IntegrateError> ok) {
  if (!ok && first_error) {
    first_error = ok;
  }
}

}  // namespace

Expected<void, IntegrateError> RayBatcher::add(RayPreparer& preparer,
                                               std::span<const Ray> rays) noexcept {
  Expected<void, IntegrateError> first_error;
  std::size_t i = 0;
  while (i < rays.size()) {
    // A run of rays of one scan.
    std::size_t run_end = i + 1;
    while (run_end < rays.size() && rays[run_end].scan == rays[i].scan) {
      ++run_end;
    }
    if (!have_scan_ || rays[i].scan != scan_) {
      ++counters_.scans;
      if (per_scan_) {
        keepFirst(first_error, flush());  // the previous scan is complete
      }
      have_scan_ = true;
      scan_split_ = false;
      scan_on_host_ = false;
      scan_ = rays[i].scan;
    }
    const std::span<const Ray> run = rays.subspan(i, run_end - i);
    if (!scan_on_host_ && backend_->preparesOnDevice(preparer.filter())) {
      addForDevice(preparer, run, first_error);
    } else {
      addPrepared(preparer, run, first_error);
    }
    i = run_end;
  }
  return first_error;
}

void RayBatcher::addForDevice(RayPreparer& preparer, std::span<const Ray> run,
                              Expected<void, IntegrateError>& first_error) noexcept {
  if (fill_ > 0) {
    keepFirst(first_error, flush());  // host-prepared rays go in first: ray order
  }
  // One batch, one preparation: rays of another sensor's filter, or a rolling window that moved
  // since the batch's first ray, start a new batch (the host prepares each ray as it comes).
  const rm_prepare_params params = preparer.params();
  if (raw_fill_ > 0 &&
      (raw_preparer_ != &preparer || std::memcmp(&raw_params_, &params, sizeof params) != 0)) {
    keepFirst(first_error, flushRaw());
  }
  raw_preparer_ = &preparer;
  raw_params_ = params;
  while (!run.empty()) {
    if (!per_scan_ && raw_fill_ == 0 && run.size() >= capacity_) {
      // A whole batch from the caller's rays: no copy here.
      keepFirst(first_error, integrateOnDevice(preparer, params, run.first(capacity_)));
      run = run.subspan(capacity_);
      continue;
    }
    const std::size_t room = capacity_ - raw_fill_;
    if (room == 0 && per_scan_) {
      // The scan outgrew the batch: on the host's way it is integrated in parts cut where the
      // batch fills with prepared rays, which only preparing tells. So the host prepares it.
      scan_on_host_ = true;
      const std::span<const Ray> held(rawData(), raw_fill_);
      raw_fill_ = 0;
      addPrepared(preparer, held, first_error);  // the window cannot have moved: same params
      addPrepared(preparer, run, first_error);
      return;
    }
    if (room == 0) {
      keepFirst(first_error, flushRaw());
      continue;
    }
    const std::size_t n = std::min(room, run.size());
    if (in_place_) {
      // Staged runs follow each other in the staging room: the batch grows over them.
      if (raw_fill_ == 0) {
        raw_view_ = run.data();
      }
      RAYMAP_ENSURES(run.data() == raw_view_ + raw_fill_);
    } else {
      std::copy(run.begin(), run.begin() + static_cast<std::ptrdiff_t>(n), raw_.data() + raw_fill_);
    }
    raw_fill_ += n;
    run = run.subspan(n);
  }
  if (!per_scan_ && raw_fill_ == capacity_) {
    keepFirst(first_error, flushRaw());
  }
}

void RayBatcher::addPrepared(RayPreparer& preparer, std::span<const Ray> run,
                             Expected<void, IntegrateError>& first_error) noexcept {
  if (raw_fill_ > 0) {
    keepFirst(first_error, flushRaw());  // rays for the device go in first: ray order
  }
  std::size_t i = 0;
  const std::size_t run_end = run.size();
  while (i < run_end) {
    const std::size_t room = capacity_ - fill_;
    const std::size_t fits = std::min(run_end - i, room);  // one prepared ray each, unsegmented
    const RayPreparer::Progress p =
        parts_.size() > 1 && preparer.filter().segment_length_m <= 0.0 &&
                fits >= kMinRaysPerHostThread * parts_.size()
            ? prepareOnHostThreads(preparer, run.subspan(i, fits))
            : preparer.prepare(run.subspan(i, run_end - i),
                               std::span<PreparedRay>(batch_.data() + fill_, room));
    fill_ += p.written;
    i += p.consumed;
    if (fill_ == capacity_ || (p.consumed == 0 && i < run_end)) {
      // Full (or no room for the next ray's pieces): in it goes.
      if (per_scan_ && i < run_end && !scan_split_) {
        ++counters_.scans_split;
        scan_split_ = true;
      }
      if (fill_ == 0) {
        // This ray has more pieces than an empty batch holds: it is left out and counted, and
        // the rays after it go on (they used to be dropped with it, uncounted).
        ++counters_.rays_too_many_pieces;
        ++i;
        continue;
      }
      keepFirst(first_error, flush());
    }
  }
}

std::span<Ray> RayBatcher::staging() {
  if (staged_.size() < capacity_) {
    // Zeroed, so touched now, at start-up: the integrator's real-time loop must not fault its
    // pages in.
    staged_.assign(capacity_, Ray{});
  }
  return {staged_.data(), capacity_};
}

Expected<void, IntegrateError> RayBatcher::integrateStaged(RayPreparer& preparer, std::size_t first,
                                                           std::size_t count) noexcept {
  RAYMAP_EXPECTS(staged_.size() >= capacity_ && first + count <= capacity_);
  // What waits from add() for the device goes first (ray order), from raw_.
  Expected<void, IntegrateError> first_error = flushRaw();
  in_place_ = true;
  keepFirst(first_error, add(preparer, std::span<const Ray>(staged_.data() + first, count)));
  keepFirst(first_error, flush());  // the view must not outlive the call
  in_place_ = false;
  raw_view_ = nullptr;
  return first_error;
}

Ray deskewedRay(const rm_scan_point& p, const DeskewTables& tables) noexcept {
  rm_vec3d origin;
  rm_vec3d sample;
  rm_deskew_point(p, tables.poses.data(), tables.segments[p.segment], &origin, &sample);
  Ray ray;
  ray.origin = Vec3d{origin.x, origin.y, origin.z};
  ray.sample = Vec3d{sample.x, sample.y, sample.z};
  ray.time_s = static_cast<double>(p.time_ns) * 1e-9;
  ray.intensity = p.intensity;
  ray.flags = p.flags;  // RM_RAW_RAY_NO_RETURN is kRayNoReturn
  ray.scan = tables.segment_scans[p.segment];
  return ray;
}

Expected<void, IntegrateError> RayBatcher::integratePoints(RayPreparer& preparer,
                                                           std::span<const rm_scan_point> points,
                                                           const DeskewTables& tables) noexcept {
  Expected<void, IntegrateError> first_error;
  std::size_t i = 0;
  while (i < points.size()) {
    // A run of points of one scan.
    const std::uint64_t scan = tables.segment_scans[points[i].segment];
    std::size_t run_end = i + 1;
    while (run_end < points.size() && tables.segment_scans[points[run_end].segment] == scan) {
      ++run_end;
    }
    std::span<const rm_scan_point> run = points.subspan(i, run_end - i);
    i = run_end;
    // Per scan, a scan larger than the batch is integrated in parts cut by prepared rays: the
    // host's way, which add() takes.
    const bool on_device = backend_->deskewsOnDevice(preparer.filter(), tables, run.size()) &&
                           (!per_scan_ || run.size() <= capacity_);
    if (!on_device) {
      while (!run.empty()) {
        const std::size_t n = std::min(run.size(), capacity_);
        for (std::size_t k = 0; k < n; ++k) {
          deskewed_[k] = deskewedRay(run[k], tables);
        }
        keepFirst(first_error, add(preparer, std::span<const Ray>(deskewed_.data(), n)));
        run = run.subspan(n);
      }
      continue;
    }
    keepFirst(first_error, flush());  // what waits goes first: ray order
    if (!have_scan_ || scan != scan_) {
      ++counters_.scans;
      have_scan_ = true;
      scan_split_ = false;
      scan_on_host_ = false;
      scan_ = scan;
    }
    const rm_prepare_params params = preparer.params();
    while (!run.empty()) {
      const std::size_t n = std::min(run.size(), capacity_);
      ++counters_.batches;
      ++counters_.device_batches;
      RayCounters counted;
      auto integrated = backend_->integratePoints(preparer, params, run.first(n), tables, counted);
      preparer.addCounters(counted);
      if (integrated) {
        counters_.rays_integrated += *integrated;
        counters_.points_deskewed_on_device += n;
      } else {
        ++counters_.batches_failed;
        keepFirst(first_error, Unexpected(integrated.error()));
      }
      run = run.subspan(n);
    }
  }
  keepFirst(first_error, flush());
  return first_error;
}

Error integrateFailure(const VoxelMap& map, const Backend& backend, IntegrateError error,
                       std::string_view raise) {
  if (error == IntegrateError::kTierFailed) {
    const auto failure = map.tierFailure();
    return Error{failure ? failure->code : ErrorCode::kIo,
                 "moving regions between the map's memory tiers failed: " +
                     (failure ? failure->message : std::string("unknown reason"))};
  }
  if (error == IntegrateError::kStoreFull && map.tiered()) {
    // Per-ray batches on the CPU split themselves to fit; a per-scan batch is one scan and an
    // NDT batch's hits follow all its misses, and device backends plan whole batches.
    return Error{ErrorCode::kCapacity,
                 "one batch touches more regions than the pool's " +
                     std::to_string(map.store().capacity()) +
                     " hold at once (per-scan, NDT and device batches are not split); raise " +
                     std::string(raise) + " or make batches smaller (queues.batch_rays)"};
  }
  if (error == IntegrateError::kStoreFull) {
    char gib[32];
    std::snprintf(gib, sizeof gib, "%g",
                  static_cast<double>(map.store().poolBytes()) / static_cast<double>(1u << 30));
    return Error{ErrorCode::kCapacity, "the map needs more than the " +
                                           std::to_string(map.store().capacity()) + " regions (" +
                                           gib + " GiB) its memory budget allows; raise " +
                                           std::string(raise)};
  }
  if (error == IntegrateError::kOutOfMemory) {
    return Error{ErrorCode::kCapacity, std::string("integration failed on the ") + backend.name() +
                                           " backend: " + toString(error) +
                                           "; make batches smaller (queues.batch_rays)"};
  }
  return Error{ErrorCode::kIo, std::string("integration failed on the ") + backend.name() +
                                   " backend: " + toString(error)};
}

}  // namespace raymap
