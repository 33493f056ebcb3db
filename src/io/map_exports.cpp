// SPDX-License-Identifier: BSD-3-Clause
// One call for every export (see map_exports.hpp).
#include "src/io/map_exports.hpp"

#include <array>
#include <cmath>
#include <utility>

#include "src/io/map_export.hpp"
#include "src/io/ndt_export.hpp"
#include "src/io/tsdf_export.hpp"

namespace raymap::io {
namespace {

NdtColour toNdtColour(ExportColour colour) noexcept {
  switch (colour) {
    case ExportColour::kIntensity:
      return NdtColour::kIntensity;
    case ExportColour::kPermeability:
      return NdtColour::kPermeability;
    case ExportColour::kHeight:
      break;
  }
  return NdtColour::kHeight;
}

}  // namespace
}  // namespace raymap::io

namespace raymap {
namespace {

constexpr std::array<std::pair<ExportKind, std::string_view>, 8> kKindNames{{
    {ExportKind::kOccupied, "occupied"},
    {ExportKind::kFree, "free"},
    {ExportKind::kMean, "mean"},
    {ExportKind::kDecay, "decay"},
    {ExportKind::kNdt, "ndt"},
    {ExportKind::kNdtPoints, "ndt-points"},
    {ExportKind::kTsdf, "tsdf"},
    {ExportKind::kTsdfMesh, "tsdf-mesh"},
}};

}  // namespace

std::string_view toString(ExportKind kind) noexcept {
  for (const auto& [k, name] : kKindNames) {
    if (k == kind) {
      return name;
    }
  }
  return "unknown";
}

std::optional<ExportKind> exportKindFromName(std::string_view name) noexcept {
  for (const auto& [kind, k_name] : kKindNames) {
    if (k_name == name) {
      return kind;
    }
  }
  return std::nullopt;
}

std::string_view toString(ExportColour colour) noexcept {
  return io::toString(io::toNdtColour(colour));  // the names of `raymap export --colour`
}

std::optional<ExportColour> exportColourFromName(std::string_view name) noexcept {
  for (const ExportColour colour :
       {ExportColour::kHeight, ExportColour::kIntensity, ExportColour::kPermeability}) {
    if (toString(colour) == name) {
      return colour;
    }
  }
  return std::nullopt;
}

}  // namespace raymap

namespace raymap::io {
namespace {

bool isNdt(ExportKind kind) { return kind == ExportKind::kNdt || kind == ExportKind::kNdtPoints; }
bool isTsdf(ExportKind kind) { return kind == ExportKind::kTsdf || kind == ExportKind::kTsdfMesh; }

Error onlyFor(std::string_view key, std::string_view modes) {
  return Error{ErrorCode::kInvalidArgument,
               std::string(key) + " applies only to export.mode " + std::string(modes)};
}

/// The first option set that `kind` does not take, by key; empty when none.
std::string_view optionNotFor(const ExportRequest& r) {
  if (r.decay_threshold && r.kind != ExportKind::kDecay) {
    return "export.threshold";
  }
  if (r.ndt_sigmas && !isNdt(r.kind)) {
    return "export.sigmas";
  }
  if (r.ndt_min_axis && !isNdt(r.kind)) {
    return "export.min_axis";
  }
  if (r.ndt_colour && !isNdt(r.kind)) {
    return "export.colour";
  }
  if (r.tsdf_min_weight && !isTsdf(r.kind)) {
    return "export.min_weight";
  }
  return {};
}

NdtExportOptions ndtOptions(const ExportRequest& r) {
  NdtExportOptions options;
  options.sigmas = r.ndt_sigmas.value_or(NdtExportOptions::kDefaultSigmas);
  options.min_axis_m = r.ndt_min_axis;
  options.colour = toNdtColour(r.ndt_colour.value_or(ExportColour::kHeight));
  return options;
}

Result<ExportCounts> counted(Result<std::uint64_t> items) {
  if (!items) {
    return Unexpected(items.error());
  }
  return ExportCounts{*items, 0};
}

}  // namespace

Expected<void, Error> validateExportRequest(const ExportRequest& r) {
  if (const std::string_view key = optionNotFor(r); !key.empty()) {
    if (isTsdf(r.kind)) {
      return fail(ErrorCode::kInvalidArgument,
                  std::string(key) + " does not apply to export.mode " +
                      std::string(toString(r.kind)) + " (its option is export.min_weight)");
    }
    if (key == "export.threshold") {
      return Unexpected(onlyFor(key, "decay"));
    }
    if (key == "export.min_weight") {
      return Unexpected(onlyFor(key, "tsdf or tsdf-mesh"));
    }
    return Unexpected(onlyFor(key, "ndt or ndt-points"));
  }
  if (r.decay_threshold && (!std::isfinite(*r.decay_threshold) || *r.decay_threshold < 0.0)) {
    return fail(ErrorCode::kInvalidArgument,
                "export.threshold: must be a finite rate >= 0 (reflections per metre)");
  }
  if (r.tsdf_min_weight && (!std::isfinite(*r.tsdf_min_weight) || *r.tsdf_min_weight < 0.0)) {
    return fail(ErrorCode::kInvalidArgument,
                "export.min_weight: must be a finite weight >= 0 (rays)");
  }
  if (isNdt(r.kind)) {
    return ndtOptions(r).validate();
  }
  return {};
}

Result<ExportCounts> exportMap(const VoxelMap& map, const ExportRequest& r,
                               const std::string& path) {
  if (auto ok = validateExportRequest(r); !ok) {
    return Unexpected(ok.error());
  }
  switch (r.kind) {
    case ExportKind::kNdt:
      return counted(exportNdtEllipsoids(map, ndtOptions(r), path));
    case ExportKind::kNdtPoints:
      return counted(exportNdtPoints(map, ndtOptions(r), path));
    case ExportKind::kTsdf:
      return counted(
          exportTsdfSurface(map, path, r.tsdf_min_weight.value_or(kDefaultTsdfMinWeight)));
    case ExportKind::kTsdfMesh: {
      auto mesh = exportTsdfMesh(map, path, r.tsdf_min_weight.value_or(kDefaultTsdfMinWeight));
      if (!mesh) {
        return Unexpected(mesh.error());
      }
      return ExportCounts{mesh->triangles, mesh->vertices};
    }
    case ExportKind::kOccupied:
    case ExportKind::kFree:
    case ExportKind::kMean:
    case ExportKind::kDecay:
      break;
  }
  static constexpr std::array<ExportMode, 4> kVoxelModes{ExportMode::kOccupied, ExportMode::kFree,
                                                         ExportMode::kMean, ExportMode::kDecay};
  ExportOptions options;
  options.decay_threshold = r.decay_threshold.value_or(0.0);
  return counted(exportPly(map, kVoxelModes[static_cast<std::size_t>(r.kind)], path, options));
}

}  // namespace raymap::io
