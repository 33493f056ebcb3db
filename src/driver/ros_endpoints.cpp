// SPDX-License-Identifier: BSD-3-Clause
// DriverPublisher and the GridMap / diagnostics listeners over Cyclone's C API.
#include "src/driver/ros_endpoints.hpp"

#include <cstdlib>
#include <cstring>

#include "diagnostic_msgs.h"
#include "grid_map_msgs.h"
#include "nav_msgs.h"
#include "tf2_msgs.h"

#include "platform/clock.hpp"
#include "src/dds/ros_time.hpp"
#include "src/dds/topic_types.hpp"

namespace raymap::driver {
namespace {

Expected<dds_entity_t, Error> reliableReader(const dds::Participant& participant,
                                             const std::string& topic_name,
                                             const dds_topic_descriptor_t* type,
                                             dds_entity_t* topic) {
  *topic = dds_create_topic(participant.handle(), type, topic_name.c_str(), nullptr, nullptr);
  if (*topic < 0) {
    return fail(ErrorCode::kIo,
                topic_name + ": cannot create the topic: " + dds_strretcode(*topic));
  }
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 50);
  dds_data_representation_id_t xcdr1[1] = {DDS_DATA_REPRESENTATION_XCDR1};
  dds_qset_data_representation(qos, 1, xcdr1);
  const dds_entity_t reader = dds_create_reader(participant.handle(), *topic, qos, nullptr);
  dds_delete_qos(qos);
  if (reader < 0) {
    return fail(ErrorCode::kIo, topic_name + ": cannot create a reader: " + dds_strretcode(reader));
  }
  return reader;
}

}  // namespace

// ---------------------------------------------------------------- publisher

Result<std::unique_ptr<DriverPublisher>> DriverPublisher::create(
    const dds::Participant& participant, const std::string& cloud_topic,
    const std::string& odometry_topic, std::uint32_t max_points) {
  std::unique_ptr<DriverPublisher> p(new DriverPublisher());
  auto cloud = dds::Writer::create(participant, cloud_topic.c_str(), dds::pointCloud2Type(),
                                   dds::Reliability::kBestEffort, 5);
  if (!cloud) {
    return Unexpected(cloud.error());
  }
  p->cloud_writer_.emplace(std::move(cloud).value());
  auto odometry = dds::Writer::create(participant, odometry_topic.c_str(), dds::odometryType(),
                                      dds::Reliability::kBestEffort, 50);
  if (!odometry) {
    return Unexpected(odometry.error());
  }
  p->odometry_writer_.emplace(std::move(odometry).value());
  auto tf = dds::Writer::create(participant, "rt/tf", dds::tfMessageType(),
                                dds::Reliability::kReliable, 100);
  if (!tf) {
    return Unexpected(tf.error());
  }
  p->tf_writer_.emplace(std::move(tf).value());
  auto tf_static =
      dds::Writer::create(participant, "rt/tf_static", dds::tfMessageType(),
                          dds::Reliability::kReliable, 1, dds::Durability::kTransientLocal);
  if (!tf_static) {
    return Unexpected(tf_static.error());
  }
  p->tf_static_writer_.emplace(std::move(tf_static).value());
  dds::CloudLayout layout;
  layout.intensity = true;
  layout.time = true;
  layout.ring = true;
  p->cloud_ = std::make_unique<dds::PointCloudMessage>(max_points, layout);
  return p;
}

void DriverPublisher::reserveCloud(std::uint32_t points) {
  if (points > cloud_->capacity()) {
    cloud_ = std::make_unique<dds::PointCloudMessage>(points, cloud_->layout());
  }
}

void DriverPublisher::publishCloud(std::span<const msgs::ScanPoint> points,
                                   std::span<const std::uint16_t> rings, std::int64_t stamp_ns,
                                   const char* frame_id) {
  cloud_->fill(points, rings, stamp_ns, frame_id);
  (void)cloud_writer_->write(cloud_->sample());
}

void DriverPublisher::publishOdometry(std::int64_t stamp_ns, const io::Pose& pose,
                                      const char* world_frame, const char* base_frame) {
  nav_msgs_msg_dds__Odometry_ m{};
  dds::setRosTime(m.header.stamp, stamp_ns);
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): read-only for dds_write
  m.header.frame_id = const_cast<char*>(world_frame);
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): read-only for dds_write
  m.child_frame_id = const_cast<char*>(base_frame);
  m.pose.pose.position = {pose.position.x(), pose.position.y(), pose.position.z()};
  m.pose.pose.orientation = {pose.orientation.x(), pose.orientation.y(), pose.orientation.z(),
                             pose.orientation.w()};
  (void)odometry_writer_->write(&m);
}

namespace {

/// A TransformStamped pointing at `parent` and `child` (which must outlive its write).
geometry_msgs_msg_dds__TransformStamped_ transformStamped(std::int64_t stamp_ns,
                                                          const io::Pose& pose, const char* parent,
                                                          const char* child) {
  geometry_msgs_msg_dds__TransformStamped_ t{};
  dds::setRosTime(t.header.stamp, stamp_ns);
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): read-only for dds_write
  t.header.frame_id = const_cast<char*>(parent);
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-const-cast): read-only for dds_write
  t.child_frame_id = const_cast<char*>(child);
  t.transform.translation = {pose.position.x(), pose.position.y(), pose.position.z()};
  t.transform.rotation = {pose.orientation.x(), pose.orientation.y(), pose.orientation.z(),
                          pose.orientation.w()};
  return t;
}

void writeTransform(dds::Writer& writer, std::int64_t stamp_ns, const io::Pose& pose,
                    const char* parent, const char* child) {
  geometry_msgs_msg_dds__TransformStamped_ t = transformStamped(stamp_ns, pose, parent, child);
  tf2_msgs_msg_dds__TFMessage_ m{};
  m.transforms._buffer = &t;
  m.transforms._length = m.transforms._maximum = 1;
  (void)writer.write(&m);
}

}  // namespace

void DriverPublisher::publishTf(std::int64_t stamp_ns, const io::Pose& pose,
                                const char* world_frame, const char* base_frame) {
  writeTransform(*tf_writer_, stamp_ns, pose, world_frame, base_frame);
}

void DriverPublisher::publishTfStatic(const io::Pose& pose, const char* parent, const char* child) {
  writeTransform(*tf_static_writer_, 0, pose, parent, child);
}

void DriverPublisher::publishTfStatic(std::span<const StaticEdge> edges) {
  std::vector<geometry_msgs_msg_dds__TransformStamped_> transforms;
  transforms.reserve(edges.size());
  for (const StaticEdge& edge : edges) {
    transforms.push_back(transformStamped(0, edge.pose, edge.parent, edge.child));
  }
  tf2_msgs_msg_dds__TFMessage_ m{};
  m.transforms._buffer = transforms.data();
  m.transforms._length = m.transforms._maximum = static_cast<std::uint32_t>(transforms.size());
  (void)tf_static_writer_->write(&m);
}

// ---------------------------------------------------------------- GridMap

const std::vector<float>* ReceivedGridMap::layer(const std::string& name) const {
  for (std::size_t i = 0; i < layers.size() && i < data.size(); ++i) {
    if (layers[i] == name) {
      return &data[i];
    }
  }
  return nullptr;
}

Result<std::unique_ptr<GridMapListener>> GridMapListener::create(
    const dds::Participant& participant, const std::string& topic) {
  std::unique_ptr<GridMapListener> l(new GridMapListener());
  auto reader = reliableReader(participant, topic, dds::gridMapType(), &l->topic_);
  if (!reader) {
    return Unexpected(reader.error());
  }
  l->reader_ = reader.value();
  l->waitset_ = dds_create_waitset(participant.handle());
  l->condition_ = dds_create_readcondition(l->reader_, DDS_ANY_STATE);
  dds_waitset_attach(l->waitset_, l->condition_, 0);
  return l;
}

GridMapListener::~GridMapListener() {
  if (waitset_ > 0) {
    dds_delete(waitset_);
  }
  if (reader_ > 0) {
    dds_delete(reader_);
  }
}

std::uint32_t GridMapListener::matchedWriters() const noexcept {
  dds_subscription_matched_status_t status{};
  return dds_get_subscription_matched_status(reader_, &status) == DDS_RETCODE_OK
             ? status.current_count
             : 0u;
}

int GridMapListener::poll(std::int64_t timeout_ns, std::vector<ReceivedGridMap>& out) {
  dds_attach_t triggered[1];
  dds_waitset_wait(waitset_, triggered, 1, timeout_ns);
  int taken_total = 0;
  for (;;) {
    void* samples[1] = {nullptr};
    dds_sample_info_t info[1];
    const int n = dds_take(reader_, samples, info, 1, 1);
    if (n <= 0) {
      break;
    }
    const std::int64_t arrival = platform::monotonicNowNs();
    if (info[0].valid_data) {
      const auto* m = static_cast<const grid_map_msgs_msg_dds__GridMap_*>(samples[0]);
      ReceivedGridMap r;
      r.arrival_ns = arrival;
      r.stamp_ns = msgs::nanosecondsOf(m->header.stamp.sec, m->header.stamp.nanosec);
      r.frame_id = m->header.frame_id != nullptr ? m->header.frame_id : "";
      r.resolution = m->info.resolution;
      r.length_x = m->info.length_x;
      r.length_y = m->info.length_y;
      r.centre_x = m->info.pose.position.x;
      r.centre_y = m->info.pose.position.y;
      for (std::uint32_t i = 0; i < m->layers._length; ++i) {
        r.layers.emplace_back(m->layers._buffer[i]);
      }
      for (std::uint32_t i = 0; i < m->basic_layers._length; ++i) {
        r.basic_layers.emplace_back(m->basic_layers._buffer[i]);
      }
      for (std::uint32_t i = 0; i < m->data._length; ++i) {
        const std_msgs_msg_dds__Float32MultiArray_& a = m->data._buffer[i];
        r.data.emplace_back(a.data._buffer, a.data._buffer + a.data._length);
        if (i == 0) {
          for (std::uint32_t d = 0; d < a.layout.dim._length; ++d) {
            const auto& dim = a.layout.dim._buffer[d];
            r.dim_labels.emplace_back(dim.label != nullptr ? dim.label : "");
            r.dim_sizes.push_back(dim.size);
            r.dim_strides.push_back(dim.stride);
          }
        }
      }
      out.push_back(std::move(r));
      ++taken_total;
    }
    dds_return_loan(reader_, samples, n);
  }
  return taken_total;
}

// ---------------------------------------------------------------- diagnostics

Result<std::unique_ptr<DiagnosticsListener>> DiagnosticsListener::create(
    const dds::Participant& participant, const std::string& topic) {
  std::unique_ptr<DiagnosticsListener> l(new DiagnosticsListener());
  auto reader = reliableReader(participant, topic, dds::diagnosticArrayType(), &l->topic_);
  if (!reader) {
    return Unexpected(reader.error());
  }
  l->reader_ = reader.value();
  return l;
}

DiagnosticsListener::~DiagnosticsListener() {
  if (reader_ > 0) {
    dds_delete(reader_);
  }
}

int DiagnosticsListener::poll() {
  int arrays = 0;
  for (;;) {
    void* samples[1] = {nullptr};
    dds_sample_info_t info[1];
    const int n = dds_take(reader_, samples, info, 1, 1);
    if (n <= 0) {
      break;
    }
    if (info[0].valid_data) {
      const auto* m = static_cast<const diagnostic_msgs_msg_dds__DiagnosticArray_*>(samples[0]);
      for (std::uint32_t s = 0; s < m->status._length; ++s) {
        const auto& status = m->status._buffer[s];
        const std::string name = status.name != nullptr ? status.name : "";
        values_[name + "/level"] = std::to_string(status.level);
        values_[name + "/message"] = status.message != nullptr ? status.message : "";
        values_[name + "/hardware_id"] = status.hardware_id != nullptr ? status.hardware_id : "";
        for (std::uint32_t v = 0; v < status.values._length; ++v) {
          const auto& kv = status.values._buffer[v];
          values_[name + "/" + (kv.key != nullptr ? kv.key : "")] =
              kv.value != nullptr ? kv.value : "";
        }
      }
      ++arrays;
    }
    dds_return_loan(reader_, samples, n);
  }
  return arrays;
}

std::optional<double> DiagnosticsListener::number(const std::string& key) const {
  const auto at = values_.find(key);
  if (at == values_.end()) {
    return std::nullopt;
  }
  char* end = nullptr;
  const double value = std::strtod(at->second.c_str(), &end);
  if (end == at->second.c_str()) {
    return std::nullopt;
  }
  return value;
}

}  // namespace raymap::driver
