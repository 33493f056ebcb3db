// SPDX-License-Identifier: BSD-3-Clause
// Discovery: another participant's writers and readers, with type and QoS, are seen through the
// built-in topics; the observer's own endpoints are not; endpoints that go away disappear.
#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "src/dds/discovery.hpp"
#include "src/dds/entities.hpp"
#include "src/dds/topic_types.hpp"
#include "tests/unit/dds/loopback_bytes.hpp"

namespace raymap::dds {
namespace {

// Waits for discovery end as soon as it happens; the bound is for a loaded machine.
constexpr auto kDiscoveryDeadline = std::chrono::seconds(10);

std::array<std::uint8_t, 16> guidOf(const Participant& participant) {
  dds_guid_t guid{};
  EXPECT_EQ(dds_get_guid(participant.handle(), &guid), DDS_RETCODE_OK);
  std::array<std::uint8_t, 16> bytes{};
  std::memcpy(bytes.data(), guid.v, bytes.size());
  return bytes;
}

const DiscoveredEndpoint* findEndpoint(const std::vector<DiscoveredEndpoint>& endpoints,
                                       const std::string& topic, bool is_writer) {
  const auto it = std::find_if(endpoints.begin(), endpoints.end(), [&](const auto& e) {
    return e.topic == topic && e.is_writer == is_writer;
  });
  return it == endpoints.end() ? nullptr : &*it;
}

/// Polls endpoints() until `predicate` holds for them (or the deadline).
template <class Predicate>
std::vector<DiscoveredEndpoint> endpointsWhen(Discovery& discovery, Predicate predicate) {
  const auto end = std::chrono::steady_clock::now() + kDiscoveryDeadline;
  std::vector<DiscoveredEndpoint> endpoints = discovery.endpoints();
  while (!predicate(endpoints) && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    endpoints = discovery.endpoints();
  }
  return endpoints;
}

class DiscoveryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto observer = Participant::create(test::decoderTestDomain());
    ASSERT_TRUE(observer.has_value()) << observer.error().message;
    observer_.emplace(std::move(observer).value());
    auto other = Participant::create(test::decoderTestDomain());
    ASSERT_TRUE(other.has_value()) << other.error().message;
    other_.emplace(std::move(other).value());
  }
  std::optional<Participant> observer_;
  std::optional<Participant> other_;
};

TEST_F(DiscoveryTest, SeesAnotherParticipantsEndpointsWithTypeAndQos) {
  auto map_writer =
      Writer::create(*other_, "rt/discovery_test_map", gridMapType(), Reliability::kReliable, 1);
  auto cloud_writer = Writer::create(*other_, "rt/discovery_test_points", pointCloud2Type(),
                                     Reliability::kBestEffort, 2);
  auto latched_writer = Writer::create(*other_, "rt/discovery_test_tf_static", tfMessageType(),
                                       Reliability::kReliable, 4, Durability::kTransientLocal);
  auto reader = RawReader::create(*other_, "rt/discovery_test_diagnostics", diagnosticArrayType(),
                                  Reliability::kReliable, 1);
  ASSERT_TRUE(map_writer && cloud_writer && latched_writer && reader);
  auto discovery = Discovery::create(*observer_);
  ASSERT_TRUE(discovery.has_value()) << discovery.error().message;

  const auto writer = waitForWriter(*discovery, "rt/discovery_test_map", 5.0);
  const auto endpoints = endpointsWhen(*discovery, [](const auto& e) {
    return findEndpoint(e, "rt/discovery_test_points", true) != nullptr &&
           findEndpoint(e, "rt/discovery_test_tf_static", true) != nullptr &&
           findEndpoint(e, "rt/discovery_test_diagnostics", false) != nullptr;
  });

  ASSERT_TRUE(writer.has_value());
  EXPECT_EQ(writer->type, "grid_map_msgs::msg::dds_::GridMap_");
  EXPECT_TRUE(writer->is_writer);
  EXPECT_EQ(writer->reliability, Reliability::kReliable);
  EXPECT_EQ(writer->durability, Durability::kVolatile);
  EXPECT_TRUE(writer->xcdr1);
  EXPECT_EQ(writer->participant_key, guidOf(*other_));
  const DiscoveredEndpoint* cloud = findEndpoint(endpoints, "rt/discovery_test_points", true);
  ASSERT_NE(cloud, nullptr);
  EXPECT_EQ(cloud->type, "sensor_msgs::msg::dds_::PointCloud2_");
  EXPECT_EQ(cloud->reliability, Reliability::kBestEffort);
  const DiscoveredEndpoint* latched = findEndpoint(endpoints, "rt/discovery_test_tf_static", true);
  ASSERT_NE(latched, nullptr);
  EXPECT_EQ(latched->durability, Durability::kTransientLocal);
  EXPECT_EQ(latched->reliability, Reliability::kReliable);
  const DiscoveredEndpoint* subscriber =
      findEndpoint(endpoints, "rt/discovery_test_diagnostics", false);
  ASSERT_NE(subscriber, nullptr);
  EXPECT_FALSE(subscriber->is_writer);
  EXPECT_EQ(subscriber->type, "diagnostic_msgs::msg::dds_::DiagnosticArray_");
  EXPECT_EQ(subscriber->reliability, Reliability::kReliable);
  EXPECT_TRUE(subscriber->xcdr1);
}

TEST_F(DiscoveryTest, ReadsWithoutTakingSoEveryCallSeesEverything) {
  auto map_writer =
      Writer::create(*other_, "rt/discovery_test_again", gridMapType(), Reliability::kReliable, 1);
  ASSERT_TRUE(map_writer.has_value());
  auto discovery = Discovery::create(*observer_);
  ASSERT_TRUE(discovery.has_value());
  ASSERT_TRUE(waitForWriter(*discovery, "rt/discovery_test_again", 5.0).has_value());

  // Moved, and asked again and again: the sample stays in the built-in reader.
  Discovery moved = std::move(discovery).value();
  for (int call = 0; call < 3; ++call) {
    EXPECT_NE(findEndpoint(moved.endpoints(), "rt/discovery_test_again", true), nullptr) << call;
  }
  EXPECT_TRUE(waitForWriter(moved, "rt/discovery_test_again", 0.0).has_value());
}

TEST_F(DiscoveryTest, LeavesOutItsOwnParticipantsEndpoints) {
  auto own_writer =
      Writer::create(*observer_, "rt/discovery_test_own", gridMapType(), Reliability::kReliable, 1);
  auto other_writer =
      Writer::create(*other_, "rt/discovery_test_theirs", gridMapType(), Reliability::kReliable, 1);
  ASSERT_TRUE(own_writer && other_writer);
  auto discovery = Discovery::create(*observer_);
  ASSERT_TRUE(discovery.has_value());

  // Once the other participant's writer is seen, the own one (local, so known first) would be
  // there too if it were not filtered.
  ASSERT_TRUE(waitForWriter(*discovery, "rt/discovery_test_theirs", 5.0).has_value());
  const auto endpoints = discovery->endpoints();
  EXPECT_EQ(findEndpoint(endpoints, "rt/discovery_test_own", true), nullptr);
  const auto own = guidOf(*observer_);
  for (const DiscoveredEndpoint& e : endpoints) {
    EXPECT_NE(e.participant_key, own) << e.topic;
  }
}

TEST_F(DiscoveryTest, WaitForWriterGivesUpAfterItsTimeout) {
  auto discovery = Discovery::create(*observer_);
  ASSERT_TRUE(discovery.has_value());
  // A reader is not a writer.
  auto reader = RawReader::create(*other_, "rt/discovery_test_read_only", gridMapType(),
                                  Reliability::kReliable, 1);
  ASSERT_TRUE(reader.has_value());
  const auto start = std::chrono::steady_clock::now();

  const auto writer = waitForWriter(*discovery, "rt/discovery_test_read_only", 0.3);

  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_FALSE(writer.has_value());
  // Not before its timeout; and it gives up by itself (no writer ever comes), however slowly.
  EXPECT_GE(elapsed_s, 0.29);
  EXPECT_LT(elapsed_s, 10.0);
  EXPECT_FALSE(waitForWriter(*discovery, "rt/discovery_test_read_only", -1.0).has_value());
}

TEST_F(DiscoveryTest, ForgetsAWriterThatWentAway) {
  auto discovery = Discovery::create(*observer_);
  ASSERT_TRUE(discovery.has_value());
  {
    auto writer =
        Writer::create(*other_, "rt/discovery_test_gone", gridMapType(), Reliability::kReliable, 1);
    ASSERT_TRUE(writer.has_value());
    ASSERT_TRUE(waitForWriter(*discovery, "rt/discovery_test_gone", 5.0).has_value());
  }
  const auto endpoints = endpointsWhen(*discovery, [](const auto& e) {
    return findEndpoint(e, "rt/discovery_test_gone", true) == nullptr;
  });
  EXPECT_EQ(findEndpoint(endpoints, "rt/discovery_test_gone", true), nullptr);
}

}  // namespace
}  // namespace raymap::dds
