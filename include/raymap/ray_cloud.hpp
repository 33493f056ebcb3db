// SPDX-License-Identifier: BSD-3-Clause
// The names of raymap 0.1 for reading recordings (raymap/recording.hpp): a RayCloudReader is a
// RecordingReader, which reads bags too.
#pragma once

#include "raymap/recording.hpp"

namespace raymap {

using RayCloudOptions = RecordingOptions;
using RayCloudReader = RecordingReader;

}  // namespace raymap
