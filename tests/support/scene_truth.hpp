// SPDX-License-Identifier: BSD-3-Clause
// Ground truth of a simulated scene for height-map cells, shared by the height-map and raymapd
// tests.
#pragma once

#include <optional>

#include "src/core/vec3.hpp"
#include "src/sim/scene.hpp"

namespace raymap::test {

/// @brief The true surface of the cell centred on `centre` (x, y; world frame, metres) with edge
/// `resolution`, when it is unambiguous: the same surface (height within a quarter voxel, so
/// ramps count) at the cell's centre, its corners and the centres of its 8 neighbours. Cells at
/// object edges are left out: lidar noise puts an object's side into the next column.
std::optional<sim::TrueSurface> unambiguousTruth(const sim::Scene& scene, Vec3d centre,
                                                 double resolution, double reference,
                                                 double min_clearance);

}  // namespace raymap::test
