// SPDX-License-Identifier: BSD-3-Clause
// The publishing loop: /tf_static once, then odometry and scans on absolute schedules.
#include "tests/fastdds/peer/publish_mode.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <thread>
#include <vector>

#include "nav_msgsPubSubTypes.h"
#include "sensor_msgsPubSubTypes.h"
#include "tf2_msgsPubSubTypes.h"
#include <fastdds/dds/core/status/PublicationMatchedStatus.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>

#include "tests/fastdds/peer/cloud_message.hpp"
#include "tests/fastdds/peer/ros_qos.hpp"
#include "tests/fastdds/peer/stop_signal.hpp"

namespace raymap::fastdds_peer {
namespace dds = eprosima::fastdds::dds;
using Clock = std::chrono::steady_clock;

namespace {

struct Writers {
  dds::DataWriter* cloud = nullptr;
  dds::DataWriter* odometry = nullptr;
  dds::DataWriter* tf_static = nullptr;
};

dds::DataWriter* makeWriter(PeerParticipant& participant, const std::string& topic_name,
                            dds::TopicDataType* type, RosProfile profile) {
  dds::Topic* topic = participant.topic(topic_name, type);
  return topic == nullptr ? nullptr
                          : participant.publisher().create_datawriter(topic, writerQos(profile));
}

std::int64_t matchedReaders(dds::DataWriter* writer) {
  dds::PublicationMatchedStatus status;
  writer->get_publication_matched_status(status);
  return status.current_count;
}

/// Where the clock of the run maps to Unix time, and the robot at any instant of it.
class Timeline {
 public:
  explicit Timeline(const PublishOptions& options)
      : start_(Clock::now()),
        unix_start_ns_(std::chrono::duration_cast<std::chrono::nanoseconds>(
                           std::chrono::system_clock::now().time_since_epoch())
                           .count()),
        speed_mps_(options.speed_mps) {}
  Clock::time_point start() const { return start_; }
  std::int64_t unixNs(Clock::time_point t) const {
    return unix_start_ns_ +
           std::chrono::duration_cast<std::chrono::nanoseconds>(t - start_).count();
  }
  Vec3 base(Clock::time_point t) const {
    const double t_s = std::chrono::duration<double>(t - start_).count();
    return {kBaseStart.x + speed_mps_ * t_s, kBaseStart.y, kBaseStart.z};
  }

 private:
  Clock::time_point start_;
  std::int64_t unix_start_ns_;
  double speed_mps_;
};

void publishTfStatic(dds::DataWriter& writer, const PublishOptions& options,
                     std::int64_t stamp_ns) {
  geometry_msgs::msg::dds_::TransformStamped_ edge;
  edge.header().stamp(rosTime(stamp_ns));
  edge.header().frame_id(options.base_frame);
  edge.child_frame_id(options.lidar_frame);
  edge.transform().translation().x(kLidarInBase.x);
  edge.transform().translation().y(kLidarInBase.y);
  edge.transform().translation().z(kLidarInBase.z);
  edge.transform().rotation().w(1.0);
  tf2_msgs::msg::dds_::TFMessage_ message;
  message.transforms().push_back(edge);
  writer.write(&message);
}

void publishOdometry(dds::DataWriter& writer, const PublishOptions& options, Vec3 base,
                     std::int64_t stamp_ns) {
  nav_msgs::msg::dds_::Odometry_ odometry;
  odometry.header().stamp(rosTime(stamp_ns));
  odometry.header().frame_id(options.world_frame);
  odometry.child_frame_id(options.base_frame);
  odometry.pose().pose().position().x(base.x);
  odometry.pose().pose().position().y(base.y);
  odometry.pose().pose().position().z(base.z);
  odometry.pose().pose().orientation().w(1.0);
  odometry.twist().twist().linear().x(options.speed_mps);
  writer.write(&odometry);
}

/// True once at least `readers` readers matched the writer and every matched reader
/// acknowledged everything it wrote.
bool acknowledged(dds::DataWriter& writer, std::int64_t readers) {
  return matchedReaders(&writer) >= std::max<std::int64_t>(readers, 1) &&
         writer.wait_for_acknowledgments(eprosima::fastrtps::Duration_t(0, 0)) ==
             eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK;
}

std::chrono::nanoseconds periodOf(double rate_hz) {
  return std::chrono::nanoseconds(std::llround(1e9 / rate_hz));
}

/// The next instant of a schedule after `due`, skipping those already past `now` (a machine
/// that fell behind publishes the newest, as a driver would, not a burst of old ones).
Clock::time_point nextDue(Clock::time_point due, std::chrono::nanoseconds period,
                          Clock::time_point now) {
  due += period;
  while (due + period <= now) {
    due += period;
  }
  return due;
}

}  // namespace

bool runPublish(PeerParticipant& participant, const PublishOptions& options, Json& result) {
  Writers writers;
  writers.cloud =
      makeWriter(participant, options.points_topic,
                 new sensor_msgs::msg::dds_::PointCloud2_PubSubType(), RosProfile::kSensorData);
  writers.odometry =
      makeWriter(participant, options.odom_topic, new nav_msgs::msg::dds_::Odometry_PubSubType(),
                 RosProfile::kDefault);
  writers.tf_static =
      makeWriter(participant, options.tf_static_topic,
                 new tf2_msgs::msg::dds_::TFMessage_PubSubType(), RosProfile::kStaticTf);
  if (writers.cloud == nullptr || writers.odometry == nullptr || writers.tf_static == nullptr) {
    result["error"] = "Fast DDS refused a writer";
    return false;
  }
  RoomLidar lidar = options.lidar;
  lidar.scan_period_s = 1.0 / options.scan_rate_hz;
  const std::chrono::nanoseconds scan_period = periodOf(options.scan_rate_hz);
  const std::chrono::nanoseconds odometry_period = periodOf(options.odometry_rate_hz);

  const Timeline timeline(options);
  publishTfStatic(*writers.tf_static, options, timeline.unixNs(timeline.start()));
  std::vector<LidarPoint> points;
  sensor_msgs::msg::dds_::PointCloud2_ cloud;
  std::int64_t clouds = 0;
  std::int64_t odometry = 0;
  Clock::time_point next_odometry = timeline.start();
  Clock::time_point scan_start = timeline.start();  // published once its revolution is over
  const Clock::time_point lidar_end =
      timeline.start() + std::chrono::nanoseconds(std::llround(options.seconds * 1e9));
  const Clock::time_point end =
      lidar_end + std::chrono::nanoseconds(std::llround(options.odometry_tail_s * 1e9));
  std::optional<Clock::time_point> tf_static_acknowledged;
  std::optional<std::int64_t> odometry_when_matched;  // messages written before they all matched
  bool lidar_started = false;
  for (Clock::time_point now = Clock::now(); now < end && !stopRequested(); now = Clock::now()) {
    if (!tf_static_acknowledged && acknowledged(*writers.tf_static, options.readers)) {
      tf_static_acknowledged = now;
    }
    if (!odometry_when_matched && matchedReaders(writers.odometry) >= options.readers) {
      odometry_when_matched = odometry;
    }
    // Once started, the lidar runs whoever comes and goes.
    lidar_started = lidar_started || !options.clouds_after_tf_static ||
                    (tf_static_acknowledged && matchedReaders(writers.cloud) >= options.readers &&
                     odometry_when_matched && odometry > *odometry_when_matched);
    if (now >= next_odometry) {
      publishOdometry(*writers.odometry, options, timeline.base(next_odometry),
                      timeline.unixNs(next_odometry));
      ++odometry;
      next_odometry = nextDue(next_odometry, odometry_period, now);
    }
    if (!lidar_started || now >= lidar_end) {
      scan_start = now;  // the lidar has not started yet, or has stopped
    } else if (now >= scan_start + scan_period) {
      const Vec3 base = timeline.base(scan_start);
      const Vec3 origin{base.x + kLidarInBase.x, base.y + kLidarInBase.y, base.z + kLidarInBase.z};
      sweep(lidar, origin, Vec3{options.speed_mps, 0.0, 0.0}, points);
      fillCloud(points, timeline.unixNs(scan_start), options.lidar_frame, cloud);
      writers.cloud->write(&cloud);
      ++clouds;
      scan_start = nextDue(scan_start, scan_period, now - scan_period);
    }
    const Clock::time_point next_scan = now < lidar_end ? scan_start + scan_period : end;
    std::this_thread::sleep_until(std::min({next_odometry, next_scan, end}));
  }
  const double elapsed_s = std::chrono::duration<double>(Clock::now() - timeline.start()).count();
  result["seconds"] = elapsed_s;
  result["clouds_published"] = clouds;
  result["points_per_cloud"] = points.size();
  result["odometry_published"] = odometry;
  result["tf_static_published"] = 1;
  result["tf_static_acknowledged_after_ms"] =  // null when it never was
      tf_static_acknowledged
          ? std::chrono::duration<double, std::milli>(*tf_static_acknowledged - timeline.start())
                .count()
          : std::nan("");
  result["cloud_readers"] = matchedReaders(writers.cloud);
  result["odometry_readers"] = matchedReaders(writers.odometry);
  result["tf_static_readers"] = matchedReaders(writers.tf_static);
  return true;
}

}  // namespace raymap::fastdds_peer
