// SPDX-License-Identifier: BSD-3-Clause
// Configuration keys in the library's messages, shown as the command line's flags.
#include "tools/raymap/option_names.hpp"

#include <array>
#include <cctype>

namespace raymap::cli {
namespace {

// Keys as the library's messages write them: raymapd's YAML key where raymapd has the option,
// else the library option struct's field (src/, include/raymap/). A row with a value
// ("map.tiers: false") is for a flag that stands for a key and a value. map.mode names how a map
// was built, in the messages of commands that read one (export): populate's --mode.
constexpr std::array kOptionFlags{
    OptionFlag{"heightmap.centre", "--center", ""},
    OptionFlag{"heightmap.size", "--size", ""},
    OptionFlag{"heightmap.min_clearance", "--min-clearance", ""},
    OptionFlag{"heightmap.floor_depth", "--floor", ""},
    OptionFlag{"heightmap.ceiling_height", "--ceiling", ""},
    OptionFlag{"map.mode", "populate --mode", "occupancy ndt-om ndt-tm decay tsdf"},
    OptionFlag{"map.decay_rate: true", "--decay-rate", ""},
    OptionFlag{"map.decay_rate", "--decay-rate", ""},
    OptionFlag{"map.region_voxels", "--region-voxels", ""},
    OptionFlag{"map.semantics", "--semantics", "ray scan"},
    OptionFlag{"map.hit_probability", "--hit", ""},
    OptionFlag{"map.miss_probability", "--miss", ""},
    OptionFlag{"map.voxel_mean: true", "without --no-mean", ""},
    OptionFlag{"map.ndt.sensor_noise", "--ndt-sensor-noise", ""},
    OptionFlag{"map.ndt.regulariser", "--ndt-regulariser", ""},
    OptionFlag{"map.ndt.sample_threshold", "--ndt-sample-threshold", ""},
    OptionFlag{"map.ndt.reinit_probability", "--ndt-reinit-probability", ""},
    OptionFlag{"map.ndt.reinit_count", "--ndt-reinit-count", ""},
    OptionFlag{"map.ndt.adaptation_rate", "--ndt-adaptation-rate", ""},
    OptionFlag{"map.ndt.initial_intensity_variance", "--ndt-initial-intensity-variance", ""},
    OptionFlag{"map.tsdf.truncation", "--tsdf-truncation", ""},
    OptionFlag{"map.tsdf.max_weight", "--tsdf-max-weight", ""},
    OptionFlag{"map.tsdf.dropoff", "--tsdf-dropoff", ""},
    OptionFlag{"map.clamp_min_probability", "--clamp-min", ""},
    OptionFlag{"map.clamp_max_probability", "--clamp-max", ""},
    OptionFlag{"map.occupied_threshold", "--threshold", ""},
    OptionFlag{"map.max_memory", "--max-memory", ""},
    OptionFlag{"map.compressed_memory", "--compressed-memory", ""},
    OptionFlag{"map.spill_dir", "--spill-dir", ""},
    OptionFlag{"map.tiers: false", "--no-tiers", ""},
    OptionFlag{"rays.min_range", "--min-range", ""},
    OptionFlag{"rays.max_range", "--max-range", ""},
    OptionFlag{"rays.max_ray_length", "--max-ray-length", ""},
    OptionFlag{"rays.segment_length", "--segment-length", ""},
    OptionFlag{"queues.batch_rays", "--batch-rays", ""},
    OptionFlag{"backend.name", "--backend", "cpu opencl cuda"},
    OptionFlag{"backend.fallback", "--fallback", "none cpu"},
    OptionFlag{"backend.device_planning", "--device-planning", "host device"},
    OptionFlag{"backend.gpu_memory", "--gpu-memory", "auto cache shared"},
    OptionFlag{"backend.gpu_cache", "--gpu-cache", ""},
    OptionFlag{"backend.cuda_device", "--cuda-device", ""},
    OptionFlag{"bag.topic", "--topic", ""},
    OptionFlag{"bag.camera_info_topic", "--camera-info-topic", ""},
    OptionFlag{"bag.pose_topic", "--pose-topic", ""},
    OptionFlag{"bag.pose_source", "--pose-source", "auto odometry tf"},
    OptionFlag{"bag.sensor_offset", "--sensor-offset", ""},
    OptionFlag{"bag.base_frame", "--base-frame", ""},
    OptionFlag{"bag.invalid_as_free", "--invalid-as-free", ""},
    OptionFlag{"bag.max_range", "--max-range", ""},
    OptionFlag{"source.trajectory", "--trajectory", ""},
    OptionFlag{"export.mode", "--mode", "occupied free mean decay ndt ndt-points tsdf tsdf-mesh"},
    OptionFlag{"export.sigmas", "--sigmas", ""},
    OptionFlag{"export.min_axis", "--min-axis", ""},
    OptionFlag{"export.min_weight", "--min-weight", ""},
    OptionFlag{"export.threshold", "--threshold", ""},
    OptionFlag{"export.colour", "--colour", "height intensity permeability"},
    OptionFlag{"replay.rate", "--rate", "max"},
    OptionFlag{"replay.skip_damaged", "--skip-damaged", ""},
    OptionFlag{"replay.include_outputs", "--include-outputs", ""},
    OptionFlag{"record.format", "--format", "rmlog mcap"},
    OptionFlag{"record.compression", "--compression", ""},
};

bool isWordChar(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '-';
}

/// Where a key or a value starting at `at` may end: not inside a longer word ("heightmap.sizes",
/// "heightmap.size.x"); a full stop that ends a sentence is fine.
bool endsWord(std::string_view text, std::size_t at) {
  if (at >= text.size()) {
    return true;
  }
  if (text[at] == '.') {
    return at + 1 >= text.size() || !isWordChar(text[at + 1]);
  }
  return !isWordChar(text[at]);
}

/// Where a key may start: not inside a longer word or key ("xheightmap.size", "a.map.mode"), nor
/// inside a path (".../heightmap.size").
bool startsWord(std::string_view text, std::size_t at) {
  if (at == 0) {
    return true;
  }
  const char before = text[at - 1];
  return !isWordChar(before) && before != '.' && before != '/';
}

/// A number at `at`: "500", "-1.5", ".5", "1,2,3", "nan", "-inf" (what printf writes).
bool numberAt(std::string_view text, std::size_t at) {
  std::string_view rest = text.substr(at);
  if (!rest.empty() && (rest[0] == '-' || rest[0] == '+')) {
    rest.remove_prefix(1);
  }
  if (rest.starts_with("nan") || rest.starts_with("inf")) {
    return endsWord(rest, 3);
  }
  const auto digit = [](char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; };
  return (!rest.empty() && digit(rest[0])) || (rest.size() > 1 && rest[0] == '.' && digit(rest[1]));
}

/// One of `values` (space-separated words) at `at`, as a whole word.
bool valueAt(std::string_view text, std::size_t at, std::string_view values) {
  while (!values.empty()) {
    const std::size_t space = values.find(' ');
    const std::string_view word = values.substr(0, space);
    if (text.substr(at).starts_with(word) && endsWord(text, at + word.size())) {
      return true;
    }
    values = space == std::string_view::npos ? std::string_view() : values.substr(space + 1);
  }
  return false;
}

/// Whether the word at `at` follows "line N: ", as a configuration file's errors name their keys
/// ("robot.yaml: line 3: map.semantics: ..."): that is the file's key, not an option to show as
/// a flag.
bool afterFileLine(std::string_view text, std::size_t at) {
  std::string_view before = text.substr(0, at);
  if (!before.ends_with(": ")) {
    return false;
  }
  before.remove_suffix(2);
  std::size_t digits = 0;
  while (digits < before.size() &&
         std::isdigit(static_cast<unsigned char>(before[before.size() - 1 - digits])) != 0) {
    ++digits;
  }
  before.remove_suffix(digits);
  return digits > 0 && before.ends_with("line ");
}

/// The longest row whose key is the whole word at `at`, or nullptr.
const OptionFlag* rowAt(std::string_view text, std::size_t at) {
  const OptionFlag* found = nullptr;
  for (const OptionFlag& row : kOptionFlags) {
    if (text.substr(at).starts_with(row.key) && endsWord(text, at + row.key.size()) &&
        (found == nullptr || row.key.size() > found->key.size())) {
      found = &row;
    }
  }
  return found;
}

}  // namespace

std::span<const OptionFlag> optionFlags() noexcept { return kOptionFlags; }

std::string withCliFlags(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  std::size_t at = 0;
  while (at < text.size()) {
    const OptionFlag* row =
        startsWord(text, at) && !afterFileLine(text, at) ? rowAt(text, at) : nullptr;
    if (row == nullptr) {
      out += text[at++];
      continue;
    }
    out += row->flag;
    at += row->key.size();
    // "key: VALUE" -> "--flag VALUE"; "key: prose" keeps its colon.
    const bool keyed_value = row->key.find(':') == std::string_view::npos &&
                             text.substr(at).starts_with(": ") &&
                             (numberAt(text, at + 2) || valueAt(text, at + 2, row->values));
    if (keyed_value) {
      out += ' ';
      at += 2;
    }
  }
  return out;
}

}  // namespace raymap::cli
