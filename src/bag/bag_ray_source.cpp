// SPDX-License-Identifier: BSD-3-Clause
// BagRaySource: the bag read in recording order; clouds wait (in bag time) for the poses that
// cover them, as raymapd's integrator does, and are then deskewed point by point.
#include "src/bag/bag_ray_source.hpp"

#include <algorithm>
#include <deque>
#include <optional>
#include <set>
#include <utility>

#include "src/msgs/point_cloud.hpp"
#include "src/msgs/pose.hpp"
#include "src/msgs/ros_names.hpp"
#include "src/pipeline/deskew.hpp"
#include "src/pipeline/pipeline_stats.hpp"
#include "src/pipeline/pose_history.hpp"
#include "src/pipeline/sensor_decoder.hpp"
#include "src/pipeline/tf_router.hpp"

namespace raymap::bag {
namespace {

constexpr const char* kPointCloud2 = "sensor_msgs/msg/PointCloud2";
constexpr const char* kImage = "sensor_msgs/msg/Image";
constexpr const char* kCameraInfo = "sensor_msgs/msg/CameraInfo";
constexpr const char* kOdometry = "nav_msgs/msg/Odometry";
constexpr const char* kTfMessage = "tf2_msgs/msg/TFMessage";
constexpr std::size_t kSkipsKept = 8;
constexpr std::size_t kFirstPointCapacity = std::size_t{1} << 18;

std::string topicsOfType(const std::vector<BagTopic>& topics, const std::string& type) {
  std::string list;
  for (const BagTopic& t : topics) {
    if (t.type == type) {
      list += (list.empty() ? "" : ", ") + t.name;
    }
  }
  return list.empty() ? "none" : list;
}

/// Every topic of the bag with its type: "/odom (nav_msgs/msg/Odometry), ...".
std::string topicsWithTypes(const std::vector<BagTopic>& topics) {
  std::string list;
  for (const BagTopic& t : topics) {
    list += (list.empty() ? "" : ", ") + t.name + " (" + t.type + ")";
  }
  return list.empty() ? "none" : list;
}

/// The index of the topic `name` names: the bag's topic of that name, else, for a DDS name
/// (rt/points, as raymapd's configuration and replay take them), its ROS topic (/points); -1.
int findBagTopic(const BagReader& bag, const std::string& name) {
  const int at = findTopic(bag.topics(), name);
  const std::string ros = msgs::rosTopicName(name);
  return at >= 0 || ros.empty() ? at : findTopic(bag.topics(), ros);
}

/// The index of the topic named `name`, checked to be of `type`.
Result<std::uint32_t> topicOfType(const BagReader& bag, const std::string& name,
                                  const std::string& type, const char* option) {
  const int at = findBagTopic(bag, name);
  if (at < 0) {
    return fail(ErrorCode::kInvalidArgument,
                std::string(option) + ": " + bag.path() + " has no topic '" + name + "' (its " +
                    type + " topics: " + topicsOfType(bag.topics(), type) + ")");
  }
  const BagTopic& t = bag.topics()[static_cast<std::size_t>(at)];
  if (t.type != type) {
    return fail(ErrorCode::kInvalidArgument, std::string(option) + ": topic '" + name + "' in " +
                                                 bag.path() + " is " + t.type + ", not " + type);
  }
  if (!t.serialization_format.empty() && t.serialization_format != "cdr") {
    return fail(ErrorCode::kUnsupported, bag.path() + ": topic '" + name + "' is serialized as '" +
                                             t.serialization_format + "'; raymap reads cdr");
  }
  return static_cast<std::uint32_t>(at);
}

/// The only topic of `type`, or an error listing them.
Result<std::uint32_t> onlyTopicOfType(const BagReader& bag, const std::string& type,
                                      const char* option) {
  int found = -1;
  for (std::size_t i = 0; i < bag.topics().size(); ++i) {
    if (bag.topics()[i].type == type) {
      if (found >= 0) {
        return fail(ErrorCode::kInvalidArgument, bag.path() + " has several " + type + " topics (" +
                                                     topicsOfType(bag.topics(), type) +
                                                     "): choose with " + option);
      }
      found = static_cast<int>(i);
    }
  }
  if (found < 0) {
    return fail(ErrorCode::kInvalidArgument,
                bag.path() + " has no " + type +
                    " topic (its topics: " + topicsWithTypes(bag.topics()) + ")");
  }
  return topicOfType(bag, bag.topics()[static_cast<std::size_t>(found)].name, type, option);
}

class BagRays final : public BagRaySource, private pipeline::PoseSink {
 public:
  BagRays(std::unique_ptr<BagReader> bag, const BagRaysOptions& options)
      : bag_(std::move(bag)), options_(options), history_(options.pose_history) {}

  Expected<void, Error> open() {
    if (auto ok = chooseCloudTopics(); !ok) {
      return ok;
    }
    if (auto ok = setUpDecoders(); !ok) {
      return ok;
    }
    if (auto ok = choosePoseTopics(); !ok) {
      return ok;
    }
    const BagReader& bag = *bag_;
    const std::string& field = options_.time_field;
    router_ = std::make_unique<pipeline::TfRouter>(options_.world_frame, options_.base_frame,
                                                   std::vector<std::string>(cloud_topics_.size()),
                                                   stats_);
    extrinsics_.assign(cloud_topics_.size(), options_.extrinsic);
    extrinsic_from_tf_.assign(cloud_topics_.size(), false);
    decoded_.resize(kFirstPointCapacity);
    report_.read_warnings = bag.openWarnings();
    info_.path = bag.path();
    info_.format = bag.storage();
    info_.has_scan = true;
    info_.time_property = field == "none" ? "" : "per-point time (" + field + ")";
    return bag_->rewind();
  }

  /// The topics to map (bag.topic): those named, or the bag's only PointCloud2 topic (else its
  /// only Image topic).
  Expected<void, Error> chooseCloudTopics() {
    const BagReader& bag = *bag_;
    if (options_.cloud_topics.empty()) {
      bool has_clouds = false;
      bool has_images = false;
      for (const BagTopic& t : bag.topics()) {
        has_clouds = has_clouds || t.type == kPointCloud2;
        has_images = has_images || t.type == kImage;
      }
      if (!has_clouds && !has_images) {
        return fail(ErrorCode::kInvalidArgument,
                    bag.path() + " has nothing to map: no " + kPointCloud2 + " and no " + kImage +
                        " topic (its topics: " + topicsWithTypes(bag.topics()) + ")");
      }
      auto t = onlyTopicOfType(bag, has_clouds ? kPointCloud2 : kImage, "bag.topic");
      if (!t) {
        return Unexpected(t.error());
      }
      cloud_topics_.push_back(t.value());
    }
    for (const std::string& name : options_.cloud_topics) {
      const int at = findBagTopic(bag, name);
      const bool image = at >= 0 && bag.topics()[static_cast<std::size_t>(at)].type == kImage;
      auto t = topicOfType(bag, name, image ? kImage : kPointCloud2, "bag.topic");
      if (!t) {
        return Unexpected(t.error());
      }
      cloud_topics_.push_back(t.value());
    }
    return {};
  }

  /// One decoder per mapped topic; a depth image topic's CameraInfo topic
  /// (bag.camera_info_topic, in order, else the image's sibling camera_info).
  Expected<void, Error> setUpDecoders() {
    const BagReader& bag = *bag_;
    std::size_t images = 0;
    for (std::uint32_t t : cloud_topics_) {
      const BagTopic& topic = bag.topics()[t];
      report_.cloud_topics.push_back(topic.name);
      pipeline::SensorDecodeSettings settings;
      settings.time_field = options_.time_field;
      settings.max_rate_hz = options_.max_rate_hz;
      int camera_info = -1;
      if (topic.type == kImage) {
        settings.kind = pipeline::SensorInputKind::kDepth;
        settings.depth = options_.depth;
        settings.max_points = options_.max_points;
        const std::string name = images < options_.camera_info_topics.size()
                                     ? options_.camera_info_topics[images]
                                     : pipeline::cameraInfoTopicFor(topic.name);
        ++images;
        auto info = topicOfType(bag, name, kCameraInfo, "bag.camera_info_topic");
        if (!info) {
          return Unexpected(info.error());
        }
        camera_info = static_cast<int>(info.value());
      }
      decoders_.emplace_back(std::move(settings));
      camera_info_topics_.push_back(camera_info);
    }
    if (images < options_.camera_info_topics.size()) {
      return fail(ErrorCode::kInvalidArgument,
                  "bag.camera_info_topic: " + std::to_string(options_.camera_info_topics.size()) +
                      " given for " + std::to_string(images) + " depth image topic(s)");
    }
    if (options_.depth.invalid_as_free && images > 0 && !(options_.depth.max_range_m > 0.0f)) {
      return fail(ErrorCode::kInvalidArgument,
                  "bag.invalid_as_free needs bag.max_range (the length of the free rays)");
    }
    return {};
  }

  /// Where poses come from (bag.pose_source, bag.pose_topic), and /tf_static when the bag has it.
  Expected<void, Error> choosePoseTopics() {
    const BagReader& bag = *bag_;
    using Source = BagRaysOptions::PoseSource;
    Source source = options_.pose_source;
    if (source == Source::kAuto) {
      auto chosen = autoPoseSource();
      if (!chosen) {
        return Unexpected(chosen.error());
      }
      source = chosen.value();
    }
    if (source == Source::kOdometry) {
      auto t = options_.pose_topic.empty()
                   ? onlyTopicOfType(bag, kOdometry, "bag.pose_topic")
                   : topicOfType(bag, options_.pose_topic, kOdometry, "bag.pose_topic");
      if (!t) {
        return Unexpected(t.error());
      }
      odometry_topic_ = static_cast<int>(t.value());
      report_.pose_source = "odometry " + bag.topics()[t.value()].name;
    } else {
      auto t = topicOfType(bag, "/tf", kTfMessage, "bag.pose_source: tf");
      if (!t) {
        return Unexpected(t.error());
      }
      tf_topic_ = static_cast<int>(t.value());
      report_.pose_source = "tf " + options_.world_frame + " -> " + options_.base_frame;
    }
    const int tf_static = findTopic(bag.topics(), "/tf_static");
    if (tf_static >= 0 && bag.topics()[static_cast<std::size_t>(tf_static)].type == kTfMessage) {
      tf_static_topic_ = tf_static;
    }
    return {};
  }

  /// bag.pose_source: auto: Odometry when bag.pose_topic names one or the bag has exactly one, else
  /// TF when it has /tf. With one Odometry topic and /tf, the one that has messages: a topic
  /// recorded but never published must not win over 275 transforms. The choice is said in
  /// report_.pose_note.
  Result<BagRaysOptions::PoseSource> autoPoseSource() {
    using Source = BagRaysOptions::PoseSource;
    const BagReader& bag = *bag_;
    int odometry = -1;
    int odometry_topics = 0;
    for (std::size_t i = 0; i < bag.topics().size(); ++i) {
      if (bag.topics()[i].type == kOdometry) {
        odometry = static_cast<int>(i);
        ++odometry_topics;
      }
    }
    const int tf = findTopic(bag.topics(), "/tf");
    if (!options_.pose_topic.empty() || (odometry_topics == 1 && tf < 0)) {
      return Source::kOdometry;
    }
    if (odometry_topics == 1) {
      auto counts = messagesPerTopic();
      if (!counts) {
        return Unexpected(counts.error());
      }
      const std::uint64_t odometry_n = counts.value()[static_cast<std::size_t>(odometry)];
      const std::uint64_t tf_n = counts.value()[static_cast<std::size_t>(tf)];
      const std::string& name = bag.topics()[static_cast<std::size_t>(odometry)].name;
      if (odometry_n == 0 && tf_n > 0) {
        report_.pose_note = "bag.pose_source: auto: poses from /tf (" + std::to_string(tf_n) +
                            " messages): the Odometry topic " + name + " has no message";
        return Source::kTf;
      }
      report_.pose_note = "bag.pose_source: auto: poses from the Odometry topic " + name + " (" +
                          std::to_string(odometry_n) + " messages), not /tf (" +
                          std::to_string(tf_n) + "); bag.pose_source: tf takes /tf";
      return Source::kOdometry;
    }
    if (tf >= 0) {
      return Source::kTf;
    }
    return fail(ErrorCode::kInvalidArgument,
                bag.path() + ": no pose source: " +
                    (odometry_topics == 0
                         ? std::string("no nav_msgs/msg/Odometry topic and no /tf")
                         : "several Odometry topics (" + topicsOfType(bag.topics(), kOdometry) +
                               "): choose with bag.pose_topic"));
  }

  /// Messages per topic: from the bag's own statistics, else counted by a pass over it.
  Result<std::vector<std::uint64_t>> messagesPerTopic() {
    if (const std::optional<BagStatistics> stated = bag_->statistics()) {
      return stated->topic_messages;
    }
    std::vector<std::uint64_t> counts(bag_->topics().size(), 0);
    auto pass = bag_->forEach([&](const BagMessage& m) {
      if (m.topic < counts.size()) {
        ++counts[m.topic];
      }
      return true;
    });
    if (!pass) {
      return Unexpected(pass.error());
    }
    return counts;
  }

  Result<std::size_t> read(std::span<Ray> out) override {
    std::size_t n = 0;
    while (n < out.size()) {
      if (current_) {
        n += convert(out.subspan(n));
        continue;
      }
      auto ready = nextReadyScan();
      if (!ready) {
        return Unexpected(ready.error());
      }
      if (!ready.value()) {
        break;  // the bag is done and no scan waits
      }
    }
    if (n == 0 && !finished_) {
      finish();
    }
    return n;
  }

  Result<bool> nextCloud(SensorCloud& cloud) override {
    if (current_) {
      return fail(ErrorCode::kInvalidArgument,
                  bag_->path() + ": this reader is reading rays; open another for clouds");
    }
    auto ready = nextReadyScan();
    if (!ready) {
      return Unexpected(ready.error());
    }
    if (!ready.value()) {
      if (!finished_) {
        finish();
      }
      return false;
    }
    takeCloud(cloud);
    ++report_.scans_integrated;
    ++scan_sequence_;
    recycle(std::move(*current_));
    current_.reset();
    return true;
  }

  const io::RaySourceInfo& info() const noexcept override { return info_; }
  double progress() const noexcept override { return bag_->progress(); }
  const BagRaysReport& report() const noexcept override { return report_; }

 private:
  struct Scan {
    msgs::CloudHeader header{};
    std::vector<msgs::ScanPoint> points;
    std::uint32_t sensor = 0;
    std::int64_t log_time_ns = 0;  // when the recorder got it (bag time, for the pose wait)
    pipeline::ScanTimes times;
  };

  /// Fills `out` from the scan being converted. @return rays written.
  std::size_t convert(std::span<Ray> out) {
    Scan& scan = *current_;
    std::size_t n = 0;
    const io::Pose& extrinsic = extrinsics_[scan.sensor];
    while (n < out.size() && point_ < scan.points.size()) {
      const msgs::ScanPoint& p = scan.points[point_++];
      if ((p.flags & msgs::kPointNoReturn) != 0u) {
        ++report_.points_no_return;
        continue;
      }
      if (!pipeline::usableTime(p.time_s, options_.max_time_offset_s)) {
        continue;  // counted when the scan was taken
      }
      if (deskewer_.toRay(p, scan.header.stamp_ns, history_, options_.pose_hold_ns, extrinsic,
                          scan_sequence_, out[n])) {
        ++n;
      }
    }
    if (point_ == scan.points.size()) {
      ++report_.scans_integrated;
      ++scan_sequence_;
      recycle(std::move(*current_));
      current_.reset();
    }
    return n;
  }

  /// Moves the current scan's usable points into `cloud` with the sensor's pose at each of
  /// their distinct times, the poses convert() gives its rays (PointDeskewer::toRay).
  void takeCloud(SensorCloud& cloud) {
    const Scan& scan = *current_;
    const io::Pose& extrinsic = extrinsics_[scan.sensor];
    const std::int64_t stamp = scan.header.stamp_ns;
    cloud.sensor = scan.sensor;
    cloud.frame_id = scan.header.frame_id;
    cloud.stamp_ns = stamp;
    cloud.extrinsic = extrinsic;
    cloud.points.clear();
    cloud.point_offsets_ns.clear();
    cloud.pose_offsets_ns.clear();
    cloud.poses.clear();
    for (const msgs::ScanPoint& p : scan.points) {
      if ((p.flags & msgs::kPointNoReturn) != 0u) {
        ++report_.points_no_return;
      } else if (pipeline::usableTime(p.time_s, options_.max_time_offset_s)) {
        cloud.point_offsets_ns.push_back(pipeline::pointTimeNs(stamp, p.time_s) - stamp);
        cloud.points.push_back(p);
      }
    }
    // One pose per distinct time, looked up as the deskewer looks it up.
    cloud.pose_offsets_ns = cloud.point_offsets_ns;
    std::sort(cloud.pose_offsets_ns.begin(), cloud.pose_offsets_ns.end());
    cloud.pose_offsets_ns.erase(
        std::unique(cloud.pose_offsets_ns.begin(), cloud.pose_offsets_ns.end()),
        cloud.pose_offsets_ns.end());
    const std::size_t distinct = cloud.pose_offsets_ns.size();
    std::size_t kept = 0;
    for (const std::int64_t offset : cloud.pose_offsets_ns) {
      io::Pose base;
      if (history_.lookup(stamp + offset, options_.pose_hold_ns, &base) ==
          pipeline::PoseLookup::kOk) {
        cloud.pose_offsets_ns[kept++] = offset;
        cloud.poses.push_back(io::compose(base, extrinsic));
      }
    }
    cloud.pose_offsets_ns.resize(kept);
    if (kept != distinct) {  // a time without a pose: its points are left out
      std::size_t out = 0;
      for (std::size_t i = 0; i < cloud.points.size(); ++i) {
        if (std::binary_search(cloud.pose_offsets_ns.begin(), cloud.pose_offsets_ns.end(),
                               cloud.point_offsets_ns[i])) {
          cloud.points[out] = cloud.points[i];
          cloud.point_offsets_ns[out++] = cloud.point_offsets_ns[i];
        }
      }
      cloud.points.resize(out);
      cloud.point_offsets_ns.resize(out);
    }
  }

  /// Reads until the oldest waiting scan has its poses (or is given up). @return false at the
  /// end of the bag with no scan left.
  Result<bool> nextReadyScan() {
    for (;;) {
      while (!waiting_.empty()) {
        const Scan& head = waiting_.front();
        io::Pose unused;
        const pipeline::PoseLookup start =
            history_.lookup(head.times.start_ns, options_.pose_hold_ns, &unused);
        const pipeline::PoseLookup end =
            history_.lookup(head.times.end_ns, options_.pose_hold_ns, &unused);
        if (start == pipeline::PoseLookup::kOk && end == pipeline::PoseLookup::kOk) {
          if (auto placed = checkExtrinsic(head); !placed) {
            return Unexpected(placed.error());
          }
          current_.emplace(std::move(waiting_.front()));
          waiting_.pop_front();
          point_ = 0;
          deskewer_.reset();
          return true;
        }
        const bool too_old =
            start == pipeline::PoseLookup::kTooOld || end == pipeline::PoseLookup::kTooOld;
        if (too_old || bag_done_ || bag_time_ns_ > head.log_time_ns + options_.pose_wait_ns) {
          ++report_.scans_no_pose;
          recycle(std::move(waiting_.front()));
          waiting_.pop_front();
          continue;
        }
        break;  // wait for more poses
      }
      if (bag_done_) {
        return false;
      }
      if (auto ok = readMessage(); !ok) {
        return Unexpected(ok.error());
      }
    }
  }

  /// A cloud about to be mapped needs its sensor's place on the base: from /tf_static, the
  /// base frame itself, or bag.sensor_offset. Without one the sensor would silently sit at the
  /// base's origin.
  Expected<void, Error> checkExtrinsic(const Scan& scan) const {
    const char* frame = router_->sensorFrame(scan.sensor);
    if (options_.extrinsic_given || extrinsic_from_tf_[scan.sensor] ||
        options_.base_frame == frame) {
      return {};
    }
    std::string frames;
    for (const std::string& f : static_frames_) {
      frames += (frames.empty() ? "" : ", ") + f;
    }
    return fail(ErrorCode::kInvalidArgument,
                bag_->path() + ": the clouds on '" +
                    bag_->topics()[cloud_topics_[scan.sensor]].name + "' are in frame '" + frame +
                    "', and /tf_static has no chain from the base frame '" + options_.base_frame +
                    "' to it (its frames: " + (frames.empty() ? "none" : frames) +
                    "): give the sensor's position on the base with bag.sensor_offset (X,Y,Z "
                    "metres; 0,0,0 if it is at the base's origin), or bag.base_frame");
  }

  Expected<void, Error> readMessage() {
    auto got = bag_->next(message_);
    if (!got) {
      return Unexpected(got.error());
    }
    if (!got.value()) {
      bag_done_ = true;
      report_.damage = bag_->pass().damage;
      report_.truncated = bag_->pass().truncated;
      return {};
    }
    ++report_.messages;
    bag_time_ns_ = std::max(bag_time_ns_, message_.log_time_ns);
    const auto topic = static_cast<int>(message_.topic);
    if (topic == odometry_topic_) {
      onOdometry();
    } else if (topic == tf_topic_ || topic == tf_static_topic_) {
      onTf(topic == tf_static_topic_);
    } else {
      for (std::uint32_t s = 0; s < cloud_topics_.size(); ++s) {
        if (message_.topic == cloud_topics_[s]) {
          onCloud(s);
        } else if (topic == camera_info_topics_[s]) {
          onCameraInfo(s);
        }
      }
    }
    return {};
  }

  void skip(const char* what, const char* reason) {
    if (report_.skips.size() < kSkipsKept) {
      report_.skips.push_back(std::string(what) + " " + std::to_string(message_.index) +
                              " on topic '" + bag_->topics()[message_.topic].name +
                              "' skipped: " + reason);
    }
  }

  void onCameraInfo(std::uint32_t sensor) {
    if (auto taken = decoders_[sensor].onCameraInfo(message_.data); !taken) {
      ++report_.camera_infos_skipped;
      skip("message", msgs::toString(taken.error()));
      return;
    }
    ++report_.camera_infos;
  }

  void onCloud(std::uint32_t sensor) {
    ++report_.clouds;
    pipeline::SensorDecoder& decoder = decoders_[sensor];
    pipeline::DecodedScan decoded = decoder.decode(message_.data, decoded_);
    while (decoded.outcome == pipeline::DecodeOutcome::kTooLarge &&
           decoded_.size() < options_.max_points) {
      decoded_.resize(std::min<std::size_t>(decoded_.size() * 2, options_.max_points));
      decoded = decoder.decode(message_.data, decoded_);
    }
    switch (decoded.outcome) {
      case pipeline::DecodeOutcome::kAccepted:
        break;
      case pipeline::DecodeOutcome::kRateLimited:
        ++report_.rate_limited;
        return;
      case pipeline::DecodeOutcome::kNoCameraInfo:
        ++report_.images_no_camera_info;
        return;
      case pipeline::DecodeOutcome::kMalformed:
      case pipeline::DecodeOutcome::kTooLarge:
      case pipeline::DecodeOutcome::kWrongFrame:  // no frame is configured: unreachable
        ++report_.clouds_skipped;
        skip("message", decoder.settings().kind == pipeline::SensorInputKind::kDepth
                            ? msgs::toString(decoded.image_error)
                            : msgs::toString(decoded.cloud_error));
        return;
    }
    router_->learnSensorFrame(sensor, decoded.header.frame_id, *this);
    Scan scan = freshScan();
    scan.header = decoded.header;
    scan.sensor = sensor;
    scan.log_time_ns = message_.log_time_ns;
    scan.points.assign(decoded_.begin(), decoded_.begin() + decoded.header.points);
    scan.times = pipeline::scanTimes(scan.points, scan.header.stamp_ns, options_.max_time_offset_s);
    report_.points_bad_time += scan.times.bad_time;
    waiting_.push_back(std::move(scan));
  }

  void onOdometry() {
    auto odometry = msgs::decodeOdometry(message_.data);
    if (!odometry) {
      ++report_.poses_skipped;
      skip("message", "not a valid nav_msgs/msg/Odometry");
      return;
    }
    (void)push(pipeline::baseInWorld(odometry.value()));
    stats_.poses_received.add();
  }

  void onTf(bool is_static) {
    std::array<msgs::StampedTransform, 64> transforms;
    auto count = msgs::decodeTfMessage(message_.data, transforms);
    if (!count) {
      ++report_.poses_skipped;
      skip("message", "not a valid tf2_msgs/msg/TFMessage (or more than 64 transforms)");
      return;
    }
    if (is_static) {
      for (const msgs::StampedTransform& t : std::span(transforms).first(count.value())) {
        static_frames_.insert(t.parent);
        static_frames_.insert(t.child);
      }
    }
    router_->onTransforms(std::span(transforms).first(count.value()), is_static, *this);
  }

  /// PoseSink: TF's base poses into the history, extrinsics to the sensors.
  bool push(const pipeline::PoseUpdate& update) noexcept override {
    if (update.kind == pipeline::PoseUpdate::kSensorExtrinsic) {
      if (update.sensor < extrinsics_.size()) {
        extrinsics_[update.sensor] = update.pose;
        extrinsic_from_tf_[update.sensor] = true;
        deskewer_.reset();
      }
      return true;
    }
    if ((odometry_topic_ >= 0 || tf_topic_ >= 0) && !history_.push(update.stamp_ns, update.pose)) {
      ++report_.poses_out_of_order;  // not after the previous stamp: ignored, as raymapd does
    }
    return true;
  }

  Scan freshScan() {
    if (spare_.empty()) {
      return Scan{};
    }
    Scan scan = std::move(spare_.back());
    spare_.pop_back();
    return scan;
  }
  void recycle(Scan&& scan) {
    scan.points.clear();
    spare_.push_back(std::move(scan));
  }

  void finish() {
    finished_ = true;
    report_.poses = stats_.poses_received.get();
    report_.tf_ignored = stats_.tf_ignored.get();
    report_.tf_unresolved = stats_.tf_unresolved.get();
    report_.extrinsics_from_tf = stats_.extrinsics_from_tf.load();
  }

  std::unique_ptr<BagReader> bag_;
  BagRaysOptions options_;
  io::RaySourceInfo info_;
  BagRaysReport report_;
  std::vector<std::uint32_t> cloud_topics_;  // per sensor: its topic index
  int odometry_topic_ = -1;
  int tf_topic_ = -1;
  int tf_static_topic_ = -1;
  std::vector<pipeline::SensorDecoder> decoders_;  // per sensor
  std::vector<int> camera_info_topics_;            // per sensor: its CameraInfo topic, or -1
  pipeline::PipelineStats stats_;                  // the TF router's counters
  std::unique_ptr<pipeline::TfRouter> router_;
  pipeline::PoseHistory history_;
  std::vector<io::Pose> extrinsics_;     // per sensor: in base_frame
  std::vector<bool> extrinsic_from_tf_;  // per sensor: /tf_static gave its extrinsic
  std::set<std::string> static_frames_;  // every frame /tf_static named (for the error)
  pipeline::PointDeskewer deskewer_;
  std::vector<msgs::ScanPoint> decoded_;  // the decoder's output (grows to the largest cloud)
  std::deque<Scan> waiting_;              // decoded clouds waiting for their poses, oldest first
  std::vector<Scan> spare_;               // emptied scans whose buffers are reused
  std::optional<Scan> current_;           // the scan being converted
  std::size_t point_ = 0;                 // its next point
  std::uint64_t scan_sequence_ = 0;
  BagMessage message_;
  std::int64_t bag_time_ns_ = INT64_MIN;
  bool bag_done_ = false;
  bool finished_ = false;
};

}  // namespace

Result<std::unique_ptr<BagRaySource>> openBagRaySource(const std::string& path,
                                                       const BagRaysOptions& options) {
  BagReadOptions read;
  read.skip_damaged = options.skip_damaged;
  auto bag = openBag(path, read);
  if (!bag) {
    return Unexpected(bag.error());
  }
  auto source = std::make_unique<BagRays>(std::move(bag).value(), options);
  if (auto ok = source->open(); !ok) {
    return Unexpected(ok.error());
  }
  return std::unique_ptr<BagRaySource>(std::move(source));
}

}  // namespace raymap::bag
