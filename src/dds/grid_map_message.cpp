// SPDX-License-Identifier: BSD-3-Clause
// The preallocated GridMap message: every sequence points into buffers owned by the Impl, with
// _release false so that Cyclone never frees them.
#include "src/dds/grid_map_message.hpp"

#include <cstring>
#include <vector>

#include "grid_map_msgs.h"
#include "raymap/assert.hpp"

#include "src/dds/frame_id.hpp"
#include "src/dds/ros_time.hpp"
#include "src/dds/topic_types.hpp"

namespace raymap::dds {
namespace {

constexpr std::size_t kBaseLayers = 4;
constexpr std::size_t kLayers = kGridLayerCount;  // at most: every layer

/// idlc declares strings as char*; the message only reads them.
char* mutableText(const char* text) noexcept {
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): C API
  return const_cast<char*>(text);
}

}  // namespace

const char* gridLayerName(GridLayer layer) noexcept {
  const auto i = static_cast<std::size_t>(layer);
  return i < kBaseLayers ? GridMapMessage::kLayerNames[i]
                         : GridMapMessage::kNormalLayerNames[i - kBaseLayers];
}

std::optional<GridLayer> gridLayerNamed(std::string_view name) noexcept {
  for (std::size_t i = 0; i < kGridLayerCount; ++i) {
    const auto layer = static_cast<GridLayer>(i);
    if (name == gridLayerName(layer)) {
      return layer;
    }
  }
  return std::nullopt;
}

GridLayerSet GridLayerSet::all(bool with_normals) noexcept {
  GridLayerSet set;
  for (std::size_t i = 0; i < (with_normals ? kGridLayerCount : kBaseLayers); ++i) {
    set.add(static_cast<GridLayer>(i));
  }
  return set;
}

bool GridLayerSet::hasNormals() const noexcept {
  return has(GridLayer::kNormalX) || has(GridLayer::kNormalY) || has(GridLayer::kNormalZ);
}

std::size_t GridLayerSet::count() const noexcept {
  std::size_t n = 0;
  for (std::size_t i = 0; i < kGridLayerCount; ++i) {
    n += has(static_cast<GridLayer>(i)) ? 1u : 0u;
  }
  return n;
}

/// Design: one heap block per message, so that moving a GridMapMessage moves a pointer and the
/// addresses inside `msg` stay valid. Only fill() writes it; Writer::write() reads it.
struct GridMapMessage::Impl {
  int cells_x = 0;
  int cells_y = 0;
  std::size_t layer_count = kBaseLayers;
  GridLayerSet chosen;
  GridLayer layer_of[kLayers] = {};  // what each of the message's layers is
  grid_map_msgs_msg_dds__GridMap_ msg{};
  char frame_id[64] = {};
  char* layer_names[kLayers] = {};
  char* basic_layers[1] = {};
  std_msgs_msg_dds__Float32MultiArray_ arrays[kLayers]{};
  std_msgs_msg_dds__MultiArrayDimension_ dims[kLayers][2]{};
  std::vector<float> data[kLayers];
};

GridMapMessage::GridMapMessage(int cells_x, int cells_y, bool with_normals)
    : GridMapMessage(cells_x, cells_y, GridLayerSet::all(with_normals)) {}

GridMapMessage::GridMapMessage(int cells_x, int cells_y, GridLayerSet layers)
    : impl_(std::make_unique<Impl>()) {
  RAYMAP_EXPECTS(cells_x > 0 && cells_y > 0 && !layers.empty());
  Impl& m = *impl_;
  m.cells_x = cells_x;
  m.cells_y = cells_y;
  m.chosen = layers;
  m.layer_count = 0;
  for (std::size_t i = 0; i < kGridLayerCount; ++i) {
    if (layers.has(static_cast<GridLayer>(i))) {
      m.layer_of[m.layer_count++] = static_cast<GridLayer>(i);
    }
  }
  const auto size_x = static_cast<std::uint32_t>(cells_x);
  const auto size_y = static_cast<std::uint32_t>(cells_y);
  const std::size_t cells = std::size_t{size_x} * size_y;

  m.msg.header.frame_id = m.frame_id;
  m.msg.info.pose.orientation.w = 1.0;
  for (std::size_t i = 0; i < m.layer_count; ++i) {
    m.layer_names[i] = mutableText(gridLayerName(m.layer_of[i]));
    m.data[i].assign(cells, 0.0F);
    auto& dims = m.dims[i];
    dims[0].label = mutableText("column_index");
    dims[0].size = size_y;
    dims[0].stride = static_cast<std::uint32_t>(cells);
    dims[1].label = mutableText("row_index");
    dims[1].size = size_x;
    dims[1].stride = size_x;
    auto& array = m.arrays[i];
    array.layout.dim._buffer = dims;
    array.layout.dim._length = 2;
    array.layout.dim._maximum = 2;
    array.layout.dim._release = false;
    array.layout.data_offset = 0;
    array.data._buffer = m.data[i].data();
    array.data._length = static_cast<std::uint32_t>(cells);
    array.data._maximum = static_cast<std::uint32_t>(cells);
    array.data._release = false;
  }
  m.basic_layers[0] = mutableText(gridLayerName(GridLayer::kElevation));
  m.msg.layers._buffer = m.layer_names;
  m.msg.layers._length = static_cast<std::uint32_t>(m.layer_count);
  m.msg.layers._maximum = static_cast<std::uint32_t>(m.layer_count);
  m.msg.layers._release = false;
  m.msg.basic_layers._buffer = m.basic_layers;
  m.msg.basic_layers._length = layers.has(GridLayer::kElevation) ? 1 : 0;
  m.msg.basic_layers._maximum = 1;
  m.msg.basic_layers._release = false;
  m.msg.data._buffer = m.arrays;
  m.msg.data._length = static_cast<std::uint32_t>(m.layer_count);
  m.msg.data._maximum = static_cast<std::uint32_t>(m.layer_count);
  m.msg.data._release = false;
  m.msg.outer_start_index = 0;
  m.msg.inner_start_index = 0;
}

GridMapMessage::GridMapMessage(GridMapMessage&&) noexcept = default;
GridMapMessage& GridMapMessage::operator=(GridMapMessage&&) noexcept = default;
GridMapMessage::~GridMapMessage() = default;

void GridMapMessage::fill(const heightmap::HeightMap& map, std::int64_t stamp_ns,
                          const char* frame_id) noexcept {
  RAYMAP_EXPECTS(impl_ != nullptr);
  Impl& m = *impl_;
  RAYMAP_EXPECTS(map.cells_x == m.cells_x && map.cells_y == m.cells_y);
  const std::size_t cells = map.cellCount();
  RAYMAP_EXPECTS(map.elevation.size() == cells && map.clearance.size() == cells &&
                 map.kind.size() == cells && map.observed_count.size() == cells);

  setRosTime(m.msg.header.stamp, stamp_ns);
  copyFrameId(m.frame_id, frame_id);

  // geometry: pose = the grid centre
  m.msg.info.resolution = map.resolution;
  m.msg.info.length_x = map.cells_x * map.resolution;
  m.msg.info.length_y = map.cells_y * map.resolution;
  m.msg.info.pose.position.x = map.centre_x;
  m.msg.info.pose.position.y = map.centre_y;
  m.msg.info.pose.position.z = 0.0;

  // layers: HeightMap is column-major with (0, 0) at +x/+y, as grid_map
  if (m.chosen.hasNormals()) {
    RAYMAP_EXPECTS(map.has_normals && map.normal_x.size() == cells &&
                   map.normal_y.size() == cells && map.normal_z.size() == cells);
  }
  const auto copy = [cells](float* out, const std::vector<float>& in) {
    std::memcpy(out, in.data(), cells * sizeof(float));
  };
  for (std::size_t l = 0; l < m.layer_count; ++l) {
    float* out = m.data[l].data();
    switch (m.layer_of[l]) {
      case GridLayer::kElevation:
        copy(out, map.elevation);
        break;
      case GridLayer::kClearance:
        copy(out, map.clearance);
        break;
      case GridLayer::kKind:
        for (std::size_t i = 0; i < cells; ++i) {
          out[i] = static_cast<float>(map.kind[i]);
        }
        break;
      case GridLayer::kObservedCount:
        for (std::size_t i = 0; i < cells; ++i) {
          out[i] = static_cast<float>(map.observed_count[i]);
        }
        break;
      case GridLayer::kNormalX:
        copy(out, map.normal_x);
        break;
      case GridLayer::kNormalY:
        copy(out, map.normal_y);
        break;
      case GridLayer::kNormalZ:
        copy(out, map.normal_z);
        break;
    }
  }
}

const void* GridMapMessage::sample() const noexcept { return &impl_->msg; }

const dds_topic_descriptor_t* GridMapMessage::descriptor() noexcept { return gridMapType(); }

int GridMapMessage::cellsX() const noexcept { return impl_->cells_x; }
int GridMapMessage::cellsY() const noexcept { return impl_->cells_y; }
bool GridMapMessage::withNormals() const noexcept { return impl_->chosen.hasNormals(); }
GridLayerSet GridMapMessage::layers() const noexcept { return impl_->chosen; }

}  // namespace raymap::dds
