// SPDX-License-Identifier: BSD-3-Clause
// Two map files that must hold the same map: what `raymap populate` wrote and what the library
// (raymap::Mapper) saved from the same input and options.
#pragma once

#include <string>

#include "raymap/mapper_config.hpp"
#include "raymap/recording.hpp"

namespace raymap::test {

/// @brief Expects (gtest) the same mode, parameters and regions, and the same bytes in every
/// layer of every region; the files' provenance (source, created_by) may differ.
void expectSameMap(const std::string& cli, const std::string& library);

/// What the library's half of such a test read.
struct LibraryRun {
  RecordingReport report;  ///< a bag's counts (zero for a file)
  bool bag = false;        ///< the input was read as a bag
};

/// How mapWithLibrary reads a recording.
enum class ReadAs : bool {
  kScans,   ///< RecordingReader::nextScan: world rays, Mapper::integrate(rays)
  kClouds,  ///< RecordingReader::nextCloud: sensor-frame points, integrate(points, poses)
};

/// @brief Maps `input` scan by scan (or cloud by cloud) with raymap::RecordingReader and
/// raymap::Mapper (`config`) and saves the map to `out`; a failure is a fatal gtest failure
/// (ASSERT_NO_FATAL_FAILURE).
void mapWithLibrary(const std::string& input, const RecordingOptions& read,
                    const MapperConfig& config, const std::string& out, LibraryRun* run = nullptr,
                    ReadAs read_as = ReadAs::kScans);

}  // namespace raymap::test
