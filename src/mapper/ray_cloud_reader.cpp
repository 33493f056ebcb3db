// SPDX-License-Identifier: BSD-3-Clause
// raymap::RayCloudReader: io::RaySource (the PLY readers of `raymap populate`), cut into scans.
#include <utility>

#include "raymap/ray_cloud.hpp"

#include "src/core/eigen_conversions.hpp"
#include "src/io/ray_source.hpp"

namespace raymap {

struct RayCloudReader::State {
  std::unique_ptr<io::RaySource> source;
  std::vector<Ray> buffer = std::vector<Ray>(std::size_t{1} << 16);
  std::size_t next = 0;  // first unread ray in buffer
  std::size_t fill = 0;  // rays in buffer
};

RayCloudReader::RayCloudReader(std::unique_ptr<State> state) noexcept : state_(std::move(state)) {}
RayCloudReader::RayCloudReader(RayCloudReader&&) noexcept = default;
RayCloudReader& RayCloudReader::operator=(RayCloudReader&&) noexcept = default;
RayCloudReader::~RayCloudReader() = default;

Result<RayCloudReader> RayCloudReader::open(const std::string& path,
                                            const RayCloudOptions& options) {
  io::RaySourceOptions source_options;
  source_options.trajectory_path = options.trajectory_path;
  source_options.sensor_offset = toVec3(options.sensor_offset);
  source_options.scan_period_s = options.scan_period_s;
  auto source = io::openRaySource(path, source_options);
  if (!source) {
    return Unexpected(source.error());
  }
  auto state = std::make_unique<State>();
  state->source = std::move(*source);
  return RayCloudReader(std::move(state));
}

Result<bool> RayCloudReader::nextScan(std::vector<WorldRay>& scan) {
  State& s = *state_;
  scan.clear();
  bool have_scan = false;
  std::uint64_t scan_number = 0;
  for (;;) {
    if (s.next == s.fill) {
      auto count = s.source->read(s.buffer);
      if (!count) {
        return Unexpected(count.error());
      }
      s.next = 0;
      s.fill = *count;
      if (s.fill == 0) {
        return have_scan;
      }
    }
    const Ray& ray = s.buffer[s.next];
    if (have_scan && ray.scan != scan_number) {
      return true;  // the next scan starts here
    }
    have_scan = true;
    scan_number = ray.scan;
    WorldRay out;
    out.origin = toEigen(ray.origin);
    out.end = toEigen(ray.sample);
    out.intensity = ray.intensity;
    out.no_return = (ray.flags & kRayNoReturn) != 0u;
    scan.push_back(out);
    ++s.next;
  }
}

double RayCloudReader::progress() const noexcept { return state_->source->progress(); }

}  // namespace raymap
