// SPDX-License-Identifier: BSD-3-Clause
// A naive reference for the height-map column search and flood fill, written from the
// specification (kernels/common/heightmap.h, docs/heightmap.md) rather than from the kernel, and a
// randomized test that every generator reproduces it bit for bit on small random maps.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "kernels/common/heightmap.h"
#include "kernels/common/key_math.h"
#include "kernels/common/voxel_mean.h"
#include "src/heightmap/heightmap_plan.hpp"
#include "tests/heightmap/column_map.hpp"
#include "tests/heightmap/heightmap_generators.hpp"

namespace raymap {
namespace {

using heightmap::HeightMap;
using heightmap::HeightmapMode;
using heightmap::HeightmapOptions;
using heightmap::HeightmapPlan;
using test::ColumnMap;

constexpr float kRefNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kRefInf = std::numeric_limits<float>::infinity();

// ---------------------------------------------------------------------------------------------
// The reference.

/// One column of the map as the search may see it: voxel states and means from box_z_min - 1 (the
/// context voxel below the lowest search range) to box_z_max. Anything else counts as unobserved.
struct Column {
  std::int32_t z_first = 0;
  std::vector<VoxelState> state;
  std::vector<rm_voxel_mean> mean;

  VoxelState at(std::int32_t z) const {
    const std::int64_t k = std::int64_t{z} - z_first;
    if (k < 0 || k >= static_cast<std::int64_t>(state.size())) {
      return VoxelState::kUnobserved;
    }
    return state[static_cast<std::size_t>(k)];
  }
  rm_voxel_mean meanAt(std::int32_t z) const {
    return mean[static_cast<std::size_t>(std::int64_t{z} - z_first)];
  }
};

Column readColumn(const VoxelMap& map, const rm_heightmap_params& p, std::int32_t x,
                  std::int32_t y) {
  Column c;
  c.z_first = p.box_z_min - 1;
  for (std::int32_t z = c.z_first; z <= p.box_z_max; ++z) {
    c.state.push_back(map.state({x, y, z}));
    c.mean.push_back(map.mean({x, y, z}));
  }
  return c;
}

struct RefCell {
  float elevation = kRefNaN;
  float clearance = kRefNaN;
  std::uint32_t kind = RM_HM_UNKNOWN;
  std::uint32_t samples = 0;
};

/// The search range of a reference: voxels whose centre lies in [ref - floor, ref + ceiling], in
/// float as the specification computes it (times the inverse resolution), clipped to the box.
std::pair<std::int32_t, std::int32_t> searchRange(const rm_heightmap_params& p, float reference) {
  const float inverse = p.inverse_resolution;
  auto z_lo = static_cast<std::int32_t>(std::floor((reference - p.floor_depth) * inverse + 0.5f));
  auto z_hi =
      static_cast<std::int32_t>(std::floor((reference + p.ceiling_height) * inverse - 0.5f));
  return {std::max(z_lo, p.box_z_min), std::min(z_hi, p.box_z_max)};
}

/// The column search, voxel by voxel: every candidate is listed, then the rule picks one.
RefCell searchColumn(const Column& c, const rm_heightmap_params& p, float reference) {
  RefCell out;
  const auto [z_lo, z_hi] = searchRange(p, reference);
  if (z_lo > z_hi) {
    return out;  // an empty search range: nothing to go on
  }
  const float res = p.resolution;
  const bool virtual_on = (p.flags & RM_HM_FLAG_VIRTUAL) != 0;
  const bool samples_on = (p.flags & RM_HM_FLAG_SAMPLES) != 0;
  const bool mean_on = samples_on && (p.flags & RM_HM_FLAG_MEAN) != 0;
  auto occupied = [&](std::int32_t z) { return c.at(z) == VoxelState::kOccupied; };
  auto freeOverUnobserved = [&](std::int32_t z) {
    return c.at(z) == VoxelState::kFree && c.at(z - 1) == VoxelState::kUnobserved;
  };
  // Distance from a height up to the bottom face of the next occupied voxel above z in the box.
  auto clearanceAbove = [&](std::int32_t z, float height) {
    for (std::int32_t u = z + 1; u <= p.box_z_max; ++u) {
      if (occupied(u)) {
        return static_cast<float>(u) * res - height;
      }
    }
    return kRefInf;
  };
  // The lowest voxel the underside rule may look at (below it, the column counts as unobserved).
  const std::int32_t context = p.box_z_min - 1;

  struct Candidate {
    float height;
    float clearance;
    std::uint32_t kind;
    std::uint32_t samples;
  };
  std::vector<Candidate> candidates;
  for (std::int32_t z = z_lo; z <= z_hi; ++z) {
    // Only the top voxel of a run of occupied voxels is a surface candidate.
    if (occupied(z) && !occupied(z + 1)) {
      std::int32_t bottom = z;
      while (bottom - 1 >= context && occupied(bottom - 1)) {
        --bottom;
      }
      std::int32_t top = z;
      while (occupied(top + 1)) {
        ++top;
      }
      const VoxelState below = bottom - 1 >= context ? c.at(bottom - 1) : VoxelState::kUnobserved;
      const std::int32_t above = top + 1;
      const bool underside = below == VoxelState::kFree && c.at(above) == VoxelState::kUnobserved;
      if (!underside) {
        const rm_voxel_mean m = c.meanAt(z);
        float height = (static_cast<float>(z) + 0.5f) * res;
        if (mean_on && m.count > 0u) {
          height = (static_cast<float>(z) + rm_mean_decode(m.packed, m.count).z) * res;
        }
        const std::uint32_t samples = samples_on ? m.count : 0u;
        candidates.push_back({height, clearanceAbove(z, height), RM_HM_SURFACE, samples});
      }
    }
    if (virtual_on && freeOverUnobserved(z)) {
      // The lowest free-over-unobserved voxel of its gap within the search range (one below
      // z_lo does not count: candidates are voxels of the search range; docs/heightmap.md).
      bool lowest_in_gap = true;
      for (std::int32_t u = z - 1; u >= z_lo && !occupied(u); --u) {
        if (freeOverUnobserved(u)) {
          lowest_in_gap = false;
          break;
        }
      }
      const float height = static_cast<float>(z) * res;
      if (lowest_in_gap && height <= reference + res) {
        candidates.push_back({height, clearanceAbove(z, height), RM_HM_VIRTUAL, 0u});
      }
    }
  }
  const Candidate* best = nullptr;
  for (const Candidate& k : candidates) {
    if (!(k.clearance >= p.min_clearance)) {
      continue;
    }
    if (best == nullptr) {
      best = &k;
      continue;
    }
    const float d = std::fabs(k.height - reference);
    const float best_d = std::fabs(best->height - reference);
    // Nearest; on equal distance a surface beats a virtual surface, then the lower wins (the
    // list is bottom-up, so an equal height keeps the lower voxel).
    if (d < best_d || (d == best_d && k.kind == RM_HM_SURFACE && best->kind == RM_HM_VIRTUAL) ||
        (d == best_d && k.kind == best->kind && k.height < best->height)) {
      best = &k;
    }
  }
  if (best != nullptr) {
    out.elevation = best->height;
    out.clearance = best->clearance;
    out.kind = best->kind;
    out.samples = best->samples;
  } else if (c.at(z_lo) == VoxelState::kFree) {
    out.kind = RM_HM_VACANT;
  }
  return out;
}

bool hasHeight(std::uint32_t kind) { return kind == RM_HM_SURFACE || kind == RM_HM_VIRTUAL; }

/// The whole grid: planar, or flood fill ring by ring from the seed cell.
void referenceMap(const std::vector<Column>& columns, const rm_heightmap_params& p,
                  std::vector<RefCell>& cells, std::vector<float>& references) {
  const std::int32_t nx = p.cells_x;
  const std::int32_t ny = p.cells_y;
  const auto count = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
  cells.assign(count, RefCell{});
  references.assign(count, p.reference_z);
  auto at = [&](std::int32_t i, std::int32_t j) {
    return static_cast<std::size_t>(i) + static_cast<std::size_t>(j) * static_cast<std::size_t>(nx);
  };
  if ((p.flags & RM_HM_FLAG_FILL) == 0) {
    for (std::size_t n = 0; n < count; ++n) {
      cells[n] = searchColumn(columns[n], p, p.reference_z);
    }
    return;
  }
  auto ring = [&](std::int32_t i, std::int32_t j) {
    return std::max(std::abs(i - p.seed_i), std::abs(j - p.seed_j));
  };
  auto sign = [](std::int32_t v) { return v > 0 ? 1 : (v < 0 ? -1 : 0); };
  std::int32_t rings = 0;
  for (std::int32_t j = 0; j < ny; ++j) {
    for (std::int32_t i = 0; i < nx; ++i) {
      rings = std::max(rings, ring(i, j) + 1);
    }
  }
  for (std::int32_t k = 0; k < rings; ++k) {
    for (std::int32_t j = 0; j < ny; ++j) {
      for (std::int32_t i = 0; i < nx; ++i) {
        if (ring(i, j) != k) {
          continue;
        }
        float reference = p.reference_z;
        if (k > 0) {
          const std::int32_t di = i - p.seed_i;
          const std::int32_t dj = j - p.seed_j;
          // The parent: one step toward the seed on each axis at the ring's distance.
          const std::int32_t pi = i - (std::abs(di) == k ? sign(di) : 0);
          const std::int32_t pj = j - (std::abs(dj) == k ? sign(dj) : 0);
          const std::size_t parent = at(pi, pj);
          std::optional<float> chosen;
          if (hasHeight(cells[parent].kind)) {
            chosen = cells[parent].elevation;
          } else if ((std::abs(di) == k) != (std::abs(dj) == k)) {
            // Not a corner: the parent's neighbours along the ring's side, lower index first,
            // when they lie in ring k - 1 and in the grid.
            const bool side_along_i = std::abs(dj) == k;
            for (const std::int32_t s : {-1, 1}) {
              const std::int32_t ni = pi + (side_along_i ? s : 0);
              const std::int32_t nj = pj + (side_along_i ? 0 : s);
              if (ni < 0 || nj < 0 || ni >= nx || nj >= ny || ring(ni, nj) != k - 1) {
                continue;
              }
              if (hasHeight(cells[at(ni, nj)].kind)) {
                chosen = cells[at(ni, nj)].elevation;
                break;
              }
            }
          }
          reference = chosen.value_or(references[parent]);
        }
        references[at(i, j)] = reference;
        cells[at(i, j)] = searchColumn(columns[at(i, j)], p, reference);
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Random maps.

/// What a randomized run asks for.
struct RandomSetup {
  std::uint32_t seed = 0;
  int maps = 0;
  int requests_per_map = 0;
};

/// A small global map filled with random but plausible columns around a centre voxel.
struct RandomScene {
  std::unique_ptr<VoxelMap> map;
  Vec3i centre_voxel{};
  double size = 2.0;
};

using Rng = std::mt19937;

int uniformInt(Rng& rng, int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); }
double uniformReal(Rng& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}
bool chance(Rng& rng, double p) { return std::bernoulli_distribution(p)(rng); }

enum class Fill : std::uint8_t { kUnset, kFree, kOccupied };

/// One column's voxels z0..z1 (index z - z0), from a mix of archetypes: ground, tables and
/// overhangs, ceilings seen from below, ditches, shadows, boxes, random runs, empty and free.
std::vector<Fill> randomColumn(Rng& rng, int z0, int z1, int ground) {
  const int n = z1 - z0 + 1;
  std::vector<Fill> col(static_cast<std::size_t>(n), Fill::kUnset);
  auto set = [&](int z_from, int z_to, Fill f) {
    for (int z = std::max(z_from, z0); z <= std::min(z_to, z1); ++z) {
      col[static_cast<std::size_t>(z - z0)] = f;
    }
  };
  auto groundLayer = [&]() {
    const int below = uniformInt(rng, 0, 9);
    if (below < 2) {
      set(ground - uniformInt(rng, 1, 6), ground - 1, Fill::kOccupied);  // thick ground
    } else if (below < 3) {
      set(ground - uniformInt(rng, 1, 6), ground - 1, Fill::kFree);  // free below: a slab
    }
    const int thick = uniformInt(rng, 1, 2);
    set(ground, ground + thick - 1, Fill::kOccupied);
    return ground + thick;
  };
  const int archetype = uniformInt(rng, 0, 99);
  if (archetype < 28) {  // ground with free space seen above it
    const int top = groundLayer();
    set(top, top + uniformInt(rng, 0, n), Fill::kFree);
  } else if (archetype < 40) {  // a table, an overhang or a platform over the ground
    int z = chance(rng, 0.8) ? groundLayer() : ground;
    const int gap = uniformInt(rng, 1, 14);
    set(z, z + gap - 1, Fill::kFree);
    z += gap;
    const int slab = uniformInt(rng, 1, 3);
    set(z, z + slab - 1, Fill::kOccupied);
    z += slab;
    // Above the slab: seen from above (a platform), free only higher up, or never seen (a
    // ceiling seen from below).
    const int above = uniformInt(rng, 0, 2);
    if (above == 0) {
      set(z, z + uniformInt(rng, 1, n), Fill::kFree);
    } else if (above == 1) {
      set(z + uniformInt(rng, 1, 4), z + uniformInt(rng, 4, 12), Fill::kFree);
    }
  } else if (archetype < 48) {  // a ceiling seen only from below, floor maybe never hit
    if (chance(rng, 0.5)) {
      groundLayer();
    }
    const int ceiling = ground + uniformInt(rng, 2, 16);
    set(ground + 1, ceiling - 1, Fill::kFree);
    set(ceiling, ceiling + uniformInt(rng, 0, 2), Fill::kOccupied);
  } else if (archetype < 58) {  // a ditch or drop-off: free down to a hidden bottom
    const int depth = uniformInt(rng, 1, 10);
    set(ground - depth, z1, Fill::kFree);
    if (chance(rng, 0.4)) {
      set(ground - depth - 1, ground - depth - 1, Fill::kOccupied);  // bottom seen
    }
  } else if (archetype < 65) {  // a shadow: free space seen only from some height up
    set(ground + uniformInt(rng, -3, 12), z1, Fill::kFree);
  } else if (archetype < 72) {  // a box: its top seen, its inside never
    const int height = uniformInt(rng, 1, 10);
    if (chance(rng, 0.5)) {
      groundLayer();
    }
    set(ground + height, ground + height, Fill::kOccupied);
    set(ground + height + 1, ground + height + uniformInt(rng, 1, n), Fill::kFree);
  } else if (archetype < 88) {  // random runs
    int z = z0;
    while (z <= z1) {
      const int len = uniformInt(rng, 1, 6);
      const int s = uniformInt(rng, 0, 2);
      set(z, z + len - 1, s == 0 ? Fill::kUnset : (s == 1 ? Fill::kFree : Fill::kOccupied));
      z += len;
    }
  } else if (archetype < 94) {  // all free: vacant
    set(z0, z1, Fill::kFree);
  }  // else never observed
  // Noise: single voxels of any state.
  for (auto& f : col) {
    if (chance(rng, 0.03)) {
      f = static_cast<Fill>(uniformInt(rng, 0, 2));
    }
  }
  return col;
}

/// Writes one voxel's log-odds and mean straight into the map's layers (as the column tests do).
void writeVoxel(VoxelMap& map, Rng& rng, Vec3i voxel, Fill f) {
  const std::int32_t n = map.geometry().region_voxels;
  auto slot = map.acquireRegion(map.regionOfVoxel(voxel));
  ASSERT_TRUE(slot);
  const rm_u32 index =
      rm_local_index(rm_local_of_voxel(rm_vec3i_make(voxel.x, voxel.y, voxel.z), n), n);
  const OccupancyParams& occ = map.occupancy();
  float value = 0.0f;
  if (f == Fill::kOccupied) {
    const int pick = uniformInt(rng, 0, 19);
    value = pick == 0   ? occ.threshold
            : pick == 1 ? occ.clamp_max
                        : static_cast<float>(uniformReal(rng, static_cast<double>(occ.threshold),
                                                         static_cast<double>(occ.clamp_max)));
  } else {
    value = uniformInt(rng, 0, 19) == 0
                ? occ.clamp_min
                : static_cast<float>(uniformReal(rng, static_cast<double>(occ.clamp_min),
                                                 static_cast<double>(occ.threshold) - 1e-3));
  }
  map.store().layerData<float>(*slot, map.occupancyLayer())[index] = value;
  if (map.meanLayer() < 0) {
    return;
  }
  if (f == Fill::kOccupied || chance(rng, 0.2)) {
    const int zpick = uniformInt(rng, 0, 5);
    const rm_u32 qz =
        zpick == 0 ? 0u : (zpick == 1 ? 1023u : static_cast<rm_u32>(uniformInt(rng, 0, 1023)));
    rm_voxel_mean& m = map.store().layerData<rm_voxel_mean>(*slot, map.meanLayer())[index];
    m.packed = static_cast<rm_u32>(uniformInt(rng, 0, 1023)) |
               (static_cast<rm_u32>(uniformInt(rng, 0, 1023)) << 10) | (qz << 20);
    m.count = chance(rng, 0.15) ? 0u : static_cast<rm_u32>(uniformInt(rng, 1, 40));
  }
}

/// A random map: region size 32, 16, 8 or 24, resolution mostly 0.1 m, a box of 2-3 m (12-30
/// voxels at other resolutions), a terrain (flat, ramp or steps) and random columns over it.
RandomScene randomScene(Rng& rng) {
  RandomScene s;
  MapConfig config;
  config.memory_budget_bytes = std::uint64_t{64} << 20;
  const int region_pick = uniformInt(rng, 0, 9);
  config.geometry.region_voxels =
      region_pick < 4 ? 32 : (region_pick < 6 ? 16 : (region_pick < 8 ? 8 : 24));
  const int res_pick = uniformInt(rng, 0, 9);
  config.geometry.resolution = res_pick < 6 ? 0.1 : (res_pick < 8 ? 0.05 : 0.2);
  config.voxel_mean = !chance(rng, 0.1);
  auto created = VoxelMap::create(config);
  EXPECT_TRUE(created) << created.error().message;
  if (!created) {
    return s;
  }
  s.map = std::make_unique<VoxelMap>(std::move(*created));
  const double res = config.geometry.resolution;
  s.size = res_pick < 6 ? uniformReal(rng, 2.0, 3.0) : res * uniformReal(rng, 12.0, 30.0);
  s.centre_voxel = {uniformInt(rng, -40, 40), uniformInt(rng, -40, 40), uniformInt(rng, -20, 20)};
  const int half = static_cast<int>(std::lround(0.5 * s.size / res));
  const int z0 = s.centre_voxel.z - half - 8;
  const int z1 = s.centre_voxel.z + half + 8;
  // Leave the top of the box unobserved in some maps, and a band of absent regions in others.
  const int z_top = chance(rng, 0.3) ? s.centre_voxel.z + uniformInt(rng, -half, half + 8) : z1;
  const int n = config.geometry.region_voxels;
  const int hole_x =
      chance(rng, 0.2) ? s.centre_voxel.x + uniformInt(rng, -half - n, half) : 1 << 20;
  const int base = s.centre_voxel.z - uniformInt(rng, 0, std::max(1, half / 2));
  const int terrain = uniformInt(rng, 0, 2);
  const int step_every = uniformInt(rng, 1, 4);
  const int step_height = uniformInt(rng, 1, 3);
  const bool along_x = chance(rng, 0.5);
  for (int x = s.centre_voxel.x - half - 2; x <= s.centre_voxel.x + half + 2; ++x) {
    for (int y = s.centre_voxel.y - half - 2; y <= s.centre_voxel.y + half + 2; ++y) {
      const int t = (along_x ? x - s.centre_voxel.x : y - s.centre_voxel.y) + half + 2;
      int ground = base;
      if (terrain == 1) {
        ground += t / step_every;  // a ramp
      } else if (terrain == 2) {
        ground += (t / (3 * step_every)) * step_height;  // steps
      }
      ground += chance(rng, 0.1) ? uniformInt(rng, -1, 1) : 0;
      if (x >= hole_x && x < hole_x + n) {
        continue;
      }
      const std::vector<Fill> col = randomColumn(rng, z0, z1, ground);
      for (int z = z0; z <= z_top; ++z) {
        const Fill f = col[static_cast<std::size_t>(z - z0)];
        if (f != Fill::kUnset) {
          writeVoxel(*s.map, rng, {x, y, z}, f);
        }
      }
    }
  }
  return s;
}

/// A random request around the scene's centre: centre on and off voxel faces, planar or fill,
/// virtual surfaces and voxel means on or off, random limits.
HeightmapOptions randomRequest(Rng& rng, const RandomScene& s) {
  const double res = s.map->geometry().resolution;
  auto coordinate = [&](int voxel) {
    const int pick = uniformInt(rng, 0, 3);
    const double f = pick == 0 ? 0.0 : (pick == 1 ? 0.5 : uniformReal(rng, 0.0, 1.0));
    return (voxel + f) * res;
  };
  HeightmapOptions o;
  o.centre = {coordinate(s.centre_voxel.x), coordinate(s.centre_voxel.y),
              coordinate(s.centre_voxel.z + uniformInt(rng, -4, 4))};
  o.size = s.size;
  o.mode = chance(rng, 0.5) ? HeightmapMode::kFill : HeightmapMode::kPlanar;
  o.virtual_surfaces = chance(rng, 0.5);
  o.use_voxel_mean = !chance(rng, 0.25);
  const int clearance_pick = uniformInt(rng, 0, 9);
  o.min_clearance = clearance_pick == 0  ? 0.0
                    : clearance_pick < 4 ? std::min(1.0, res * uniformInt(rng, 1, 10))
                                         : uniformReal(rng, 0.0, 1.0);
  auto limit = [&]() -> std::optional<double> {
    const int pick = uniformInt(rng, 0, 2);
    if (pick == 0) {
      return std::nullopt;  // size / 2
    }
    return pick == 1 ? res * uniformInt(rng, 0, 15) : uniformReal(rng, 0.0, 1.5);
  };
  o.floor_depth = limit();
  o.ceiling_height = limit();
  return o;
}

// ---------------------------------------------------------------------------------------------
// Comparison.

bool sameFloat(float a, float b) {
  return (std::isnan(a) && std::isnan(b)) ||
         std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b);
}

std::string describeFloat(float v) {
  char text[64];
  std::snprintf(text, sizeof text, "%.9g (0x%08x)", static_cast<double>(v),
                std::bit_cast<std::uint32_t>(v));
  return text;
}

std::string describeOptions(const HeightmapOptions& o) {
  std::ostringstream s;
  s.precision(17);
  s << "centre=(" << o.centre.x << ", " << o.centre.y << ", " << o.centre.z << ") size=" << o.size
    << " mode=" << heightmap::toString(o.mode) << " min_clearance=" << o.min_clearance
    << " floor=" << (o.floor_depth ? std::to_string(*o.floor_depth) : std::string("default"))
    << " ceiling="
    << (o.ceiling_height ? std::to_string(*o.ceiling_height) : std::string("default"))
    << " virtual=" << o.virtual_surfaces << " use_voxel_mean=" << o.use_voxel_mean;
  return s.str();
}

std::string describeColumn(const Column& c, const rm_heightmap_params& p, float reference) {
  const auto [z_lo, z_hi] = searchRange(p, reference);
  std::ostringstream s;
  s << "  column (z from top; box z " << p.box_z_min << ".." << p.box_z_max << ", search " << z_lo
    << ".." << z_hi << ", res " << describeFloat(p.resolution) << "):\n";
  for (std::int32_t z = p.box_z_max; z >= c.z_first; --z) {
    const VoxelState st = c.at(z);
    const rm_voxel_mean m = c.meanAt(z);
    s << "    z " << z << ": "
      << (st == VoxelState::kOccupied ? "occupied" : (st == VoxelState::kFree ? "free" : "-"));
    if (st == VoxelState::kOccupied) {
      s << " mean_z " << describeFloat(rm_mean_decode(m.packed, m.count).z) << " count " << m.count;
    }
    s << (z == z_lo ? "  <- z_lo" : "") << (z == z_hi ? "  <- z_hi" : "") << "\n";
  }
  return s.str();
}

std::string describeCell(const char* who, float elevation, float clearance, std::uint32_t kind,
                         std::uint32_t samples, float reference) {
  std::ostringstream s;
  s << "  " << who << ": kind " << kind << " elevation " << describeFloat(elevation)
    << " clearance " << describeFloat(clearance) << " samples " << samples << " reference "
    << describeFloat(reference) << "\n";
  return s.str();
}

/// Per-kind cell counts over a run, to show what the random maps exercised.
struct Coverage {
  std::size_t requests = 0;
  std::size_t fill_requests = 0;
  std::size_t cells = 0;
  std::size_t kinds[4] = {0, 0, 0, 0};
};

/// Generates every request of `setup` with `generator` and compares each cell with the
/// reference. Stops at the first mismatch, with the column, the request and both answers.
void runRandomized(heightmap::HeightmapGenerator& generator, const RandomSetup& setup,
                   Coverage& coverage) {
  Rng rng(setup.seed);
  HeightmapPlan plan;
  HeightMap out;
  std::vector<Column> columns;
  std::vector<RefCell> expected;
  std::vector<float> references;
  std::vector<std::size_t> order;
  for (int map_index = 0; map_index < setup.maps; ++map_index) {
    const RandomScene scene = randomScene(rng);
    ASSERT_NE(scene.map, nullptr);
    for (int request = 0; request < setup.requests_per_map; ++request) {
      const HeightmapOptions o = randomRequest(rng, scene);
      // The centre's region must be stored for the centre to lie inside a global map.
      ASSERT_TRUE(scene.map->acquireRegion(scene.map->regionOfVoxel(scene.map->voxelOf(o.centre))));
      auto planned = heightmap::planHeightmap(*scene.map, o, plan);
      ASSERT_TRUE(planned) << planned.error().message << "\n" << describeOptions(o);
      const rm_heightmap_params& p = plan.params;
      // The seed is the centre's column.
      ASSERT_EQ(p.voxel_x0 - p.seed_i, scene.map->voxelOf(o.centre).x);
      ASSERT_EQ(p.voxel_y0 - p.seed_j, scene.map->voxelOf(o.centre).y);
      auto generated = generator.generate(*scene.map, plan, out);
      ASSERT_TRUE(generated) << generated.error().message;
      ASSERT_EQ(out.cells_x, p.cells_x);
      ASSERT_EQ(out.cells_y, p.cells_y);

      columns.clear();
      for (std::int32_t j = 0; j < p.cells_y; ++j) {
        for (std::int32_t i = 0; i < p.cells_x; ++i) {
          columns.push_back(readColumn(*scene.map, p, p.voxel_x0 - i, p.voxel_y0 - j));
        }
      }
      referenceMap(columns, p, expected, references);
      ++coverage.requests;
      coverage.fill_requests += o.mode == HeightmapMode::kFill ? 1 : 0;
      // Cells in ring order from the seed, so that in fill mode the first mismatch reported is
      // where the answers part, not a cell that inherited a different reference.
      order.resize(expected.size());
      for (std::size_t n = 0; n < order.size(); ++n) {
        order[n] = n;
      }
      auto ring = [&](std::size_t n) {
        const auto i = static_cast<std::int32_t>(n % static_cast<std::size_t>(p.cells_x));
        const auto j = static_cast<std::int32_t>(n / static_cast<std::size_t>(p.cells_x));
        return std::max(std::abs(i - p.seed_i), std::abs(j - p.seed_j));
      };
      std::stable_sort(order.begin(), order.end(),
                       [&](std::size_t a, std::size_t b) { return ring(a) < ring(b); });
      for (const std::size_t n : order) {
        const RefCell& e = expected[n];
        const bool same = out.kind[n] == e.kind && sameFloat(out.elevation[n], e.elevation) &&
                          sameFloat(out.clearance[n], e.clearance) &&
                          out.observed_count[n] == e.samples &&
                          sameFloat(out.reference[n], references[n]);
        if (!same) {
          const auto i = static_cast<std::int32_t>(n % static_cast<std::size_t>(p.cells_x));
          const auto j = static_cast<std::int32_t>(n / static_cast<std::size_t>(p.cells_x));
          FAIL() << generator.name() << " differs from the reference: seed " << setup.seed
                 << ", map " << map_index << ", request " << request << ", cell (" << i << ", " << j
                 << ") = voxel column (" << p.voxel_x0 - i << ", " << p.voxel_y0 - j
                 << "), seed cell (" << p.seed_i << ", " << p.seed_j << ")\n  "
                 << describeOptions(o) << "\n  region_voxels " << p.region_voxels << " floor "
                 << describeFloat(p.floor_depth) << " ceiling " << describeFloat(p.ceiling_height)
                 << " min_clearance " << describeFloat(p.min_clearance) << " flags " << p.flags
                 << "\n"
                 << describeCell("reference", e.elevation, e.clearance, e.kind, e.samples,
                                 references[n])
                 << describeCell(generator.name(), out.elevation[n], out.clearance[n], out.kind[n],
                                 out.observed_count[n], out.reference[n])
                 << describeColumn(columns[n], p, references[n]);
        }
        ++coverage.cells;
        ++coverage.kinds[std::min<std::uint32_t>(e.kind, 3u)];
      }
    }
  }
}

/// The generated cell of voxel column (0, 0).
RefCell generateColumn(heightmap::HeightmapGenerator& generator, VoxelMap& map,
                       const HeightmapOptions& o) {
  HeightmapPlan plan;
  auto planned = heightmap::planHeightmap(map, o, plan);
  EXPECT_TRUE(planned) << planned.error().message;
  HeightMap out;
  auto generated = generator.generate(map, plan, out);
  EXPECT_TRUE(generated) << generated.error().message;
  int i = 0;
  int j = 0;
  EXPECT_TRUE(out.cellOf(0.05, 0.05, &i, &j));
  const std::size_t n = out.index(i, j);
  return {out.elevation[n], out.clearance[n], out.kind[n], out.observed_count[n]};
}

HeightmapOptions columnRequest(double reference_z) {
  HeightmapOptions o;
  o.centre = {0.05, 0.05, reference_z};
  o.size = 2.0;
  return o;
}

class HeightmapReference : public ::testing::TestWithParam<std::string> {};

TEST_P(HeightmapReference, RandomMapsMatchTheReferenceExactly) {
  REQUIRE_HEIGHTMAP_GENERATOR(GetParam(), generator);
  // The device generators cost more per map (uploads, one launch per fill ring): fewer maps.
  const bool device = GetParam() != "cpu";
  const RandomSetup setup{20240611u, device ? 200 : 300, 3};
  Coverage coverage;
  runRandomized(*generator, setup, coverage);
  std::printf(
      "[ reference ] %s: %zu requests (%zu fill), %zu cells: %zu unknown, %zu surface, "
      "%zu virtual, %zu vacant\n",
      GetParam().c_str(), coverage.requests, coverage.fill_requests, coverage.cells,
      coverage.kinds[0], coverage.kinds[1], coverage.kinds[2], coverage.kinds[3]);
}

// A ceiling two voxels thick seen only from below (free under it, never seen above): with
// min_clearance 0 its lower voxel must not become a surface (only a run's top is a candidate,
// and this run is an underside).
TEST_P(HeightmapReference, NoVoxelOfACeilingSeenFromBelowIsASurface) {
  REQUIRE_HEIGHTMAP_GENERATOR(GetParam(), generator);
  ColumnMap m;
  m.freeRange(0, 0, 2, 23);  // the floor was never hit
  m.set(0, 0, 24, ColumnMap::kOccupied, 0.9f, 3);
  m.set(0, 0, 25, ColumnMap::kOccupied, 0.1f, 3);  // nothing seen above
  HeightmapOptions o = columnRequest(0.0);
  o.size = 6.0;  // the box reaches 3 m up
  o.min_clearance = 0.0;
  const RefCell c = generateColumn(*generator, m.map(), o);
  EXPECT_EQ(c.kind, RM_HM_UNKNOWN) << "elevation " << c.elevation << " clearance " << c.clearance;
  EXPECT_TRUE(std::isnan(c.elevation));
}

// The same ceiling, three voxels thick (z 4..6 over free z 0..3, nothing seen above), is no
// surface wherever the search range starts: the run's own voxel below decides.
TEST_P(HeightmapReference, ACeilingIsNoSurfaceWhereverTheSearchRangeStarts) {
  REQUIRE_HEIGHTMAP_GENERATOR(GetParam(), generator);
  ColumnMap m;
  m.freeRange(0, 0, 0, 3);
  m.occupied(0, 0, 4);
  m.occupied(0, 0, 5);
  m.occupied(0, 0, 6);
  HeightmapOptions o = columnRequest(0.52);
  o.floor_depth = 0.15;  // z_lo = floor(0.37 / 0.1 + 0.5) = 4
  RefCell c = generateColumn(*generator, m.map(), o);
  EXPECT_EQ(c.kind, RM_HM_UNKNOWN) << "z_lo 4: elevation " << c.elevation;
  o.floor_depth = 0.05;  // z_lo = floor(0.47 / 0.1 + 0.5) = 5
  c = generateColumn(*generator, m.map(), o);
  EXPECT_EQ(c.kind, RM_HM_UNKNOWN) << "z_lo 5: elevation " << c.elevation;
}

// observed_count is the surface voxel's sample count whenever the map has the mean layer, also
// when heights come from voxel centres.
TEST_P(HeightmapReference, ObservedCountIsTheSurfaceSamplesWithoutVoxelMean) {
  REQUIRE_HEIGHTMAP_GENERATOR(GetParam(), generator);
  ColumnMap m;
  m.set(0, 0, -1, ColumnMap::kOccupied, 0.9f, 3);
  m.freeRange(0, 0, 0, 9);
  HeightmapOptions o = columnRequest(0.0);
  o.use_voxel_mean = false;
  const RefCell c = generateColumn(*generator, m.map(), o);
  EXPECT_EQ(c.kind, RM_HM_SURFACE);
  EXPECT_NEAR(c.elevation, -0.05, 1e-6);  // the voxel centre
  EXPECT_EQ(c.samples, 3u);
}

INSTANTIATE_TEST_SUITE_P(Generators, HeightmapReference,
                         ::testing::ValuesIn(test::heightmapGeneratorNames()),
                         [](const ::testing::TestParamInfo<std::string>& param_info) {
                           return param_info.param;
                         });

}  // namespace
}  // namespace raymap
