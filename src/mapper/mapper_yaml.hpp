// SPDX-License-Identifier: BSD-3-Clause
// The `map:` and `backend:` sections of a YAML configuration as the library's MapOptions and
// BackendOptions: one reading of raymapd's names, used by raymapd and by `raymap populate
// --config` (a file written for raymapd configures populate too). Start-up code only.
#pragma once

#include <string>
#include <vector>

#include "raymap/error.hpp"
#include "raymap/mapper_config.hpp"

#include "src/config/yaml_reader.hpp"

namespace raymap::mapper {

/// @brief Reads the `map:` section at `node` into `map`: keys present replace the values `map`
/// holds (so a caller's defaults stand for absent keys). Errors go to `ctx` (file, line, key);
/// older spellings are read and described in `warnings`. `window` and `save_on_exit` are
/// raymapd's (a rolling window, the file to save at exit): accepted, and left to the caller.
void readMapOptions(config::Context& ctx, const YAML::Node& node, MapOptions& map,
                    std::vector<std::string>& warnings);

/// @brief Reads the `backend:` section at `node` into `backend`, as readMapOptions does.
void readBackendOptions(config::Context& ctx, const YAML::Node& node, BackendOptions& backend,
                        std::vector<std::string>& warnings);

/// @brief The `map:` and `backend:` sections of the YAML file at `path` (other sections, such as
/// raymapd's sensors and pose, are not read), applied over `base`. Errors name the file, line,
/// key and reason; combinations are not checked here (toMapConfig does).
Result<MapperConfig> loadMapperConfig(const std::string& path, MapperConfig base,
                                      std::vector<std::string>& warnings);

}  // namespace raymap::mapper
