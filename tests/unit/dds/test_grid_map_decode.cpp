// SPDX-License-Identifier: BSD-3-Clause
// decodeGridMap: what GridMapMessage sends (through Cyclone) decodes back to the height map;
// hand-encoded big-endian bytes; truncated, inconsistent and random bytes are refused safely.
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "src/dds/grid_map_message.hpp"
#include "src/dds/topic_types.hpp"
#include "src/msgs/grid_map_decode.hpp"
#include "tests/unit/dds/cdr_test_writer.hpp"
#include "tests/unit/dds/loopback_bytes.hpp"

namespace raymap::dds {

using namespace msgs;  // the ROS 2 message codecs (src/msgs) these tests exercise
namespace {

/// A 5 x 3 map with NaN, +inf and every kind.
heightmap::HeightMap makeDecodeMap() {
  heightmap::HeightMap map;
  map.resolution = 0.2;
  map.cells_x = 5;
  map.cells_y = 3;
  map.centre_x = 12.5;
  map.centre_y = -3.25;
  map.resizeLayers();
  for (std::size_t i = 0; i < map.cellCount(); ++i) {
    map.elevation[i] = 0.1F * static_cast<float>(i) - 0.5F;
    map.clearance[i] = 2.0F;
    map.kind[i] = static_cast<std::uint32_t>(i % 4);
    map.observed_count[i] = static_cast<std::uint32_t>(i * 3);
  }
  map.elevation[4] = std::numeric_limits<float>::quiet_NaN();
  map.clearance[4] = std::numeric_limits<float>::quiet_NaN();
  map.clearance[7] = std::numeric_limits<float>::infinity();
  return map;
}

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

/// The bytes of GridMapMessage::fill(makeDecodeMap(), ...) as Cyclone serializes them.
std::vector<std::byte> cycloneGridMapBytes() {
  const heightmap::HeightMap map = makeDecodeMap();
  GridMapMessage message(map.cells_x, map.cells_y);
  message.fill(map, 1'700'000'123'456'789'012LL, "odom");
  auto bytes = test::cyclonesBytes("rt/decode_test_grid_map", gridMapType(), {message.sample()});
  return bytes.empty() ? std::vector<std::byte>{} : bytes.front();
}

/// A hand-encoded GridMap: `layers` names, `arrays` arrays of `dims` dimensions with `values`
/// elements each.
struct HandMap {
  bool little_endian = true;
  std::vector<std::string> layers = {"elevation", "variance"};
  std::size_t arrays = 2;
  std::vector<std::uint32_t> dim_sizes = {2, 3};  // column_index, row_index
  std::uint32_t data_offset = 0;
  std::size_t values = 6;
};

std::vector<std::byte> encodeHandMap(const HandMap& m) {
  test::CdrTestWriter w(m.little_endian);
  w.i32(-2);  // a stamp before the epoch: sec -2, nanosec 5e8 = -1.5 s
  w.u32(500'000'000U);
  w.string("map");
  w.f64(0.5);   // resolution
  w.f64(1.5);   // length_x
  w.f64(1.0);   // length_y
  w.f64(-4.0);  // position
  w.f64(7.25);
  w.f64(0.5);
  w.f64(0.0);  // orientation x, y, z, w
  w.f64(0.0);
  w.f64(0.0);
  w.f64(1.0);
  w.u32(static_cast<std::uint32_t>(m.layers.size()));
  for (const std::string& name : m.layers) {
    w.string(name);
  }
  w.u32(1);
  w.string("elevation");
  w.u32(static_cast<std::uint32_t>(m.arrays));
  for (std::size_t a = 0; a < m.arrays; ++a) {
    w.u32(static_cast<std::uint32_t>(m.dim_sizes.size()));
    for (std::size_t d = 0; d < m.dim_sizes.size(); ++d) {
      w.string(d == 0 ? "column_index" : "row_index");
      w.u32(m.dim_sizes[d]);
      w.u32(d == 0 ? 6U : 3U);
    }
    w.u32(m.data_offset);
    w.u32(static_cast<std::uint32_t>(m.values));
    for (std::size_t i = 0; i < m.values; ++i) {
      w.f32(static_cast<float>(a * 100 + i) + 0.5F);
    }
  }
  w.u16(3);
  w.u16(1);
  return w.data();
}

TEST(DecodeGridMap, WhatGridMapMessageSendsDecodesToTheHeightMap) {
  const heightmap::HeightMap map = makeDecodeMap();
  const std::vector<std::byte> cdr = cycloneGridMapBytes();
  ASSERT_FALSE(cdr.empty());

  const auto decoded = decodeGridMap(cdr);

  ASSERT_TRUE(decoded.has_value()) << toString(decoded.error());
  EXPECT_EQ(decoded->stamp_ns, 1'700'000'123'456'789'012LL);
  EXPECT_EQ(decoded->frame_id, "odom");
  EXPECT_DOUBLE_EQ(decoded->resolution, 0.2);
  EXPECT_DOUBLE_EQ(decoded->length_x, 5 * 0.2);
  EXPECT_DOUBLE_EQ(decoded->length_y, 3 * 0.2);
  EXPECT_EQ(decoded->centre_x, 12.5);
  EXPECT_EQ(decoded->centre_y, -3.25);
  EXPECT_EQ(decoded->centre_z, 0.0);
  EXPECT_EQ(decoded->qw, 1.0);
  EXPECT_EQ(decoded->qx, 0.0);
  ASSERT_EQ(decoded->layers.size(), 4U);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(decoded->layers[i], GridMapMessage::kLayerNames[i]);
  }
  ASSERT_EQ(decoded->basic_layers.size(), 1U);
  EXPECT_EQ(decoded->basic_layers[0], "elevation");
  ASSERT_EQ(decoded->data.size(), 4U);
  const std::size_t cells = map.cellCount();
  for (const GridMapLayerData& array : decoded->data) {
    ASSERT_EQ(array.dims.size(), 2U);
    EXPECT_EQ(array.dims[0].label, "column_index");
    EXPECT_EQ(array.dims[0].size, 3U);
    EXPECT_EQ(array.dims[0].stride, 15U);
    EXPECT_EQ(array.dims[1].label, "row_index");
    EXPECT_EQ(array.dims[1].size, 5U);
    EXPECT_EQ(array.dims[1].stride, 5U);
    EXPECT_EQ(array.data_offset, 0U);
    ASSERT_EQ(array.data.size(), cells);
  }
  for (std::size_t i = 0; i < cells; ++i) {
    EXPECT_TRUE(sameBits(decoded->data[0].data[i], map.elevation[i])) << i;
    EXPECT_TRUE(sameBits(decoded->data[1].data[i], map.clearance[i])) << i;
    EXPECT_EQ(decoded->data[2].data[i], static_cast<float>(map.kind[i])) << i;
    EXPECT_EQ(decoded->data[3].data[i], static_cast<float>(map.observed_count[i])) << i;
  }
  EXPECT_EQ(decoded->outer_start_index, 0);
  EXPECT_EQ(decoded->inner_start_index, 0);
}

TEST(DecodeGridMap, AMessageWithNormalsCarriesTheNormalLayers) {
  heightmap::HeightMap map = makeDecodeMap();
  map.has_normals = true;
  map.resizeLayers();
  for (std::size_t i = 0; i < map.cellCount(); ++i) {
    map.normal_x[i] = 0.01F * static_cast<float>(i);
    map.normal_y[i] = -0.02F * static_cast<float>(i);
    map.normal_z[i] = 1.0F - 0.01F * static_cast<float>(i);
  }
  map.normal_x[4] = std::numeric_limits<float>::quiet_NaN();
  GridMapMessage message(map.cells_x, map.cells_y, true);
  EXPECT_TRUE(message.withNormals());
  message.fill(map, 1, "odom");
  auto bytes =
      test::cyclonesBytes("rt/decode_test_grid_map_normals", gridMapType(), {message.sample()});
  ASSERT_FALSE(bytes.empty());

  const auto decoded = decodeGridMap(bytes.front());

  ASSERT_TRUE(decoded.has_value()) << toString(decoded.error());
  ASSERT_EQ(decoded->layers.size(), 7U);
  ASSERT_EQ(decoded->data.size(), 7U);
  const std::vector<float>* normals[3] = {&map.normal_x, &map.normal_y, &map.normal_z};
  for (std::size_t n = 0; n < 3; ++n) {
    EXPECT_EQ(decoded->layers[4 + n], GridMapMessage::kNormalLayerNames[n]);
    ASSERT_EQ(decoded->data[4 + n].data.size(), map.cellCount());
    for (std::size_t i = 0; i < map.cellCount(); ++i) {
      EXPECT_TRUE(sameBits(decoded->data[4 + n].data[i], (*normals[n])[i])) << n << " " << i;
    }
  }
  EXPECT_EQ(decoded->layers[4], "normal_x");  // elevation_mapping's names
  EXPECT_EQ(decoded->layers[5], "normal_y");
  EXPECT_EQ(decoded->layers[6], "normal_z");
}

TEST(DecodeGridMap, AChoiceOfLayersCarriesOnlyThoseInTheirOrder) {
  // heightmap.layers: a planner that reads two layers receives two (issue 53).
  heightmap::HeightMap map = makeDecodeMap();
  GridMapMessage message(map.cells_x, map.cells_y,
                         GridLayerSet{}.add(GridLayer::kKind).add(GridLayer::kElevation));
  EXPECT_FALSE(message.withNormals());
  message.fill(map, 1, "odom");
  auto bytes =
      test::cyclonesBytes("rt/decode_test_grid_map_layers", gridMapType(), {message.sample()});
  ASSERT_FALSE(bytes.empty());
  const auto decoded = decodeGridMap(bytes.front());
  ASSERT_TRUE(decoded.has_value()) << toString(decoded.error());
  ASSERT_EQ(decoded->layers, (std::vector<std::string>{"elevation", "kind"}));
  EXPECT_EQ(decoded->basic_layers, (std::vector<std::string>{"elevation"}));
  ASSERT_EQ(decoded->data.size(), 2U);
  for (std::size_t i = 0; i < map.cellCount(); ++i) {
    EXPECT_TRUE(sameBits(decoded->data[0].data[i], map.elevation[i])) << i;
    EXPECT_EQ(decoded->data[1].data[i], static_cast<float>(map.kind[i])) << i;
  }

  // Without elevation there is no basic layer; the message is smaller by the layers left out.
  GridMapMessage clearance_only(map.cells_x, map.cells_y,
                                GridLayerSet{}.add(GridLayer::kClearance));
  clearance_only.fill(map, 1, "odom");
  auto small = test::cyclonesBytes("rt/decode_test_grid_map_clearance", gridMapType(),
                                   {clearance_only.sample()});
  ASSERT_FALSE(small.empty());
  const auto one = decodeGridMap(small.front());
  ASSERT_TRUE(one.has_value());
  EXPECT_EQ(one->layers, (std::vector<std::string>{"clearance"}));
  EXPECT_TRUE(one->basic_layers.empty());
  EXPECT_GE(bytes.front().size() - small.front().size(), map.cellCount() * 4);
}

TEST(DecodeGridMap, ReadsBothByteOrders) {
  for (const bool little_endian : {true, false}) {
    HandMap hand;
    hand.little_endian = little_endian;
    const auto decoded = decodeGridMap(encodeHandMap(hand));
    ASSERT_TRUE(decoded.has_value()) << toString(decoded.error());
    EXPECT_EQ(decoded->stamp_ns, -1'500'000'000LL);
    EXPECT_EQ(decoded->frame_id, "map");
    EXPECT_EQ(decoded->resolution, 0.5);
    EXPECT_EQ(decoded->length_x, 1.5);
    EXPECT_EQ(decoded->length_y, 1.0);
    EXPECT_EQ(decoded->centre_x, -4.0);
    EXPECT_EQ(decoded->centre_y, 7.25);
    EXPECT_EQ(decoded->centre_z, 0.5);
    ASSERT_EQ(decoded->data.size(), 2U);
    ASSERT_EQ(decoded->data[1].data.size(), 6U);
    EXPECT_EQ(decoded->data[1].data[5], 105.5F);
    EXPECT_EQ(decoded->outer_start_index, 3);
    EXPECT_EQ(decoded->inner_start_index, 1);
  }
}

TEST(DecodeGridMap, AcceptsADataOffsetThatTheDimensionsLeaveRoomFor) {
  HandMap hand;
  hand.data_offset = 2;
  hand.values = 8;
  const auto decoded = decodeGridMap(encodeHandMap(hand));
  ASSERT_TRUE(decoded.has_value()) << toString(decoded.error());
  EXPECT_EQ(decoded->data[0].data_offset, 2U);
}

TEST(DecodeGridMap, RefusesEveryTruncation) {
  const std::vector<std::byte> cdr = cycloneGridMapBytes();
  ASSERT_FALSE(cdr.empty());
  const auto full = decodeGridMap(cdr);
  ASSERT_TRUE(full.has_value());
  for (std::size_t size = 0; size < cdr.size(); ++size) {
    const auto decoded = decodeGridMap(std::span<const std::byte>(cdr.data(), size));
    ASSERT_FALSE(decoded.has_value())
        << "a prefix of " << size << " of " << cdr.size() << " bytes decoded";
    const GridMapError expected =
        size < 4 ? GridMapError::kBadEncapsulation : GridMapError::kTruncated;
    EXPECT_EQ(decoded.error(), expected) << size;
  }
}

TEST(DecodeGridMap, RefusesBadEncapsulation) {
  std::vector<std::byte> cdr = cycloneGridMapBytes();
  ASSERT_FALSE(cdr.empty());
  cdr[1] = std::byte{0x07};  // neither CDR_LE nor CDR_BE
  ASSERT_FALSE(decodeGridMap(cdr).has_value());
  EXPECT_EQ(decodeGridMap(cdr).error(), GridMapError::kBadEncapsulation);
  cdr[0] = std::byte{0x01};
  cdr[1] = std::byte{0x01};
  EXPECT_EQ(decodeGridMap(cdr).error(), GridMapError::kBadEncapsulation);
}

TEST(DecodeGridMap, RefusesAbsurdCountsBeforeReservingForThem) {
  std::vector<std::byte> cdr = cycloneGridMapBytes();
  ASSERT_FALSE(cdr.empty());
  // The layers count sits at payload offset 104: stamp 8, "odom" 4 + 5, padding to 24, info
  // 10 doubles.
  constexpr std::size_t kLayersCount = 4 + 104;
  std::uint32_t count = 0;
  std::memcpy(&count, cdr.data() + kLayersCount, sizeof(count));
  ASSERT_EQ(count, 4U);
  const std::uint32_t huge = 0xFFFFFFF0U;
  std::memcpy(cdr.data() + kLayersCount, &huge, sizeof(huge));
  const auto decoded = decodeGridMap(cdr);
  ASSERT_FALSE(decoded.has_value());
  EXPECT_EQ(decoded.error(), GridMapError::kTruncated);
}

TEST(DecodeGridMap, RefusesAStringWithoutItsNul) {
  test::CdrTestWriter w;
  w.i32(1);
  w.u32(2);
  w.u32(4);  // frame_id of length 4 ("abc" + NUL) whose last byte is not NUL
  for (const char c : std::string("abcd")) {
    w.u8(static_cast<std::uint8_t>(c));
  }
  for (int i = 0; i < 64; ++i) {
    w.f64(0.0);
  }
  const auto decoded = decodeGridMap(w.data());
  ASSERT_FALSE(decoded.has_value());
  EXPECT_EQ(decoded.error(), GridMapError::kMalformed);
}

TEST(DecodeGridMap, RefusesLayersWithoutOneArrayEach) {
  HandMap hand;
  hand.arrays = 1;
  const auto decoded = decodeGridMap(encodeHandMap(hand));
  ASSERT_FALSE(decoded.has_value());
  EXPECT_EQ(decoded.error(), GridMapError::kLayerCountMismatch);
}

TEST(DecodeGridMap, RefusesArraysWhoseDimensionsDoNotMatchTheirData) {
  HandMap too_few;
  too_few.values = 5;  // 2 x 3 dims
  EXPECT_EQ(decodeGridMap(encodeHandMap(too_few)).error(), GridMapError::kLayoutMismatch);
  HandMap one_dim;
  one_dim.dim_sizes = {6};
  EXPECT_EQ(decodeGridMap(encodeHandMap(one_dim)).error(), GridMapError::kLayoutMismatch);
  HandMap offset_past;
  offset_past.data_offset = 1;  // 6 cells after an offset of 1 need 7 values
  EXPECT_EQ(decodeGridMap(encodeHandMap(offset_past)).error(), GridMapError::kLayoutMismatch);
}

TEST(DecodeGridMap, SurvivesRandomAndMutatedBytes) {
  const std::vector<std::byte> good = cycloneGridMapBytes();
  ASSERT_FALSE(good.empty());
  std::mt19937 random(1234);
  int decoded_count = 0;
  for (int round = 0; round < 3000; ++round) {
    std::vector<std::byte> cdr;
    if (round % 2 == 0) {
      // random bytes behind a valid header
      cdr.resize(4 + random() % 600);
      for (std::byte& b : cdr) {
        b = static_cast<std::byte>(random() & 0xFF);
      }
      cdr[0] = std::byte{0};
      cdr[1] = std::byte{static_cast<std::uint8_t>(random() & 1)};
    } else {
      // the good message with a few bytes flipped
      cdr = good;
      for (int flips = 0; flips < 4; ++flips) {
        cdr[4 + random() % (cdr.size() - 4)] = static_cast<std::byte>(random() & 0xFF);
      }
    }
    const auto decoded = decodeGridMap(cdr);  // must not crash or read out of bounds (ASan)
    decoded_count += decoded.has_value() ? 1 : 0;
  }
  // Some flips only change values: those still decode.
  EXPECT_GT(decoded_count, 0);
}

TEST(LayerStats, CountsFiniteValuesAndTheirRange) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<float> values = {nan, 1.5F, -2.0F, inf, 0.25F, -inf};
  const LayerStats stats = layerStats(values);
  EXPECT_EQ(stats.cells, 6U);
  EXPECT_EQ(stats.finite, 3U);
  EXPECT_EQ(stats.min, -2.0F);
  EXPECT_EQ(stats.max, 1.5F);

  const std::vector<float> unknown = {nan, nan, inf};
  const LayerStats none = layerStats(unknown);
  EXPECT_EQ(none.cells, 3U);
  EXPECT_EQ(none.finite, 0U);
  EXPECT_TRUE(std::isnan(none.min));
  EXPECT_TRUE(std::isnan(none.max));
  EXPECT_EQ(layerStats({}).cells, 0U);
}

TEST(GridMapError, HasStableNames) {
  EXPECT_STREQ(toString(GridMapError::kTruncated), "truncated");
  EXPECT_STREQ(toString(GridMapError::kBadEncapsulation), "bad_encapsulation");
  EXPECT_STREQ(toString(GridMapError::kMalformed), "malformed");
  EXPECT_STREQ(toString(GridMapError::kLayerCountMismatch), "layer_count_mismatch");
  EXPECT_STREQ(toString(GridMapError::kLayoutMismatch), "layout_mismatch");
}

}  // namespace
}  // namespace raymap::dds
