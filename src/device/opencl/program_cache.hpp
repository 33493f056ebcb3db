// SPDX-License-Identifier: BSD-3-Clause
// Building OpenCL programs, with the device binaries cached on disk so that a restart (a service
// restarted by systemd, the next offline run) does not compile again.
#pragma once

#include <string>
#include <string_view>

#include "raymap/error.hpp"

#include "src/device/opencl/cl_runtime.hpp"

namespace raymap::opencl {

/// @brief Where and whether program binaries are cached.
struct ProgramCacheOptions {
  /// Directory for cached binaries. Empty: $RAYMAP_CACHE_DIR/opencl, else
  /// $XDG_CACHE_HOME/raymap/opencl, else $HOME/.cache/raymap/opencl; if none can be created the
  /// program is simply built every time (a warning goes to `warning`).
  std::string directory;
  bool enabled = true;
};

/// @brief How a program was obtained (for logs, stats and tests).
struct BuiltProgram {
  ProgramHandle program;
  bool from_cache = false;  ///< loaded from a cached binary
  std::string cache_path;   ///< file used or written ("" when caching is off or unavailable)
  std::string warning;      ///< non-fatal problem (cache not writable, stale binary rebuilt)
};

/// @brief Builds `source` with `options` for the context's device. The cache key is a 64-bit hash
/// of the source, the options, the platform name and version, the device name and the driver
/// version; a cached binary that fails to load or build is ignored and replaced. Binaries are
/// written to a temporary file and renamed. A build failure returns kUnsupported with the
/// compiler's build log in the message.
Result<BuiltProgram> buildProgram(const DeviceContext& ctx, std::string_view source,
                                  const std::string& options, const ProgramCacheOptions& cache);

}  // namespace raymap::opencl
