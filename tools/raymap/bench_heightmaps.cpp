// SPDX-License-Identifier: BSD-3-Clause
#include "tools/raymap/bench_heightmaps.hpp"

#include <algorithm>
#include <chrono>

namespace raymap::cli {
namespace {

/// The value at quantile q of `values` (nearest rank); 0 when empty.
double quantile(std::vector<double> values, double q) {
  if (values.empty()) {
    return 0.0;
  }
  std::sort(values.begin(), values.end());
  const auto rank = static_cast<std::size_t>(q * static_cast<double>(values.size() - 1) + 0.5);
  return values[std::min(rank, values.size() - 1)];
}

}  // namespace

Expected<void, Error> BenchHeightmaps::maybeGenerate(std::uint64_t rays_read, Vec3d sensor,
                                                     VoxelMap& map, Backend& backend,
                                                     const backends::BackendChoice& choice) {
  if (!enabled() || rays_read < next_at_) {
    return {};
  }
  next_at_ = (rays_read / options_.every_rays + 1) * options_.every_rays;
  if (!generator_) {
    backends::BackendChoice own = choice;
    own.name = backend.name();
    auto created = options_.from_host ? backends::createHeightmapGenerator(own)
                                      : backends::createHeightmapGenerator(backend);
    if (!created) {
      return Unexpected(created.error());
    }
    generator_ = std::move(created->generator);
  }
  const auto start = std::chrono::steady_clock::now();
  const std::uint64_t downloaded = backend.stats().region_bytes_from_device;
  if (generator_->readsHostStore()) {
    if (auto ok = backend.synchronise(); !ok) {
      return fail(ErrorCode::kIo,
                  std::string("--heightmap-every: synchronising the map: ") + toString(ok.error()));
    }
  }
  heightmap::HeightmapOptions request;
  request.size = options_.size_m;
  request.centre = sensor;
  if (!heightmap::planHeightmap(map, request, plan_)) {
    ++skipped_;  // the sensor is outside the map so far
    return {};
  }
  const std::uint64_t copied = generator_->bytesCopied();
  const std::uint64_t map_copied = generator_->mapBytesCopied();
  if (auto ok = generator_->generate(map, plan_, out_); !ok) {
    return fail(ok.error().code, "--heightmap-every: " + ok.error().message);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  seconds_ += seconds;
  generate_ms_.push_back(seconds * 1e3);
  copy_bytes_.push_back(static_cast<double>(generator_->mapBytesCopied() - map_copied));
  transfer_bytes_.push_back(static_cast<double>(generator_->bytesCopied() - copied));
  sync_bytes_.push_back(static_cast<double>(backend.stats().region_bytes_from_device - downloaded));
  return {};
}

Json BenchHeightmaps::json(std::uint64_t rays, double integrate_seconds) const {
  const double total = integrate_seconds + seconds_;
  return {
      {"every_rays", options_.every_rays},
      {"size_m", options_.size_m},
      {"reads", generator_ && !generator_->readsHostStore() ? "device layers" : "host store"},
      {"generator", generator_ ? generator_->name() : ""},
      {"heightmaps", generate_ms_.size()},
      {"skipped_outside_map", skipped_},
      {"cycle_p50_ms", quantile(generate_ms_, 0.5)},
      {"cycle_p99_ms", quantile(generate_ms_, 0.99)},
      {"cycle_seconds_total", seconds_},
      {"sync_copy_bytes_p50", quantile(sync_bytes_, 0.5)},
      {"sync_copy_bytes_p99", quantile(sync_bytes_, 0.99)},
      {"heightmap_copy_bytes_p50", quantile(copy_bytes_, 0.5)},
      {"heightmap_copy_bytes_p99", quantile(copy_bytes_, 0.99)},
      {"heightmap_transfer_bytes_p99", quantile(transfer_bytes_, 0.99)},
      {"rays_per_second_with_heightmaps", total > 0 ? static_cast<double>(rays) / total : 0.0},
  };
}

}  // namespace raymap::cli
