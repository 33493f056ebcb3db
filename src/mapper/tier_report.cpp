// SPDX-License-Identifier: BSD-3-Clause
// Tier reports of a job (see tier_report.hpp).
#include "src/mapper/tier_report.hpp"

namespace raymap::mapper {

std::optional<TierReport> tierReport(const VoxelMap& map) {
  const auto stats = map.tierStats();
  if (!stats) {
    return std::nullopt;
  }
  return TierReport{map.store().capacity(), map.store().size(), *stats};
}

Expected<void, Error> checkTiers(const VoxelMap& map) {
  if (auto failure = map.tierFailure()) {
    return Unexpected(*failure);
  }
  return {};
}

}  // namespace raymap::mapper
