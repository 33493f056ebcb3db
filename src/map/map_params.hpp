// SPDX-License-Identifier: BSD-3-Clause
// Parameters of a voxel map: geometry, occupancy probabilities and integration semantics.
#pragma once

#include <cmath>
#include <cstdint>
#include <optional>
#include <string_view>

#include "raymap/error.hpp"
#include "raymap/map_types.hpp"

#include "kernels/common/ndt.h"
#include "kernels/common/occupancy.h"
#include "kernels/common/tsdf.h"

namespace raymap {

/// @brief ln(p / (1 - p)).
inline float logOdds(double probability) noexcept {
  return static_cast<float>(std::log(probability / (1.0 - probability)));
}

/// @brief 1 - 1 / (1 + e^l); -inf maps to 0 and +inf to 1.
inline double probability(float log_odds) noexcept {
  return 1.0 - 1.0 / (1.0 + std::exp(static_cast<double>(log_odds)));
}

/// @brief Occupancy update parameters, all in log-odds.
/// Defaults: hit 0.9, miss 0.45, clamps -2.0 / +3.511 log-odds (p = 0.1192 / 0.971, OctoMap's
/// clamps), threshold 0.5. Value type; validated once with validate().
struct OccupancyParams {
  static constexpr double kDefaultHitProbability = 0.9;
  static constexpr double kDefaultMissProbability = 0.45;
  static constexpr float kDefaultClampMin = -2.0f;
  static constexpr float kDefaultClampMax = 3.511f;
  static constexpr double kDefaultThresholdProbability = 0.5;

  float hit = logOdds(kDefaultHitProbability);
  float miss = logOdds(kDefaultMissProbability);
  float clamp_min = kDefaultClampMin;
  float clamp_max = kDefaultClampMax;
  float threshold = logOdds(kDefaultThresholdProbability);

  /// @brief OctoMap's defaults (hit 0.7, miss 0.4, same clamps), for comparisons with OctoMap.
  static OccupancyParams octomap() noexcept {
    OccupancyParams p;
    p.hit = logOdds(0.7);
    p.miss = logOdds(0.4);
    return p;
  }

  /// @brief Checks hit > 0 > miss, clamp_min < threshold <= clamp_max and finiteness.
  Expected<void, Error> validate() const;

  rm_occupancy_params toKernel() const noexcept {
    return rm_occupancy_params{hit, miss, clamp_min, clamp_max, threshold};
  }
  friend bool operator==(const OccupancyParams&, const OccupancyParams&) = default;
};

// MapMode, Semantics: raymap/map_types.hpp (public).
const char* toString(MapMode mode) noexcept;
/// @brief "occupancy", "ndt-om", "ndt-tm", "tsdf" (as the tools spell them).
std::optional<MapMode> mapModeFromName(std::string_view name) noexcept;
inline bool isNdt(MapMode mode) noexcept {
  return mode == MapMode::kNdtOm || mode == MapMode::kNdtTm;
}

/// @brief TSDF parameters (kernels/common/tsdf.h has the rules), metres. Value type; validated
/// with validate(). Unset distances follow the resolution.
struct TsdfParams {
  static constexpr double kDefaultTruncationVoxels = 3.0;
  static constexpr double kDefaultMaxWeight = 1.0e4;  // OHM's and Voxblox's
  static constexpr double kDefaultDropoffVoxels = 1.0;

  /// Truncation distance tau, metres: distances are kept within [-tau, tau], and rays are walked
  /// on tau behind their sample. Unset: 3 voxel edges (tau should span a few voxels so the zero
  /// crossing has a voxel on each side).
  std::optional<double> truncation_m;
  /// Largest voxel weight (rays): a voxel seen by more rays averages over the last ~max_weight.
  double max_weight = kDefaultMaxWeight;
  /// Drop-off distance eps, metres: behind the surface the ray weight falls linearly from 1 at
  /// -eps to 0 at -tau (Voxblox). 0 = constant weight. Unset: 1 voxel edge (Voxblox's choice).
  std::optional<double> dropoff_m;

  double truncationMetres(double resolution) const noexcept {
    return truncation_m.value_or(kDefaultTruncationVoxels * resolution);
  }
  double dropoffMetres(double resolution) const noexcept {
    return dropoff_m.value_or(kDefaultDropoffVoxels * resolution);
  }
  /// @brief Checks tau > 0, 0 <= eps < tau and max_weight > 0; names the parameter at fault.
  Expected<void, Error> validate(double resolution) const;
  rm_tsdf_params toKernel(double resolution) const noexcept;
  friend bool operator==(const TsdfParams&, const TsdfParams&) = default;
};

/// @brief NDT-OM / NDT-TM parameters (kernels/common/ndt.h has the rules), in metres and
/// probabilities. Value type; validated with validate().
struct NdtParams {
  static constexpr double kDefaultSensorNoise = 0.05;  // metres
  static constexpr double kDefaultRegulariser = 0.1;   // voxel edges
  static constexpr std::uint32_t kDefaultSampleThreshold = 4;
  static constexpr double kDefaultReinitProbability = 0.2;
  static constexpr std::uint32_t kDefaultReinitCount = 100;
  static constexpr double kDefaultInitialIntensityVariance = 1.0;
  static constexpr double kAdaptationScale = 2.0;

  /// Range noise of the sensor (sigma), metres.
  double sensor_noise = kDefaultSensorNoise;
  /// Sigma added on every axis where a Gaussian is inverted, as a fraction of the voxel edge
  /// (OHM's seed of 0.1 voxel): a flat surfel stays invertible.
  double regulariser = kDefaultRegulariser;
  /// Samples a voxel needs before its Gaussian shapes the misses; one value on every backend
  /// (OHM used 3 on the CPU and 4 on the GPU). 4: the fewest that can span three dimensions.
  std::uint32_t sample_threshold = kDefaultSampleThreshold;
  /// A voxel whose occupancy probability fell below this, with reinit_count samples, restarts its
  /// Gaussian at the next hit (a transient object has gone).
  double reinit_probability = kDefaultReinitProbability;
  std::uint32_t reinit_count = kDefaultReinitCount;
  /// How strongly a ray through a surfel lowers its occupancy, in [0,1]. Unset: from the miss
  /// probability, alpha = clamp(2 (1 - 2 p_miss), 0, 1) (0.2 for p_miss = 0.45), so a ray straight
  /// through a surfel counts about twice a plain miss.
  std::optional<double> adaptation_rate;
  /// NDT-TM: variance of the intensity after the first sample (sensor intensity units squared).
  double initial_intensity_variance = kDefaultInitialIntensityVariance;

  /// @brief The adaptation rate in effect for a map with these occupancy parameters.
  double adaptationRate(const OccupancyParams& occupancy) const noexcept;
  /// @brief Checks ranges; names the parameter at fault.
  Expected<void, Error> validate() const;
  /// @brief The kernel parameters, in voxel units for a map of `resolution` metres.
  rm_ndt_params toKernel(double resolution, const OccupancyParams& occupancy,
                         MapMode mode) const noexcept;
  friend bool operator==(const NdtParams&, const NdtParams&) = default;
};

const char* toString(Semantics semantics) noexcept;

/// @brief Geometry of the voxel grid.
/// Voxel v covers [v * resolution, (v + 1) * resolution) metres on each axis (world frame); a
/// region is region_voxels^3 voxels.
struct MapGeometry {
  static constexpr double kDefaultResolution = 0.1;  // metres
  static constexpr std::int32_t kDefaultRegionVoxels = 32;
  static constexpr std::int32_t kMinRegionVoxels = 4;
  static constexpr std::int32_t kMaxRegionVoxels = 128;

  double resolution = kDefaultResolution;  ///< voxel edge, metres
  std::int32_t region_voxels = kDefaultRegionVoxels;

  double regionExtent() const noexcept { return resolution * region_voxels; }
  std::uint32_t voxelsPerRegion() const noexcept {
    const auto n = static_cast<std::uint32_t>(region_voxels);
    return n * n * n;
  }
  /// @brief Checks 1 mm <= resolution <= 100 m and region_voxels in [4, 128].
  Expected<void, Error> validate() const;
  friend bool operator==(const MapGeometry&, const MapGeometry&) = default;
};

}  // namespace raymap
