// SPDX-License-Identifier: BSD-3-Clause
// `raymap populate`'s use of the library's mapping job (src/mapper/integration_job.hpp): the
// progress bar and the statistics JSON.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "raymap/error.hpp"
#include "raymap/recording.hpp"

#include "src/device/backend_choice.hpp"
#include "src/map/voxel_map.hpp"
#include "src/mapper/integration_job.hpp"
#include "tools/raymap/json_output.hpp"
#include "tools/raymap/memory_tiers.hpp"

namespace raymap::cli {

// Backend creation is shared with raymapd (src/device/backend_choice.hpp).
using backends::availableBackends;
using backends::BackendChoice;
using backends::createBackend;
using backends::CreatedBackend;
using backends::CreatedHeightmapGenerator;
using backends::createHeightmapGenerator;

/// @brief Everything `raymap populate` needs besides output paths: the library job's options
/// (filter, backend, batch size) and the input.
struct PopulateOptions : mapper::IntegrationOptions {
  std::string input;
  RecordingOptions recording;  ///< how the input is read (a PLY, or a rosbag2 bag)
  MapConfig map;
  bool progress = true;  ///< progress bar on a terminal
};

using PopulateReport = mapper::IntegrationReport;
using StreamState = mapper::IntegrationSession;
using mapper::inputWarning;

/// @brief mapper::integrateRays with a progress bar on a terminal (options.progress) that shows
/// the tiers' pool once they move regions.
Result<PopulateReport> integrateStream(VoxelMap& map, const PopulateOptions& options,
                                       const mapper::RayChunkReader& next_chunk,
                                       const std::function<double()>& fraction,
                                       StreamState* reuse = nullptr);

/// @brief mapper::integrateRecording of options.input with the progress bar, recorded as made
/// by `raymap populate`.
Result<PopulateReport> populateFromFile(VoxelMap& map, const PopulateOptions& options);

/// @brief The statistics JSON of a run (keys documented in docs/cli.md).
Json statsJson(const PopulateReport& report, const PopulateOptions& options);

}  // namespace raymap::cli
