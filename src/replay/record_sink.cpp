// SPDX-License-Identifier: BSD-3-Clause
// The two record sinks: raymap's log (src/record) and a rosbag2 MCAP bag (src/bag).
#include "src/replay/record_sink.hpp"

#include <utility>

#include "src/bag/rosbag_writer.hpp"
#include "src/dds/topic_types.hpp"
#include "src/msgs/ros_names.hpp"
#include "src/record/record_log_writer.hpp"

namespace raymap::replay {
namespace {

class RecordLogSink final : public RecordSink {
 public:
  explicit RecordLogSink(std::unique_ptr<record::RecordLogWriter> log) : log_(std::move(log)) {}
  Result<std::uint32_t> addTopic(const std::string& dds_topic, const std::string& type,
                                 bool reliable, bool latched) override {
    return log_->addTopic(
        dds_topic, type,
        reliable ? record::LogReliability::kReliable : record::LogReliability::kBestEffort,
        latched ? record::LogDurability::kTransientLocal : record::LogDurability::kVolatile);
  }
  Result<void> write(std::uint32_t id, std::int64_t receive_unix_ns,
                     std::int64_t receive_monotonic_ns, std::int64_t source_unix_ns,
                     std::span<const std::byte> cdr) override {
    return log_->write(id, receive_unix_ns, receive_monotonic_ns, source_unix_ns, cdr);
  }
  Result<void> close() override { return log_->close(); }
  const std::string& partialPath() const noexcept override { return log_->partialPath(); }
  std::uint64_t messages() const noexcept override { return log_->messages(); }
  std::uint64_t bytes() const noexcept override { return log_->bytes(); }

 private:
  std::unique_ptr<record::RecordLogWriter> log_;
};

/// A rosbag2 bag: ROS topic names, log time = when it was received (as ros2 bag record does),
/// publish time = the writer's source timestamp.
class RosbagSink final : public RecordSink {
 public:
  explicit RosbagSink(std::unique_ptr<bag::RosbagWriter> bag) : bag_(std::move(bag)) {}
  Result<std::uint32_t> addTopic(const std::string& dds_topic, const std::string& type,
                                 bool reliable, bool latched) override {
    // Bags name types the ROS way (sensor_msgs/msg/PointCloud2), DDS the IDL way.
    const dds::KnownTopicType* known = dds::findTopicType(type);
    return bag_->addTopic(msgs::rosTopicName(dds_topic), known != nullptr ? known->ros_name : type,
                          bag::offeredQosYaml(reliable, latched, latched ? 1 : kRecordReaderDepth));
  }
  Result<void> write(std::uint32_t id, std::int64_t receive_unix_ns, std::int64_t,
                     std::int64_t source_unix_ns, std::span<const std::byte> cdr) override {
    return bag_->write(id, receive_unix_ns, source_unix_ns, cdr);
  }
  Result<void> close() override { return bag_->close(); }
  const std::string& partialPath() const noexcept override { return bag_->partialPath(); }
  std::uint64_t messages() const noexcept override { return bag_->messages(); }
  std::uint64_t bytes() const noexcept override { return bag_->bytes(); }

 private:
  std::unique_ptr<bag::RosbagWriter> bag_;
};

}  // namespace

Result<std::unique_ptr<RecordSink>> openRecordSink(const std::string& output, RecordFormat format,
                                                   const std::string& compression) {
  if (format == RecordFormat::kMcapBag) {
    auto parsed = bag::parseChunkCompression(compression);
    if (!parsed) {
      return fail(ErrorCode::kInvalidArgument, "record.compression: " + parsed.error().message);
    }
    bag::RosbagWriterOptions options;
    options.compression = parsed.value();
    auto bag = bag::RosbagWriter::create(output, options);
    if (!bag) {
      return Unexpected(bag.error());
    }
    return std::unique_ptr<RecordSink>(std::make_unique<RosbagSink>(std::move(bag).value()));
  }
  if (compression != "none") {
    return fail(ErrorCode::kInvalidArgument,
                "record.compression applies to record.format: mcap (a .rmlog is raw capture)");
  }
  auto log = record::RecordLogWriter::create(output);
  if (!log) {
    return Unexpected(log.error());
  }
  return std::unique_ptr<RecordSink>(std::make_unique<RecordLogSink>(std::move(log).value()));
}

}  // namespace raymap::replay
