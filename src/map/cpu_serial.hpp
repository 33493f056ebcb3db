// SPDX-License-Identifier: BSD-3-Clause
// The single-threaded reference integrator of the CPU backend.
#pragma once

#include <span>

#include "raymap/expected.hpp"

#include "src/map/backend.hpp"
#include "src/map/cpu_voxel_ops.hpp"

namespace raymap::detail {

/// @brief Integrates a batch ray by ray and, within a ray, region span by region span, creating
/// regions as they are reached. Stops at the first region the store cannot create (kStoreFull;
/// the batch is then partly integrated). @rt allocates: no.
Expected<void, IntegrateError> integrateSerial(const IntegrationContext& ctx,
                                               std::span<const PreparedRay> rays,
                                               RegionSlotCache& cache, WorkerStats& stats) noexcept;

}  // namespace raymap::detail
