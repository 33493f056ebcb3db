// SPDX-License-Identifier: BSD-3-Clause
// The subcommands of `raymap`. Each registers itself on the app and sets *exit_code when it runs.
#pragma once

#include <cstdint>
#include <string>

#include "raymap/error.hpp"
#include <CLI/CLI.hpp>

namespace raymap::cli {

/// Exit codes of the raymap program.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;  ///< bad input, unwritable output, full store, ...
inline constexpr int kExitUsage = 2;    ///< unknown option, bad option value

void addPopulateCommand(CLI::App& app, int* exit_code);
void addInfoCommand(CLI::App& app, int* exit_code);
void addExportCommand(CLI::App& app, int* exit_code);
/// `raymap heightmap`: the 2.5D height map of a map file (PNG, CSV).
void addHeightmapCommand(CLI::App& app, int* exit_code);
void addBenchCommand(CLI::App& app, int* exit_code);
void addDemoCommand(CLI::App& app, int* exit_code);
/// `raymap simulate`: a lidar recording and the true height field of a scene file.
void addSimulateCommand(CLI::App& app, int* exit_code);
/// Present in every build; lists OpenCL and CUDA devices, says why an API has none, and exits 1
/// only when neither has a device.
void addDevicesCommand(CLI::App& app, int* exit_code);
/// `raymap topics`: the DDS/ROS 2 topics seen on a domain (built-in discovery topics).
void addTopicsCommand(CLI::App& app, int* exit_code);
/// `raymap echo TOPIC`: the messages of one topic of a known type, human-readable or JSON Lines.
void addEchoCommand(CLI::App& app, int* exit_code);

/// `raymap replay`: recorded data published over DDS like a live robot's sensors.
void addReplayCommand(CLI::App& app, int* exit_code);
/// `raymap record`: DDS topics recorded as raw CDR into a log.
void addRecordCommand(CLI::App& app, int* exit_code);
/// `raymap security`: SROS2 keystores, enclaves and permissions for DDS Security.
void addSecurityCommand(CLI::App& app, int* exit_code);

/// @brief The exit code for an error of io::StagedOutputs::add(): kExitUsage for a conflict
/// between the arguments (an output that is an input), kExitFailure otherwise.
inline int exitCodeFor(const Error& error) noexcept {
  return error.code == ErrorCode::kInvalidArgument ? kExitUsage : kExitFailure;
}

/// @brief Prints "raymap <command>: error: <message>" on stderr.
void printError(const std::string& command, const std::string& message);

/// @brief 1234567 -> "1,234,567".
std::string withCommas(std::uint64_t value);

/// @brief For an error that is damage (a corrupt record, a file cut off) in a command reading
/// bags: " (--skip-damaged ...)", the way to read what they hold; else empty.
std::string bagDamageHint(bool reads_bags, const Error& error);

}  // namespace raymap::cli
