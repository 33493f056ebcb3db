// SPDX-License-Identifier: BSD-3-Clause
// unambiguousTruth: the scene's surface sampled across a cell and its neighbours.
#include "tests/support/scene_truth.hpp"

#include <cmath>
#include <utility>

namespace raymap::test {

std::optional<sim::TrueSurface> unambiguousTruth(const sim::Scene& scene, Vec3d c,
                                                 double resolution, double reference,
                                                 double min_clearance) {
  const auto truth = sim::trueSurface(scene, c.x, c.y, reference, min_clearance);
  if (!truth) {
    return std::nullopt;
  }
  const double r = resolution;
  for (const auto& [dx, dy] : {std::pair{-1.0, -1.0},
                               {-1.0, 0.0},
                               {-1.0, 1.0},
                               {0.0, -1.0},
                               {0.0, 1.0},
                               {1.0, -1.0},
                               {1.0, 0.0},
                               {1.0, 1.0},
                               {-0.49, -0.49},
                               {-0.49, 0.49},
                               {0.49, -0.49},
                               {0.49, 0.49}}) {
    const auto other =
        sim::trueSurface(scene, c.x + dx * r, c.y + dy * r, reference, min_clearance);
    if (!other || std::abs(other->height - truth->height) > 0.25 * r ||
        std::isinf(other->clearance) != std::isinf(truth->clearance) ||
        (!std::isinf(truth->clearance) &&
         std::abs(other->clearance - truth->clearance) > 0.25 * r)) {
      return std::nullopt;
    }
  }
  return truth;
}

}  // namespace raymap::test
