// SPDX-License-Identifier: BSD-3-Clause
// Height-map CSV and image: cell colours, a legend drawn with a built-in 5x7 bitmap font, PNG.
#include "src/io/heightmap_export.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string_view>

#include "raymap/assert.hpp"

#include "src/io/atomic_file.hpp"
#include "src/io/png_writer.hpp"

namespace raymap::io {
namespace {

using heightmap::CellKind;
using heightmap::HeightMap;

// ---------------------------------------------------------------------------------------------
// CSV

constexpr std::size_t kCsvFlushBytes = std::size_t{1} << 20;

void appendNumber(std::string& out, double value) {
  if (std::isnan(value)) {
    out += "nan";  // printf would write "-nan" for a NaN with its sign bit set
    return;
  }
  if (std::isinf(value)) {
    out += value > 0.0 ? "inf" : "-inf";
    return;
  }
  if (std::fabs(value) < 0.00005) {
    value = 0.0;  // no "-0.0000"
  }
  std::array<char, 48> text{};
  const int n = std::snprintf(text.data(), text.size(), "%.4f", value);
  out.append(text.data(),
             static_cast<std::size_t>(std::clamp(n, 0, static_cast<int>(text.size()) - 1)));
}

Expected<void, Error> checkLayers(const std::string& path, const HeightMap& map) {
  if (map.cells_x < 0 || map.cells_y < 0) {
    return fail(ErrorCode::kInvalidArgument, "cannot write '" + path + "': the height map is " +
                                                 std::to_string(map.cells_x) + " x " +
                                                 std::to_string(map.cells_y) + " cells");
  }
  const std::size_t n = map.cellCount();
  if (map.elevation.size() != n || map.clearance.size() != n || map.kind.size() != n) {
    return fail(ErrorCode::kInvalidArgument,
                "cannot write '" + path + "': the height map's layers hold " +
                    std::to_string(map.elevation.size()) + " / " +
                    std::to_string(map.clearance.size()) + " / " + std::to_string(map.kind.size()) +
                    " cells (elevation / clearance / kind), expected " + std::to_string(n));
  }
  if (map.has_normals &&
      (map.normal_x.size() != n || map.normal_y.size() != n || map.normal_z.size() != n)) {
    return fail(ErrorCode::kInvalidArgument,
                "cannot write '" + path + "': the height map's normal layers hold " +
                    std::to_string(map.normal_x.size()) + " cells, expected " + std::to_string(n));
  }
  return {};
}

// ---------------------------------------------------------------------------------------------
// Colours

// Control colours of the elevation scale at t = 0, 1/8, ..., 1: a viridis-like ramp (dark purple,
// indigo, blue, teal, green, lime, yellow) with lightness rising monotonically, so the order of
// heights reads without the legend and survives greyscale printing.
constexpr std::array<Rgb, 9> kScale{{
    {68, 1, 84},
    {71, 44, 122},
    {59, 81, 139},
    {44, 113, 142},
    {33, 144, 141},
    {39, 173, 129},
    {92, 200, 99},
    {170, 220, 50},
    {253, 231, 37},
}};

// Virtual cells: stripes along the anti-diagonal, kHatchWidth of every kHatchPeriod pixels.
constexpr int kHatchPeriod = 6;
constexpr int kHatchWidth = 2;

bool hatched(int x, int y) { return (x + y) % kHatchPeriod < kHatchWidth; }

// ---------------------------------------------------------------------------------------------
// Bitmap font: 5x7 glyphs, one byte per row, bit 4 the leftmost column. Only the characters the
// legend uses (digits, signs, and the letters of its labels); others draw as a hollow box.

struct Glyph {
  char c;
  std::array<std::uint8_t, 7> rows;
};

constexpr std::array<Glyph, 32> kFont{{
    {' ', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}},
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}},
    {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}},
    {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}},
    {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}},
    {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}},
    {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}},
    {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
    {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},
    {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {'a', {0x00, 0x00, 0x0E, 0x01, 0x0F, 0x11, 0x0F}},
    {'c', {0x00, 0x00, 0x0E, 0x10, 0x10, 0x11, 0x0E}},
    {'e', {0x00, 0x00, 0x0E, 0x11, 0x1F, 0x10, 0x0E}},
    {'i', {0x04, 0x00, 0x0C, 0x04, 0x04, 0x04, 0x0E}},
    {'k', {0x10, 0x10, 0x12, 0x14, 0x18, 0x14, 0x12}},
    {'l', {0x0C, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'m', {0x00, 0x00, 0x1A, 0x15, 0x15, 0x11, 0x11}},
    {'n', {0x00, 0x00, 0x16, 0x19, 0x11, 0x11, 0x11}},
    {'o', {0x00, 0x00, 0x0E, 0x11, 0x11, 0x11, 0x0E}},
    {'r', {0x00, 0x00, 0x16, 0x19, 0x10, 0x10, 0x10}},
    {'t', {0x08, 0x08, 0x1C, 0x08, 0x08, 0x09, 0x06}},
    {'u', {0x00, 0x00, 0x11, 0x11, 0x11, 0x13, 0x0D}},
    {'v', {0x00, 0x00, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'w', {0x00, 0x00, 0x11, 0x11, 0x15, 0x15, 0x0A}},
    {'x', {0x00, 0x00, 0x11, 0x0A, 0x04, 0x0A, 0x11}},
    {'y', {0x00, 0x00, 0x11, 0x11, 0x0F, 0x01, 0x0E}},
}};
constexpr std::array<std::uint8_t, 7> kMissingGlyph{0x1F, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1F};

constexpr int kFontScale = 2;                 // each font pixel is 2 x 2 image pixels
constexpr int kTextHeight = 7 * kFontScale;   // pixels
constexpr int kTextAdvance = 6 * kFontScale;  // glyph plus one column of spacing

const std::array<std::uint8_t, 7>& glyphRows(char c) {
  for (const Glyph& glyph : kFont) {
    if (glyph.c == c) {
      return glyph.rows;
    }
  }
  return kMissingGlyph;
}

int textWidth(std::string_view text) {
  return text.empty() ? 0 : static_cast<int>(text.size()) * kTextAdvance - kFontScale;
}

// ---------------------------------------------------------------------------------------------
// Layout

constexpr int kMargin = 16;        // around everything
constexpr int kLegendGap = 28;     // between the map column and the legend
constexpr int kScaleBarGap = 10;   // between the map and the scale bar
constexpr int kScaleBarThick = 4;  // bar height
constexpr int kScaleBarTick = 10;  // end ticks' height
constexpr int kLabelGap = 6;       // between a graphic and its text
constexpr int kBarWidth = 20;      // colour bar
constexpr int kBarHeight = 201;    // colour bar (odd: the 5 ticks fall on whole pixels)
constexpr int kTickLength = 5;
constexpr int kTickCount = 5;
constexpr int kSwatch = 20;  // swatch edge
constexpr int kSwatchPitch = 30;
constexpr int kSectionGap = 24;  // between legend sections
constexpr int kArrowLength = 44;
constexpr int kArrowHead = 6;
constexpr std::string_view kLegendTitle = "elevation (m)";
constexpr std::array<std::string_view, 3> kSwatchLabels{"virtual", "vacant", "unknown"};

/// Everything renderHeightmap() places; the public layout plus the legend's geometry and text.
struct Plan {
  HeightmapImageLayout layout;
  int map_width = 0;  // pixels
  int map_height = 0;
  int scale_bar_pixels = 0;
  std::string scale_label;
  std::array<std::string, kTickCount> tick_labels;
  int legend_x = 0;
  int bar_y = 0;
  int swatch_y = 0;
  int axes_y = 0;  // top of the axis hint
};

std::string formatTick(double value, int decimals) {
  if (std::fabs(value) < 0.5 * std::pow(10.0, -decimals)) {
    value = 0.0;  // no "-0.00"
  }
  std::array<char, 48> text{};
  const int n = std::snprintf(text.data(), text.size(), "%.*f", decimals, value);
  return std::string(text.data(),
                     static_cast<std::size_t>(std::clamp(n, 0, static_cast<int>(text.size()) - 1)));
}

/// A round length (1, 2 or 5 x 10^k metres): the largest not over a fifth of the map width, made
/// longer if that would draw shorter than a few pixels.
double scaleBarLength(double map_width_m, double pixels_per_m) {
  const double target = map_width_m / 5.0;
  double decade = std::pow(10.0, std::floor(std::log10(target)));
  double length = decade;
  for (const double step : {2.0, 5.0}) {
    if (step * decade <= target * (1.0 + 1e-9)) {
      length = step * decade;
    }
  }
  constexpr double kMinPixels = 4.0;
  int guard = 0;
  while (length * pixels_per_m < kMinPixels && guard++ < 64) {
    const double mantissa = length / decade;
    if (mantissa < 1.5) {
      length = 2.0 * decade;
    } else if (mantissa < 3.5) {
      length = 5.0 * decade;
    } else {
      decade *= 10.0;
      length = decade;
    }
  }
  return length;
}

/// The map's layers and the options, each checked by name.
Expected<void, Error> checkImageInput(const HeightMap& map, const HeightmapImageOptions& options) {
  const std::string what = "height-map image: ";
  if (map.cells_x < 1 || map.cells_y < 1) {
    return fail(ErrorCode::kInvalidArgument, what + "the map is " + std::to_string(map.cells_x) +
                                                 " x " + std::to_string(map.cells_y) +
                                                 " cells (need at least one)");
  }
  const std::size_t n = map.cellCount();
  if (map.elevation.size() != n || map.kind.size() != n) {
    return fail(ErrorCode::kInvalidArgument, what + "the elevation and kind layers hold " +
                                                 std::to_string(map.elevation.size()) + " and " +
                                                 std::to_string(map.kind.size()) +
                                                 " cells, expected " + std::to_string(n));
  }
  if (!(map.resolution > 0.0) || !std::isfinite(map.resolution)) {
    return fail(ErrorCode::kInvalidArgument,
                what + "resolution " + std::to_string(map.resolution) + " is not positive");
  }
  if (options.cell_pixels < 0 || options.cell_pixels > HeightmapImageOptions::kMaxCellPixels) {
    return fail(ErrorCode::kInvalidArgument,
                what + "cell_pixels " + std::to_string(options.cell_pixels) + " is outside 0 to " +
                    std::to_string(HeightmapImageOptions::kMaxCellPixels));
  }
  for (const auto& [name, limit] : {std::pair{"elevation_min_m", options.elevation_min_m},
                                    std::pair{"elevation_max_m", options.elevation_max_m}}) {
    if (limit.has_value() && !std::isfinite(*limit)) {
      return fail(ErrorCode::kInvalidArgument, what + name + " is not finite");
    }
  }
  if (options.elevation_min_m.has_value() && options.elevation_max_m.has_value() &&
      !(*options.elevation_min_m < *options.elevation_max_m)) {
    return fail(ErrorCode::kInvalidArgument,
                what + "elevation_min_m " + std::to_string(*options.elevation_min_m) +
                    " is not below elevation_max_m " + std::to_string(*options.elevation_max_m));
  }
  return {};
}

/// The colour scale's range: fixed by the options, else the surface cells' heights (virtual
/// cells are clamped into it: a deep drop seen from above would otherwise squash the scale),
/// else the virtual cells'; a metre at least.
std::pair<double, double> elevationRange(const HeightMap& map,
                                         const HeightmapImageOptions& options) {
  const std::size_t n = map.cellCount();
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  for (const CellKind ranged : {CellKind::kSurface, CellKind::kVirtualSurface}) {
    if (lo <= hi) {
      break;
    }
    for (std::size_t k = 0; k < n; ++k) {
      const double z = static_cast<double>(map.elevation[k]);
      if (static_cast<CellKind>(map.kind[k]) == ranged && std::isfinite(z)) {
        lo = std::min(lo, z);
        hi = std::max(hi, z);
      }
    }
  }
  if (!(lo <= hi)) {
    lo = map.reference_z;  // nothing observed: centre an arbitrary metre on the reference
    hi = map.reference_z;
  }
  const bool fixed_min = options.elevation_min_m.has_value();
  const bool fixed_max = options.elevation_max_m.has_value();
  lo = options.elevation_min_m.value_or(lo);
  hi = options.elevation_max_m.value_or(hi);
  if (!(hi > lo)) {
    if (fixed_min && !fixed_max) {
      hi = lo + 1.0;
    } else if (fixed_max && !fixed_min) {
      lo = hi - 1.0;
    } else {
      const double mid = lo;
      lo = mid - 0.5;
      hi = mid + 0.5;
    }
  }
  return {lo, hi};
}

/// The tick labels of the colour bar; returns the widest one's width in pixels.
int labelTicks(Plan& plan) {
  const double lo = plan.layout.elevation_min_m;
  const double step = (plan.layout.elevation_max_m - lo) / (kTickCount - 1);
  const int decimals = std::clamp(static_cast<int>(std::ceil(-std::log10(step))) + 1, 2, 6);
  int tick_width = 0;
  for (int k = 0; k < kTickCount; ++k) {
    plan.tick_labels[static_cast<std::size_t>(k)] = formatTick(lo + k * step, decimals);
    tick_width = std::max(tick_width, textWidth(plan.tick_labels[static_cast<std::size_t>(k)]));
  }
  return tick_width;
}

/// The scale bar under the map: a round length and its label.
void planScaleBar(const HeightMap& map, Plan& plan) {
  const double pixels_per_m = plan.layout.cell_pixels / map.resolution;
  const double bar_m = scaleBarLength(map.cells_x * map.resolution, pixels_per_m);
  plan.scale_bar_pixels = std::max(1, static_cast<int>(std::lround(bar_m * pixels_per_m)));
  std::array<char, 48> text{};
  const int written = std::snprintf(text.data(), text.size(), "%g m", bar_m);
  plan.scale_label.assign(text.data(), static_cast<std::size_t>(std::clamp(
                                           written, 0, static_cast<int>(text.size()) - 1)));
}

/// Where everything goes: the map column (the map, the scale bar and its label under it) and the
/// legend beside it (title, colour bar with ticks, swatches, axis hint).
void placeColumns(Plan& plan, int tick_width) {
  HeightmapImageLayout& layout = plan.layout;
  layout.map_x = kMargin;
  layout.map_y = kMargin;
  const int column_width =
      std::max({plan.map_width, plan.scale_bar_pixels + 1, textWidth(plan.scale_label)});
  const int column_height =
      plan.map_height + kScaleBarGap + kScaleBarTick + kLabelGap + kTextHeight;
  plan.legend_x = kMargin + column_width + kLegendGap;
  plan.bar_y = kMargin + kTextHeight + kLabelGap + kTextHeight / 2;
  plan.swatch_y = plan.bar_y + kBarHeight + kTextHeight / 2 + kSectionGap;
  plan.axes_y = plan.swatch_y + static_cast<int>(kSwatchLabels.size()) * kSwatchPitch + kSectionGap;
  const int legend_bottom = plan.axes_y + kTextHeight + kArrowLength;
  int legend_width =
      std::max(textWidth(kLegendTitle), kBarWidth + kTickLength + kLabelGap + tick_width);
  for (const std::string_view label : kSwatchLabels) {
    legend_width = std::max(legend_width, kSwatch + kLabelGap + textWidth(label));
  }
  legend_width = std::max(legend_width, kArrowLength + kLabelGap + textWidth("x") + kArrowHead);
  layout.width = plan.legend_x + legend_width + kMargin;
  layout.height = std::max(kMargin + column_height, legend_bottom) + kMargin;
}

Result<Plan> makePlan(const HeightMap& map, const HeightmapImageOptions& options) {
  if (auto ok = checkImageInput(map, options); !ok) {
    return Unexpected(ok.error());
  }
  Plan plan;
  HeightmapImageLayout& layout = plan.layout;
  const int longest = std::max(map.cells_x, map.cells_y);
  if (options.cell_pixels > 0) {
    layout.cell_pixels = options.cell_pixels;
  } else {
    const int grow = (kAutoMinMapPixels + map.cells_x - 1) / map.cells_x;
    layout.cell_pixels = std::max(1, std::min(grow, kAutoMaxMapPixels / longest));
  }
  if (static_cast<long long>(longest) * layout.cell_pixels > kMaxMapPixels) {
    return fail(ErrorCode::kInvalidArgument,
                "height-map image: " + std::to_string(map.cells_x) + " x " +
                    std::to_string(map.cells_y) + " cells at " +
                    std::to_string(layout.cell_pixels) + " pixels each exceed " +
                    std::to_string(kMaxMapPixels) + " pixels per side");
  }
  plan.map_width = map.cells_x * layout.cell_pixels;
  plan.map_height = map.cells_y * layout.cell_pixels;
  const auto [lo, hi] = elevationRange(map, options);
  layout.elevation_min_m = lo;
  layout.elevation_max_m = hi;
  const int tick_width = labelTicks(plan);
  planScaleBar(map, plan);
  placeColumns(plan, tick_width);
  return plan;
}

// ---------------------------------------------------------------------------------------------
// Drawing

class Canvas {
 public:
  explicit Canvas(RgbImage& image) : image_(image) {}

  void set(int x, int y, Rgb colour) {
    if (x < 0 || y < 0 || x >= image_.width || y >= image_.height) {
      return;
    }
    const std::size_t at = (static_cast<std::size_t>(y) * static_cast<std::size_t>(image_.width) +
                            static_cast<std::size_t>(x)) *
                           3;
    image_.rgb[at] = colour.r;
    image_.rgb[at + 1] = colour.g;
    image_.rgb[at + 2] = colour.b;
  }
  void fill(int x0, int y0, int w, int h, Rgb colour) {
    for (int y = y0; y < y0 + h; ++y) {
      for (int x = x0; x < x0 + w; ++x) {
        set(x, y, colour);
      }
    }
  }
  /// A one-pixel frame drawn just outside the w x h rectangle at (x0, y0).
  void frame(int x0, int y0, int w, int h, Rgb colour) {
    fill(x0 - 1, y0 - 1, w + 2, 1, colour);
    fill(x0 - 1, y0 + h, w + 2, 1, colour);
    fill(x0 - 1, y0, 1, h, colour);
    fill(x0 + w, y0, 1, h, colour);
  }
  /// Text with its top-left corner at (x, y).
  void text(int x, int y, std::string_view text, Rgb colour) {
    for (const char c : text) {
      const auto& rows = glyphRows(c);
      for (int row = 0; row < 7; ++row) {
        for (int col = 0; col < 5; ++col) {
          if (((rows[static_cast<std::size_t>(row)] >> (4 - col)) & 1) != 0) {
            fill(x + col * kFontScale, y + row * kFontScale, kFontScale, kFontScale, colour);
          }
        }
      }
      x += kTextAdvance;
    }
  }
  /// The virtual-cell look over a block: `base` with the hatch on image-fixed diagonals.
  void hatchedBlock(int x0, int y0, int w, int h, Rgb base) {
    for (int y = y0; y < y0 + h; ++y) {
      for (int x = x0; x < x0 + w; ++x) {
        set(x, y, hatched(x, y) ? kVirtualHatchColour : base);
      }
    }
  }

 private:
  RgbImage& image_;
};

Rgb cellColour(CellKind kind, float elevation, const HeightmapImageLayout& layout) {
  const double z = static_cast<double>(elevation);
  if ((kind != CellKind::kSurface && kind != CellKind::kVirtualSurface) || !std::isfinite(z)) {
    return kind == CellKind::kVacant ? kVacantColour : kUnknownColour;
  }
  return elevationColour((z - layout.elevation_min_m) /
                         (layout.elevation_max_m - layout.elevation_min_m));
}

void drawMap(Canvas& canvas, const HeightMap& map, const Plan& plan) {
  const HeightmapImageLayout& layout = plan.layout;
  const int s = layout.cell_pixels;
  for (int j = 0; j < map.cells_y; ++j) {
    const int y0 = layout.map_y + j * s;  // j counts along -y: row j from the top
    for (int i = 0; i < map.cells_x; ++i) {
      const int x0 = layout.map_x + (map.cells_x - 1 - i) * s;  // i counts along -x
      const std::size_t k = map.index(i, j);
      const auto kind = static_cast<CellKind>(map.kind[k]);
      const Rgb colour = cellColour(kind, map.elevation[k], layout);
      if (kind == CellKind::kVirtualSurface) {
        canvas.hatchedBlock(x0, y0, s, s, colour);
      } else {
        canvas.fill(x0, y0, s, s, colour);
      }
    }
  }
  canvas.frame(layout.map_x, layout.map_y, plan.map_width, plan.map_height, kHeightmapInk);

  // Scale bar: a bar with end ticks, its length under it.
  const int bar_x = layout.map_x;
  const int tick_y = layout.map_y + plan.map_height + kScaleBarGap;
  const int bar_y = tick_y + (kScaleBarTick - kScaleBarThick) / 2;
  canvas.fill(bar_x, bar_y, plan.scale_bar_pixels, kScaleBarThick, kHeightmapInk);
  canvas.fill(bar_x, tick_y, 1, kScaleBarTick, kHeightmapInk);
  canvas.fill(bar_x + plan.scale_bar_pixels - 1, tick_y, 1, kScaleBarTick, kHeightmapInk);
  canvas.text(bar_x, tick_y + kScaleBarTick + kLabelGap, plan.scale_label, kHeightmapInk);
}

void drawLegend(Canvas& canvas, const Plan& plan) {
  const int x = plan.legend_x;
  canvas.text(x, kMargin, kLegendTitle, kHeightmapInk);

  // Colour bar, high at the top, with kTickCount ticks and labels.
  for (int row = 0; row < kBarHeight; ++row) {
    const double t = 1.0 - static_cast<double>(row) / (kBarHeight - 1);
    canvas.fill(x, plan.bar_y + row, kBarWidth, 1, elevationColour(t));
  }
  canvas.frame(x, plan.bar_y, kBarWidth, kBarHeight, kHeightmapInk);
  for (int k = 0; k < kTickCount; ++k) {
    const int y = plan.bar_y + (kBarHeight - 1) - k * (kBarHeight - 1) / (kTickCount - 1);
    canvas.fill(x + kBarWidth, y, kTickLength, 1, kHeightmapInk);
    canvas.text(x + kBarWidth + kTickLength + kLabelGap, y - kTextHeight / 2,
                plan.tick_labels[static_cast<std::size_t>(k)], kHeightmapInk);
  }

  // Swatches for the cells without a height.
  for (std::size_t k = 0; k < kSwatchLabels.size(); ++k) {
    const int y = plan.swatch_y + static_cast<int>(k) * kSwatchPitch;
    if (k == 0) {
      canvas.hatchedBlock(x, y, kSwatch, kSwatch, elevationColour(0.5));
    } else {
      canvas.fill(x, y, kSwatch, kSwatch, k == 1 ? kVacantColour : kUnknownColour);
    }
    canvas.frame(x, y, kSwatch, kSwatch, kHeightmapInk);
    canvas.text(x + kSwatch + kLabelGap, y + (kSwatch - kTextHeight) / 2, kSwatchLabels[k],
                kHeightmapInk);
  }

  // Axis hint: arrows from a common origin, x to the right and y up.
  const int ox = x + kArrowHead;
  const int oy = plan.axes_y + kTextHeight / 2 + kArrowLength;
  canvas.fill(ox, oy - 1, kArrowLength, 2, kHeightmapInk);
  canvas.fill(ox - 1, oy - kArrowLength, 2, kArrowLength, kHeightmapInk);
  for (int d = 0; d < kArrowHead; ++d) {
    canvas.fill(ox + kArrowLength - d, oy - 1 - d, 1, 2 + 2 * d, kHeightmapInk);  // x head
    canvas.fill(ox - 1 - d, oy - kArrowLength + d, 2 + 2 * d, 1, kHeightmapInk);  // y head
  }
  canvas.text(ox + kArrowLength + kLabelGap, oy - kTextHeight / 2, "x", kHeightmapInk);
  canvas.text(ox + kArrowHead + kLabelGap, oy - kArrowLength - kTextHeight / 2, "y", kHeightmapInk);
}

}  // namespace

Expected<void, Error> writeHeightmapCsv(const std::string& path, const HeightMap& map) {
  if (auto checked = checkLayers(path, map); !checked.has_value()) {
    return checked;
  }
  auto file = AtomicFileWriter::open(path);
  if (!file.has_value()) {
    return Unexpected(std::move(file).error());
  }
  // The normal columns only when the map has them, so that occupancy maps' files stay as before.
  const bool normals = map.has_normals;
  std::string out = normals ? "x,y,elevation,clearance,kind,normal_x,normal_y,normal_z\n"
                            : "x,y,elevation,clearance,kind\n";
  out.reserve(kCsvFlushBytes + 256);
  for (int j = 0; j < map.cells_y; ++j) {
    for (int i = 0; i < map.cells_x; ++i) {
      const std::size_t k = map.index(i, j);
      const Vec3d centre = map.cellCentre(i, j);
      appendNumber(out, centre.x);
      out += ',';
      appendNumber(out, centre.y);
      out += ',';
      appendNumber(out, static_cast<double>(map.elevation[k]));
      out += ',';
      appendNumber(out, static_cast<double>(map.clearance[k]));
      out += ',';
      out += heightmap::toString(static_cast<CellKind>(map.kind[k]));
      if (normals) {
        for (const std::vector<float>* layer : {&map.normal_x, &map.normal_y, &map.normal_z}) {
          out += ',';
          appendNumber(out, static_cast<double>((*layer)[k]));
        }
      }
      out += '\n';
      if (out.size() >= kCsvFlushBytes) {
        if (auto written = file->write(out); !written.has_value()) {
          return written;
        }
        out.clear();
      }
    }
  }
  if (auto written = file->write(out); !written.has_value()) {
    return written;
  }
  return file->commit();
}

Rgb elevationColour(double t) noexcept {
  if (!(t > 0.0)) {
    return kScale.front();  // also NaN
  }
  if (t >= 1.0) {
    return kScale.back();
  }
  const double position = t * static_cast<double>(kScale.size() - 1);
  const auto segment = static_cast<std::size_t>(position);
  const double f = position - static_cast<double>(segment);
  const Rgb& a = kScale[segment];
  const Rgb& b = kScale[segment + 1];
  const auto mix = [f](std::uint8_t from, std::uint8_t to) {
    return static_cast<std::uint8_t>(
        std::lround(static_cast<double>(from) + f * (static_cast<double>(to) - from)));
  };
  return {mix(a.r, b.r), mix(a.g, b.g), mix(a.b, b.b)};
}

Result<HeightmapImageLayout> layoutHeightmapImage(const HeightMap& map,
                                                  const HeightmapImageOptions& options) {
  auto plan = makePlan(map, options);
  if (!plan.has_value()) {
    return Unexpected(std::move(plan).error());
  }
  return plan->layout;
}

Rgb RgbImage::at(int x, int y) const noexcept {
  RAYMAP_EXPECTS(x >= 0 && y >= 0 && x < width && y < height);
  const std::size_t k = (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                         static_cast<std::size_t>(x)) *
                        3;
  return {rgb[k], rgb[k + 1], rgb[k + 2]};
}

RgbImage renderHeightmap(const HeightMap& map, const HeightmapImageOptions& options) {
  auto plan = makePlan(map, options);
  RAYMAP_EXPECTS(plan.has_value());
  RgbImage image;
  image.width = plan->layout.width;
  image.height = plan->layout.height;
  image.rgb.resize(static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) *
                   3);
  Canvas canvas(image);
  canvas.fill(0, 0, image.width, image.height, kHeightmapBackground);
  drawMap(canvas, map, *plan);
  drawLegend(canvas, *plan);
  return image;
}

Expected<void, Error> writeHeightmapPng(const std::string& path, const HeightMap& map,
                                        const HeightmapImageOptions& options) {
  if (auto plan = makePlan(map, options); !plan.has_value()) {
    Error error = std::move(plan).error();
    error.message = "cannot write '" + path + "': " + error.message;
    return Unexpected(std::move(error));
  }
  const RgbImage image = renderHeightmap(map, options);
  return writePng(path, image.width, image.height, image.rgb);
}

}  // namespace raymap::io
