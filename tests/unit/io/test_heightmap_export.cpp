// SPDX-License-Identifier: BSD-3-Clause
// Height-map CSV and PNG: CSV lines per kind, the image's cell colours, orientation, scale and
// legend (checked on the decoded PNG), option checks, failures that leave nothing behind.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "src/heightmap/height_map.hpp"
#include "src/io/heightmap_export.hpp"
#include "tests/support/decoded_png.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::io {

namespace {

using heightmap::CellKind;
using heightmap::HeightMap;
using test::TempDir;

constexpr float kNanCell = std::numeric_limits<float>::quiet_NaN();
constexpr float kInfCell = std::numeric_limits<float>::infinity();

/// A map with every cell unknown.
HeightMap emptyMap(int cells_x, int cells_y, double resolution = 0.5) {
  HeightMap map;
  map.resolution = resolution;
  map.cells_x = cells_x;
  map.cells_y = cells_y;
  map.centre_x = 10.0;
  map.centre_y = -5.0;
  map.resizeLayers();
  std::fill(map.elevation.begin(), map.elevation.end(), kNanCell);
  std::fill(map.clearance.begin(), map.clearance.end(), kNanCell);
  std::fill(map.kind.begin(), map.kind.end(), static_cast<std::uint32_t>(CellKind::kUnknown));
  return map;
}

void setCell(HeightMap& map, int i, int j, CellKind kind, float elevation, float clearance) {
  const std::size_t k = map.index(i, j);
  map.kind[k] = static_cast<std::uint32_t>(kind);
  map.elevation[k] = elevation;
  map.clearance[k] = clearance;
}

/// 4 x 3 cells of 0.5 m centred on (10, -5): the high surface at (0, 0) (+x/+y corner), the low
/// one at (3, 2) (-x/-y corner), a virtual cell at (1, 0), a vacant cell at (2, 1), the rest
/// unknown.
constexpr int kHighI = 0, kHighJ = 0, kLowI = 3, kLowJ = 2, kVirtualI = 1, kVirtualJ = 0,
              kVacantI = 2, kVacantJ = 1, kUnknownI = 3, kUnknownJ = 0;
HeightMap sampleMap() {
  HeightMap map = emptyMap(4, 3);
  setCell(map, kHighI, kHighJ, CellKind::kSurface, 2.0f, kInfCell);
  setCell(map, kLowI, kLowJ, CellKind::kSurface, 1.0f, 0.75f);
  setCell(map, kVirtualI, kVirtualJ, CellKind::kVirtualSurface, 1.5f, 0.3f);
  setCell(map, kVacantI, kVacantJ, CellKind::kVacant, kNanCell, kNanCell);
  return map;
}

std::vector<std::string> readLines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) {
    lines.push_back(line);
  }
  return lines;
}

std::string fileText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// ---------------------------------------------------------------------------------------------
// CSV

TEST(HeightmapCsv, HeaderThenOneLinePerCellInStorageOrder) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("map.csv");
  const HeightMap map = sampleMap();

  // Act
  auto written = writeHeightmapCsv(path, map);

  // Assert
  ASSERT_TRUE(written.has_value()) << written.error().message;
  const std::vector<std::string> lines = readLines(path);
  ASSERT_EQ(lines.size(), map.cellCount() + 1);
  EXPECT_EQ(lines[0], "x,y,elevation,clearance,kind");
  // Cell centres: x = 10 + (2 - i - 0.5) * 0.5, y = -5 + (1.5 - j - 0.5) * 0.5.
  EXPECT_EQ(lines[1 + map.index(kHighI, kHighJ)], "10.7500,-4.5000,2.0000,inf,surface");
  EXPECT_EQ(lines[1 + map.index(kLowI, kLowJ)], "9.2500,-5.5000,1.0000,0.7500,surface");
  EXPECT_EQ(lines[1 + map.index(kVirtualI, kVirtualJ)], "10.2500,-4.5000,1.5000,0.3000,virtual");
  EXPECT_EQ(lines[1 + map.index(kVacantI, kVacantJ)], "9.7500,-5.0000,nan,nan,vacant");
  EXPECT_EQ(lines[1 + map.index(kUnknownI, kUnknownJ)], "9.2500,-4.5000,nan,nan,unknown");
  EXPECT_EQ(fileText(path).back(), '\n');
}

TEST(HeightmapCsv, EveryLineHasFiveFieldsAndTheCellsCentre) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("map.csv");
  const HeightMap map = sampleMap();

  // Act
  auto written = writeHeightmapCsv(path, map);

  // Assert
  ASSERT_TRUE(written.has_value()) << written.error().message;
  const std::vector<std::string> lines = readLines(path);
  ASSERT_EQ(lines.size(), map.cellCount() + 1);
  for (int j = 0; j < map.cells_y; ++j) {
    for (int i = 0; i < map.cells_x; ++i) {
      const std::string& line = lines[1 + map.index(i, j)];
      EXPECT_EQ(std::count(line.begin(), line.end(), ','), 4) << line;
      const Vec3d centre = map.cellCentre(i, j);
      EXPECT_NEAR(std::stod(line.substr(0, line.find(','))), centre.x, 1e-4) << line;
      EXPECT_NEAR(std::stod(line.substr(line.find(',') + 1)), centre.y, 1e-4) << line;
    }
  }
}

TEST(HeightmapCsv, ANegativeNanIsWrittenAsNan) {
  // Arrange: printf would write "-nan" for a NaN with its sign bit set.
  TempDir dir;
  const std::string path = dir.file("map.csv");
  HeightMap map = emptyMap(1, 1);
  map.elevation[0] = std::copysign(kNanCell, -1.0f);
  map.clearance[0] = std::copysign(kNanCell, -1.0f);

  // Act
  auto written = writeHeightmapCsv(path, map);

  // Assert
  ASSERT_TRUE(written.has_value()) << written.error().message;
  EXPECT_EQ(fileText(path), "x,y,elevation,clearance,kind\n10.0000,-5.0000,nan,nan,unknown\n");
}

TEST(HeightmapCsv, AnEmptyMapWritesTheHeaderOnly) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("map.csv");

  // Act
  auto written = writeHeightmapCsv(path, emptyMap(0, 0));

  // Assert
  ASSERT_TRUE(written.has_value()) << written.error().message;
  EXPECT_EQ(fileText(path), "x,y,elevation,clearance,kind\n");
}

TEST(HeightmapCsv, AnUnwritablePathFailsNamingItAndLeavesNothing) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("missing/map.csv");

  // Act
  auto written = writeHeightmapCsv(path, sampleMap());

  // Assert
  ASSERT_FALSE(written.has_value());
  EXPECT_EQ(written.error().code, ErrorCode::kIo);
  EXPECT_NE(written.error().message.find(path), std::string::npos) << written.error().message;
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(HeightmapCsv, LayersOfTheWrongSizeFailAndLeaveTheOldFileAlone) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("map.csv");
  std::ofstream(path) << "old\n";
  HeightMap map = sampleMap();
  map.clearance.pop_back();

  // Act
  auto written = writeHeightmapCsv(path, map);

  // Assert
  ASSERT_FALSE(written.has_value());
  EXPECT_EQ(written.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(written.error().message.find(path), std::string::npos) << written.error().message;
  EXPECT_EQ(fileText(path), "old\n");
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()),
                          std::filesystem::directory_iterator()),
            1);
}

// ---------------------------------------------------------------------------------------------
// Colour scale

double distance(Rgb a, Rgb b) {
  const double dr = a.r - b.r;
  const double dg = a.g - b.g;
  const double db = a.b - b.b;
  return std::sqrt(dr * dr + dg * dg + db * db);
}

double luma(Rgb c) { return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b; }

TEST(ElevationColour, EndsClampAndLightnessRises) {
  EXPECT_EQ(elevationColour(-1.0), elevationColour(0.0));
  EXPECT_EQ(elevationColour(2.0), elevationColour(1.0));
  EXPECT_EQ(elevationColour(std::nan("")), elevationColour(0.0));
  for (int k = 1; k <= 100; ++k) {
    EXPECT_GT(luma(elevationColour(k / 100.0)), luma(elevationColour((k - 1) / 100.0))) << k;
  }
}

TEST(ElevationColour, TheOtherCellColoursAreFarFromTheScale) {
  double nearest_vacant = 1e9;
  double nearest_unknown = 1e9;
  double nearest_hatch = 1e9;
  for (int k = 0; k <= 1000; ++k) {
    const Rgb c = elevationColour(k / 1000.0);
    nearest_vacant = std::min(nearest_vacant, distance(c, kVacantColour));
    nearest_unknown = std::min(nearest_unknown, distance(c, kUnknownColour));
    nearest_hatch = std::min(nearest_hatch, distance(c, kVirtualHatchColour));
  }
  constexpr double kDistinct = 60.0;  // RGB distance that reads as a different colour
  EXPECT_GT(nearest_vacant, kDistinct);
  EXPECT_GT(nearest_unknown, kDistinct);
  EXPECT_GT(nearest_hatch, kDistinct);
  EXPECT_GT(distance(kVacantColour, kUnknownColour), kDistinct);
}

// ---------------------------------------------------------------------------------------------
// Image

/// Pixel access into a decoded PNG.
Rgb pixel(const test::DecodedPng& png, int x, int y) {
  const std::size_t k = (static_cast<std::size_t>(y) * static_cast<std::size_t>(png.width) +
                         static_cast<std::size_t>(x)) *
                        3;
  return {png.pixels.at(k), png.pixels.at(k + 1), png.pixels.at(k + 2)};
}

/// The colours in cell (i, j)'s block, computed from the layout's documented placement.
std::set<std::tuple<int, int, int>> blockColours(const test::DecodedPng& png, const HeightMap& map,
                                                 const HeightmapImageLayout& layout, int i, int j) {
  std::set<std::tuple<int, int, int>> colours;
  const int s = layout.cell_pixels;
  const int x0 = layout.map_x + (map.cells_x - 1 - i) * s;
  const int y0 = layout.map_y + j * s;
  for (int y = y0; y < y0 + s; ++y) {
    for (int x = x0; x < x0 + s; ++x) {
      const Rgb c = pixel(png, x, y);
      colours.insert({c.r, c.g, c.b});
    }
  }
  return colours;
}

std::tuple<int, int, int> tuple(Rgb c) { return {c.r, c.g, c.b}; }

/// Writes the map as a PNG and decodes it (with the layout it was drawn with).
struct WrittenImage {
  test::DecodedPng png;
  HeightmapImageLayout layout;
};
std::optional<WrittenImage> writeAndDecode(const TempDir& dir, const HeightMap& map,
                                           const HeightmapImageOptions& options = {}) {
  const std::string path = dir.file("map.png");
  auto written = writeHeightmapPng(path, map, options);
  if (!written.has_value()) {
    ADD_FAILURE() << written.error().message;
    return std::nullopt;
  }
  auto layout = layoutHeightmapImage(map, options);
  auto png = test::decodePng(path);
  if (!layout.has_value() || !png.has_value()) {
    ADD_FAILURE() << "no layout or no PNG";
    return std::nullopt;
  }
  return WrittenImage{*png, *layout};
}

TEST(HeightmapImage, EachKindHasItsColourInItsCellsBlock) {
  // Arrange
  TempDir dir;
  const HeightMap map = sampleMap();

  // Act
  const auto image = writeAndDecode(dir, map);

  // Assert
  ASSERT_TRUE(image.has_value());
  const auto& [png, layout] = *image;
  EXPECT_EQ(layout.cell_pixels, 100);  // 4 cells: the smallest scale giving >= 400 px
  EXPECT_DOUBLE_EQ(layout.elevation_min_m, 1.0);
  EXPECT_DOUBLE_EQ(layout.elevation_max_m, 2.0);
  using Colours = std::set<std::tuple<int, int, int>>;
  // The higher surface is the top of the scale, the lower the bottom.
  EXPECT_EQ(blockColours(png, map, layout, kHighI, kHighJ), Colours{tuple(elevationColour(1.0))});
  EXPECT_EQ(blockColours(png, map, layout, kLowI, kLowJ), Colours{tuple(elevationColour(0.0))});
  EXPECT_EQ(blockColours(png, map, layout, kVacantI, kVacantJ), Colours{tuple(kVacantColour)});
  EXPECT_EQ(blockColours(png, map, layout, kUnknownI, kUnknownJ), Colours{tuple(kUnknownColour)});
  // Virtual: its elevation's colour (mid-scale) hatched in magenta.
  EXPECT_EQ(blockColours(png, map, layout, kVirtualI, kVirtualJ),
            (Colours{tuple(elevationColour(0.5)), tuple(kVirtualHatchColour)}));
}

TEST(HeightmapImage, PlusXIsRightAndPlusYIsUp) {
  // Arrange: one surface cell at the +x/-y corner (i = 0, j = cells_y - 1) of a 6 x 5 map.
  TempDir dir;
  HeightMap map = emptyMap(6, 5);
  setCell(map, 0, 4, CellKind::kSurface, 0.0f, kInfCell);
  ASSERT_GT(map.cellCentre(0, 4).x, map.cellCentre(1, 4).x);
  ASSERT_LT(map.cellCentre(0, 4).y, map.cellCentre(0, 3).y);

  // Act
  const auto image = writeAndDecode(dir, map);

  // Assert: the non-unknown pixels of the map part form exactly its bottom-right block.
  ASSERT_TRUE(image.has_value());
  const auto& [png, layout] = *image;
  const int s = layout.cell_pixels;
  int x_min = png.width, x_max = -1, y_min = png.height, y_max = -1;
  for (int y = layout.map_y; y < layout.map_y + map.cells_y * s; ++y) {
    for (int x = layout.map_x; x < layout.map_x + map.cells_x * s; ++x) {
      if (pixel(png, x, y) != kUnknownColour) {
        x_min = std::min(x_min, x);
        x_max = std::max(x_max, x);
        y_min = std::min(y_min, y);
        y_max = std::max(y_max, y);
      }
    }
  }
  EXPECT_EQ(x_min, layout.map_x + 5 * s);
  EXPECT_EQ(x_max, layout.map_x + 6 * s - 1);
  EXPECT_EQ(y_min, layout.map_y + 4 * s);
  EXPECT_EQ(y_max, layout.map_y + 5 * s - 1);
  // One elevation only: the range is widened around it, so it is mid-scale.
  EXPECT_EQ(pixel(png, x_min, y_min), elevationColour(0.5));
}

TEST(HeightmapImage, TheMapIsFramedAndTheLegendShowsScaleAndSwatches) {
  // Arrange
  TempDir dir;
  const HeightMap map = sampleMap();

  // Act
  const auto image = writeAndDecode(dir, map);

  // Assert
  ASSERT_TRUE(image.has_value());
  const auto& [png, layout] = *image;
  const int map_width = map.cells_x * layout.cell_pixels;
  const int map_height = map.cells_y * layout.cell_pixels;
  EXPECT_EQ(pixel(png, layout.map_x - 1, layout.map_y - 1), kHeightmapInk);
  EXPECT_EQ(pixel(png, layout.map_x + map_width, layout.map_y + map_height), kHeightmapInk);
  EXPECT_EQ(pixel(png, 0, 0), kHeightmapBackground);
  // Legend: right of the map. The colour bar's ends, the swatches and text are there.
  std::set<std::tuple<int, int, int>> legend;
  int ink = 0;
  for (int y = 0; y < png.height; ++y) {
    for (int x = layout.map_x + map_width + 2; x < png.width; ++x) {
      const Rgb c = pixel(png, x, y);
      legend.insert(tuple(c));
      ink += c == kHeightmapInk ? 1 : 0;
    }
  }
  for (const Rgb c : {elevationColour(0.0), elevationColour(0.5), elevationColour(1.0),
                      kVacantColour, kUnknownColour, kVirtualHatchColour}) {
    EXPECT_EQ(legend.count(tuple(c)), 1u) << int{c.r} << " " << int{c.g} << " " << int{c.b};
  }
  EXPECT_GT(ink, 500) << "legend text and arrows";
  // Scale bar under the map: ink in the rows below the frame, starting at the map's left edge.
  bool bar = false;
  for (int y = layout.map_y + map_height + 2; y < png.height && !bar; ++y) {
    bar = pixel(png, layout.map_x, y) == kHeightmapInk &&
          pixel(png, layout.map_x + 20, y) == kHeightmapInk;
  }
  EXPECT_TRUE(bar);
}

TEST(HeightmapImage, FixedElevationRangePlacesColoursOnIt) {
  // Arrange
  TempDir dir;
  const HeightMap map = sampleMap();
  HeightmapImageOptions options;
  options.elevation_min_m = 0.0;
  options.elevation_max_m = 4.0;

  // Act
  const auto image = writeAndDecode(dir, map, options);

  // Assert
  ASSERT_TRUE(image.has_value());
  const auto& [png, layout] = *image;
  EXPECT_DOUBLE_EQ(layout.elevation_min_m, 0.0);
  EXPECT_DOUBLE_EQ(layout.elevation_max_m, 4.0);
  using Colours = std::set<std::tuple<int, int, int>>;
  EXPECT_EQ(blockColours(png, map, layout, kHighI, kHighJ), Colours{tuple(elevationColour(0.5))});
  EXPECT_EQ(blockColours(png, map, layout, kLowI, kLowJ), Colours{tuple(elevationColour(0.25))});
}

TEST(HeightmapImage, CellPixelsOptionSetsTheBlockSize) {
  // Arrange
  HeightmapImageOptions options;
  options.cell_pixels = 7;

  // Act
  const auto layout = layoutHeightmapImage(sampleMap(), options);
  const RgbImage image = renderHeightmap(sampleMap(), options);

  // Assert
  ASSERT_TRUE(layout.has_value()) << layout.error().message;
  EXPECT_EQ(layout->cell_pixels, 7);
  EXPECT_EQ(image.width, layout->width);
  EXPECT_EQ(image.height, layout->height);
  EXPECT_EQ(image.at(layout->map_x + 3 * 7, layout->map_y), elevationColour(1.0));
  EXPECT_EQ(image.at(layout->map_x, layout->map_y + 2 * 7 + 6), elevationColour(0.0));
}

TEST(HeightmapImage, AutomaticScaleKeepsTheMapBetween400And1600Pixels) {
  for (const auto& [cells_x, cells_y] :
       {std::pair{1, 1}, std::pair{3, 2}, std::pair{30, 30}, std::pair{100, 400},
        std::pair{399, 10}, std::pair{401, 401}, std::pair{1600, 1600}}) {
    // Act
    const auto layout = layoutHeightmapImage(emptyMap(cells_x, cells_y));

    // Assert
    ASSERT_TRUE(layout.has_value()) << layout.error().message;
    const int width = cells_x * layout->cell_pixels;
    const int height = cells_y * layout->cell_pixels;
    EXPECT_LE(std::max(width, height), 1600) << cells_x << " x " << cells_y;
    if (std::max(cells_x, cells_y) * 2 <= 1600 && cells_x >= cells_y) {
      EXPECT_GE(width, 400) << cells_x << " x " << cells_y;
    }
  }
  // More cells than 1600: one pixel per cell.
  const auto big = layoutHeightmapImage(emptyMap(2000, 10));
  ASSERT_TRUE(big.has_value());
  EXPECT_EQ(big->cell_pixels, 1);
}

TEST(HeightmapImage, AMapWithoutSurfacesStillRenders) {
  // Arrange
  HeightMap map = emptyMap(5, 5);
  setCell(map, 2, 2, CellKind::kVacant, kNanCell, kNanCell);

  // Act
  const auto layout = layoutHeightmapImage(map);
  const RgbImage image = renderHeightmap(map);

  // Assert
  ASSERT_TRUE(layout.has_value()) << layout.error().message;
  EXPECT_LT(layout->elevation_min_m, layout->elevation_max_m);
  const int s = layout->cell_pixels;
  EXPECT_EQ(image.at(layout->map_x + 2 * s, layout->map_y + 2 * s), kVacantColour);
  EXPECT_EQ(image.at(layout->map_x, layout->map_y), kUnknownColour);
}

TEST(HeightmapImage, BadOptionsAndMapsAreRejectedNamingThePath) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("map.png");
  HeightmapImageOptions negative_scale;
  negative_scale.cell_pixels = -1;
  HeightmapImageOptions huge_scale;
  huge_scale.cell_pixels = HeightmapImageOptions::kMaxCellPixels + 1;
  HeightmapImageOptions inverted;
  inverted.elevation_min_m = 2.0;
  inverted.elevation_max_m = 1.0;
  HeightmapImageOptions infinite;
  infinite.elevation_max_m = std::numeric_limits<double>::infinity();
  HeightMap short_layer = sampleMap();
  short_layer.kind.pop_back();
  const HeightMap good = sampleMap();
  const std::vector<std::pair<const HeightMap*, HeightmapImageOptions>> cases{
      {&good, negative_scale}, {&good, huge_scale}, {&good, inverted},
      {&good, infinite},       {&short_layer, {}},  {nullptr, {}}};
  const HeightMap empty = emptyMap(0, 3);

  for (const auto& [map, options] : cases) {
    // Act
    auto written = writeHeightmapPng(path, map != nullptr ? *map : empty, options);

    // Assert
    ASSERT_FALSE(written.has_value());
    EXPECT_EQ(written.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(written.error().message.find(path), std::string::npos) << written.error().message;
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(HeightmapImage, AnUnwritablePathFailsNamingItAndLeavesNothing) {
  // Arrange
  TempDir dir;
  const std::string path = dir.file("missing/map.png");

  // Act
  auto written = writeHeightmapPng(path, sampleMap());

  // Assert
  ASSERT_FALSE(written.has_value());
  EXPECT_EQ(written.error().code, ErrorCode::kIo);
  EXPECT_NE(written.error().message.find(path), std::string::npos) << written.error().message;
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

}  // namespace
}  // namespace raymap::io
