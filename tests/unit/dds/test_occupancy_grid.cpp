// SPDX-License-Identifier: BSD-3-Clause
// OccupancyGridMessage through Cyclone's serializer and back through decodeOccupancyGrid; and the
// decoder's refusals.
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "src/dds/occupancy_grid_message.hpp"
#include "src/dds/topic_types.hpp"
#include "src/msgs/occupancy_grid_decode.hpp"
#include "tests/unit/dds/loopback_bytes.hpp"

namespace raymap::dds {

using namespace msgs;  // the ROS 2 message codecs (src/msgs) these tests exercise
namespace {

std::vector<std::byte> cycloneCostmapBytes() {
  OccupancyGridMessage message(4, 3);
  const std::span<std::int8_t> cells = message.cells();
  for (std::size_t i = 0; i < cells.size(); ++i) {
    cells[i] = static_cast<std::int8_t>(i == 0 ? -1 : (i == 11 ? 100 : static_cast<int>(i)));
  }
  message.fill(0.25, {-1.5, 2.0, 0.0}, 1'700'000'123'456'789'012LL, "map");
  auto bytes =
      test::cyclonesBytes("rt/decode_test_costmap", occupancyGridType(), {message.sample()});
  return bytes.empty() ? std::vector<std::byte>{} : bytes.front();
}

TEST(OccupancyGrid, WhatTheMessageWritesDecodesToTheSameCellsAndGeometry) {
  const std::vector<std::byte> bytes = cycloneCostmapBytes();
  ASSERT_FALSE(bytes.empty());

  auto grid = decodeOccupancyGrid(bytes);

  ASSERT_TRUE(grid.has_value()) << toString(grid.error());
  EXPECT_EQ(grid->stamp_ns, 1'700'000'123'456'789'012LL);
  EXPECT_EQ(grid->map_load_time_ns, grid->stamp_ns);
  EXPECT_EQ(grid->frame_id, "map");
  EXPECT_FLOAT_EQ(grid->resolution, 0.25F);
  EXPECT_EQ(grid->width, 4u);
  EXPECT_EQ(grid->height, 3u);
  EXPECT_DOUBLE_EQ(grid->origin_x, -1.5);
  EXPECT_DOUBLE_EQ(grid->origin_y, 2.0);
  EXPECT_DOUBLE_EQ(grid->qw, 1.0);
  ASSERT_EQ(grid->data.size(), 12u);
  EXPECT_EQ(grid->data[0], -1);
  EXPECT_EQ(grid->data[5], 5);
  EXPECT_EQ(grid->data[11], 100);
}

TEST(OccupancyGrid, TruncatedOrInconsistentBytesAreRefusedWithTheReason) {
  std::vector<std::byte> bytes = cycloneCostmapBytes();
  ASSERT_FALSE(bytes.empty());
  for (std::size_t keep = 0; keep < bytes.size(); keep += 7) {
    auto grid = decodeOccupancyGrid(std::span<const std::byte>(bytes).first(keep));
    EXPECT_FALSE(grid.has_value()) << keep << " bytes";
  }
  // width is after the stamp (8), the frame (4 + 4 "map\0"), map_load_time (8), resolution (4):
  // byte 4 + 28 of the little-endian payload. 5 x 3 cells against 12 bytes of data.
  bytes[4 + 28] = std::byte{5};
  auto mismatch = decodeOccupancyGrid(bytes);
  ASSERT_FALSE(mismatch.has_value());
  EXPECT_EQ(mismatch.error(), OccupancyGridError::kSizeMismatch);
}

}  // namespace
}  // namespace raymap::dds
