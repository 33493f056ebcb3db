// SPDX-License-Identifier: BSD-3-Clause
// Height maps as files: a PNG a person can look at and a CSV for machines.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "raymap/error.hpp"

#include "src/heightmap/height_map.hpp"

namespace raymap::io {

/// @brief Writes one line per cell, in storage order (index i + j * cells_x), after the header
/// `x,y,elevation,clearance,kind`. x, y: the cell centre (world frame, metres, `%.4f`);
/// elevation, clearance: metres, `%.4f`, or `nan` / `inf`; kind: `surface`, `virtual`, `vacant`
/// or `unknown`. When the map has normals (map.has_normals) three more columns follow,
/// `normal_x,normal_y,normal_z` (unit vector, world frame, `%.4f` or `nan`). Written through a
/// temporary file and rename.
/// @return nothing, or an Error naming the path (kInvalidArgument when the layers do not hold
/// cells_x * cells_y cells, kIo when the file cannot be written).
Expected<void, Error> writeHeightmapCsv(const std::string& path, const heightmap::HeightMap& map);

/// An 8-bit sRGB colour.
struct Rgb {
  std::uint8_t r = 0;
  std::uint8_t g = 0;
  std::uint8_t b = 0;
  friend bool operator==(const Rgb&, const Rgb&) = default;
};

/// Colours of the height-map image other than the elevation scale. None of them is on the scale
/// (the scale has no greys and no magenta).
inline constexpr Rgb kHeightmapBackground{255, 255, 255};  ///< outside the map and the legend
inline constexpr Rgb kHeightmapInk{0, 0, 0};               ///< text, frames, scale bar, arrows
inline constexpr Rgb kVacantColour{200, 200, 200};         ///< light grey
inline constexpr Rgb kUnknownColour{40, 40, 40};           ///< near-black grey
inline constexpr Rgb kVirtualHatchColour{255, 0, 255};     ///< magenta diagonal stripes

/// @brief The elevation colour scale: a viridis-like ramp from dark purple (0) through blue and
/// green to yellow (1), perceptually ordered by lightness. Piecewise linear between 9 control
/// colours. @param[in] t position on the scale, clamped to [0, 1] (NaN gives the low end).
Rgb elevationColour(double t) noexcept;

/// @brief How a height map is drawn. Aggregate; checked by layoutHeightmapImage().
struct HeightmapImageOptions {
  static constexpr int kDefaultCellPixels = 0;  ///< choose automatically
  static constexpr int kMaxCellPixels = 256;
  /// Pixels per cell edge. 0: the smallest integer that makes the map part at least
  /// kAutoMinMapPixels wide, reduced so that neither side exceeds kAutoMaxMapPixels (1 when the map
  /// has more cells than that).
  int cell_pixels = kDefaultCellPixels;
  /// Elevation at the low / high end of the colour scale, metres; nullopt: the lowest / highest
  /// elevation of the surface cells (of the virtual cells when there is no surface). Elevations
  /// outside are clamped.
  std::optional<double> elevation_min_m;
  std::optional<double> elevation_max_m;
};

inline constexpr int kAutoMinMapPixels = 400;
inline constexpr int kAutoMaxMapPixels = 1600;
/// Largest map part accepted per side, pixels (with an explicit cell_pixels).
inline constexpr int kMaxMapPixels = 16384;

/// @brief Where things lie in the image renderHeightmap() draws. Pixel coordinates: x right,
/// y down, (0, 0) the top-left pixel.
struct HeightmapImageLayout {
  int width = 0;  ///< whole image, pixels
  int height = 0;
  int cell_pixels = 1;  ///< edge of the square block each cell is drawn as
  /// Top-left pixel of the map part. Cell (i, j) covers the block whose top-left pixel is
  /// (map_x + (cells_x - 1 - i) * cell_pixels, map_y + j * cell_pixels): world +x to the right,
  /// +y up, so cell (0, 0) (the +x/+y corner) is the top-right block.
  int map_x = 0;
  int map_y = 0;
  double elevation_min_m = 0.0;  ///< elevation drawn as elevationColour(0)
  double elevation_max_m = 1.0;  ///< elevation drawn as elevationColour(1)
};

/// @brief Checks a map and options and lays out the image: the layers must hold cells_x *
/// cells_y cells (at least one), cell_pixels must be 0 to kMaxCellPixels, fixed elevation limits
/// finite with min < max, and the map part at most kMaxMapPixels per side.
/// When the elevation range is empty (one height, or no surface at all) it is widened to 1 m.
/// @return the layout, or an Error (kInvalidArgument) naming the field and the reason.
Result<HeightmapImageLayout> layoutHeightmapImage(const heightmap::HeightMap& map,
                                                  const HeightmapImageOptions& options = {});

/// An 8-bit RGB image: rows top to bottom, pixels left to right, 3 bytes per pixel.
struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;
  /// @pre 0 <= x < width, 0 <= y < height.
  Rgb at(int x, int y) const noexcept;
};

/// @brief Draws a height map seen from above (+x right, +y up), one square block of pixels per
/// cell, with a legend to its right.
///
/// Cells: surface cells in elevationColour() of their elevation over the layout's range;
/// virtual cells the same with kVirtualHatchColour diagonal stripes (continuous across
/// neighbouring virtual cells); vacant cells kVacantColour; unknown cells (and cells whose
/// elevation is not finite) kUnknownColour. The map is framed in kHeightmapInk; below it a scale
/// bar (a 1, 2 or 5 x 10^k metre length near a fifth of the map width, labelled e.g. "5 m").
/// Legend: "elevation (m)" over a vertical colour bar (high at the top) with 5 tick labels,
/// swatches labelled "virtual", "vacant", "unknown", and axis arrows "x" (right) and "y" (up).
/// Cost: O(pixels).
/// @pre layoutHeightmapImage(map, options) succeeds (aborts otherwise).
RgbImage renderHeightmap(const heightmap::HeightMap& map,
                         const HeightmapImageOptions& options = {});

/// @brief renderHeightmap() written as a PNG through a temporary file and rename.
/// @return nothing, or an Error naming the path (the checks of layoutHeightmapImage(), kIo when
/// the file cannot be written).
Expected<void, Error> writeHeightmapPng(const std::string& path, const heightmap::HeightMap& map,
                                        const HeightmapImageOptions& options = {});

}  // namespace raymap::io
