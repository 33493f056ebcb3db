// SPDX-License-Identifier: BSD-3-Clause
#include "src/mapper/mapper_yaml.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>

#include "src/core/byte_size.hpp"
#include "src/device/backend_choice.hpp"
#include "src/map/map_params.hpp"

namespace raymap::mapper {
namespace {

using config::choiceOr;
using config::Context;
using config::Fields;
using config::flag;
using config::text;

/// map.ndt: only the keys given are set, so that the library's conversion refuses them for a
/// map of another mode and supplies the defaults; it also checks their ranges.
void readNdt(Context& ctx, const YAML::Node& node, const std::string& path, NdtOptions& ndt) {
  Fields f(ctx, node, path);
  f.knownKeys({"sensor_noise", "regulariser", "sample_threshold", "reinit_probability",
               "reinit_count", "adaptation_rate", "initial_intensity_variance"});
  const auto number = [&](const char* key, std::optional<double>& out) {
    if (f.has(key)) {
      out = f.number(key);
    }
  };
  number("sensor_noise", ndt.sensor_noise);
  number("regulariser", ndt.regulariser);
  number("reinit_probability", ndt.reinit_probability);
  number("adaptation_rate", ndt.adaptation_rate);
  number("initial_intensity_variance", ndt.initial_intensity_variance);
  if (f.has("sample_threshold")) {
    ndt.sample_threshold = f.integer<std::uint32_t>("sample_threshold", 0u, 1u, 1'000'000u);
  }
  if (f.has("reinit_count")) {
    ndt.reinit_count = f.integer<std::uint32_t>("reinit_count", 0u, 1u, 1'000'000'000u);
  }
}

/// map.semantics: "ray" or "scan", as `raymap populate --semantics` and `raymap info` spell them;
/// the older "per-ray" and "per-scan" are read with a warning naming the new value.
void readSemantics(Fields& f, Semantics& semantics, std::vector<std::string>& warnings) {
  if (!f.has("semantics")) {
    return;
  }
  static const std::vector<std::string> kNames = {"ray", "scan", "per-ray", "per-scan"};
  const std::size_t choice = f.choice("semantics", kNames);
  if (choice >= 2) {
    warnings.push_back(f.path("semantics") + ": " + kNames[choice] + " is the old name: write " +
                       kNames[choice - 2] + " (the old one is read until the next release)");
  }
  semantics = choice % 2 == 0 ? Semantics::kPerRay : Semantics::kPerScan;
}

/// map.clamp_min_probability / clamp_max_probability, probabilities as every other occupancy
/// key; the older clamp_min / clamp_max (log-odds) are read with a warning naming the new key.
void readClamp(Fields& f, const std::string& old_key, double& clamp,
               std::vector<std::string>& warnings) {
  const std::string key = old_key + "_probability";
  if (f.has(old_key)) {
    warnings.push_back(f.path(old_key) + " is the old key (log-odds): write map." + key +
                       " with a probability (the old one is read until the next release)");
    f.check(!f.has(key), old_key, "give map." + key + " or map." + old_key + ", not both");
    clamp = probability(static_cast<float>(f.number(old_key, 0.0)));
    return;
  }
  clamp = f.number(key, clamp);
}

/// backend.gpu_cache: "auto", a size ("512MiB") or a region count ("2000regions"), as
/// `raymap populate --gpu-cache`; the older gpu_cache_mb (MiB, 0 = automatic) is read with a
/// warning naming the new key.
void readGpuCache(Fields& f, BackendOptions& backend, std::vector<std::string>& warnings) {
  if (f.has("gpu_cache_mb")) {
    warnings.push_back(f.path("gpu_cache_mb") +
                       " is the old key: write backend.gpu_cache with a size (512MiB), a region "
                       "count (2000regions) or auto (the old one is read until the next release)");
    f.check(!f.has("gpu_cache"), "gpu_cache_mb",
            "give backend.gpu_cache or gpu_cache_mb, not both");
    backend.gpu_cache_bytes =
        std::uint64_t{f.integer<std::uint32_t>("gpu_cache_mb", 0u, 0u, 1u << 20)} << 20;
    backend.gpu_cache_regions = 0;
    return;
  }
  if (!f.has("gpu_cache")) {
    return;
  }
  auto size = parseCacheSize(text(f, "gpu_cache", "auto"));
  if (!size) {
    f.check(false, "gpu_cache", size.error().message);
    return;
  }
  backend.gpu_cache_bytes = size->bytes;
  backend.gpu_cache_regions = size->regions;
}

/// The index of `current` in `choices` (the fallback of choiceOr: an absent key keeps it).
std::size_t indexOf(const std::vector<std::string>& choices, const std::string& current) {
  const auto it = std::find(choices.begin(), choices.end(), current);
  return it == choices.end() ? 0 : static_cast<std::size_t>(it - choices.begin());
}

}  // namespace

void readMapOptions(Context& ctx, const YAML::Node& node, MapOptions& map,
                    std::vector<std::string>& warnings) {
  Fields f(ctx, node, "map");
  f.knownKeys({"resolution", "region_voxels", "window", "semantics", "voxel_mean",
               "hit_probability", "miss_probability", "clamp_min_probability",
               "clamp_max_probability", "occupied_threshold", "clamp_min", "clamp_max",
               "save_on_exit", "mode", "ndt", "decay_rate"});
  map.resolution = f.positive("resolution", map.resolution);
  map.region_voxels =
      f.integer<std::int32_t>("region_voxels", map.region_voxels, MapGeometry::kMinRegionVoxels,
                              MapGeometry::kMaxRegionVoxels);
  readSemantics(f, map.semantics, warnings);
  map.voxel_mean = flag(f, "voxel_mean", map.voxel_mean);
  map.decay_rate = flag(f, "decay_rate", map.decay_rate);
  static const std::vector<std::string> kModes = {"occupancy", "ndt-om", "ndt-tm"};
  if (f.has("mode")) {
    map.mode = *mapModeFromName(kModes[f.choice("mode", kModes)]);
  }
  if (f.has("ndt")) {
    readNdt(ctx, f.get("ndt"), f.path("ndt"), map.ndt);
  }
  map.hit_probability = f.number("hit_probability", map.hit_probability);
  map.miss_probability = f.number("miss_probability", map.miss_probability);
  map.occupied_threshold = f.number("occupied_threshold", map.occupied_threshold);
  readClamp(f, "clamp_min", map.clamp_min_probability, warnings);
  readClamp(f, "clamp_max", map.clamp_max_probability, warnings);
}

void readBackendOptions(Context& ctx, const YAML::Node& node, BackendOptions& backend,
                        std::vector<std::string>& warnings) {
  Fields f(ctx, node, "backend");
  f.knownKeys({"name", "threads", "fallback", "opencl_platform", "opencl_device", "cuda_device",
               "gpu_cache", "gpu_cache_mb", "gpu_memory", "opencl_span_work", "device_planning"});
  static const std::vector<std::string> kNames = {"cpu", "opencl", "cuda"};
  backend.name = kNames[choiceOr(f, "name", kNames, indexOf(kNames, backend.name))];
  const std::vector<std::string> available = backends::availableBackends();
  if (std::find(available.begin(), available.end(), backend.name) == available.end()) {
    f.check(false, "name",
            "this build has no " + backend.name + " backend (rebuild with it, or use cpu)");
  }
  backend.threads = f.integer<unsigned>("threads", backend.threads, 0u, 256u);
  static const std::vector<std::string> kFallback = {"none", "cpu"};
  backend.fallback_cpu = choiceOr(f, "fallback", kFallback, backend.fallback_cpu ? 1 : 0) == 1;
  backend.opencl_platform = text(f, "opencl_platform", backend.opencl_platform);
  backend.opencl_device = text(f, "opencl_device", backend.opencl_device);
  backend.cuda_device = f.integer<int>("cuda_device", backend.cuda_device, 0, 64);
  readGpuCache(f, backend, warnings);
  static const std::vector<std::string> kMemory = {"auto", "cache", "shared"};
  backend.gpu_memory =
      kMemory[choiceOr(f, "gpu_memory", kMemory, indexOf(kMemory, backend.gpu_memory))];
  static const std::vector<std::string> kSpanWork = {"auto", "span", "region"};
  backend.opencl_span_work = kSpanWork[choiceOr(f, "opencl_span_work", kSpanWork,
                                                indexOf(kSpanWork, backend.opencl_span_work))];
  static const std::vector<std::string> kPlanning = {"host", "device"};
  backend.device_planning = kPlanning[choiceOr(f, "device_planning", kPlanning,
                                               indexOf(kPlanning, backend.device_planning))];
}

Result<MapperConfig> loadMapperConfig(const std::string& path, MapperConfig base,
                                      std::vector<std::string>& warnings) {
  std::ifstream in(path);
  if (!in) {
    return fail(ErrorCode::kIo, path + ": cannot open the configuration file");
  }
  std::ostringstream contents;
  contents << in.rdbuf();
  YAML::Node root;
  try {
    root = YAML::Load(contents.str());
  } catch (const YAML::Exception& e) {
    return fail(ErrorCode::kFormat,
                path + ": line " + std::to_string(e.mark.line + 1) + ": not valid YAML: " + e.msg);
  }
  Context ctx(path);
  if (!root.IsMap()) {
    return fail(ErrorCode::kFormat, path + ": expected a mapping with map: and backend: sections");
  }
  if (root["map"].IsDefined()) {
    readMapOptions(ctx, root["map"], base.map, warnings);
  }
  if (!ctx.failed() && root["backend"].IsDefined()) {
    readBackendOptions(ctx, root["backend"], base.backend, warnings);
  }
  if (ctx.failed()) {
    return Unexpected(ctx.error());
  }
  return base;
}

}  // namespace raymap::mapper
