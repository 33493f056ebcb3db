// SPDX-License-Identifier: BSD-3-Clause
// CdrWriter: serialized bytes go out unchanged (padding included) and bytes that are not the
// type are refused, on loopback in one process.
#include <chrono>
#include <cstring>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <unistd.h>

#include "src/dds/cdr_writer.hpp"
#include "src/dds/entities.hpp"
#include "src/dds/topic_types.hpp"
#include "tests/unit/dds/cdr_test_writer.hpp"
#include "tests/unit/dds/test_domain.hpp"

namespace raymap::dds {
namespace {

std::vector<std::vector<std::byte>> receive(RawReader& reader, std::size_t count,
                                            std::chrono::milliseconds timeout) {
  std::vector<std::vector<std::byte>> samples;
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (samples.size() < count && std::chrono::steady_clock::now() < end) {
    reader.takeEach([&samples](std::span<const std::byte> cdr,
                               std::int64_t) { samples.emplace_back(cdr.begin(), cdr.end()); },
                    16);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return samples;
}

TEST(CdrWriter, SendsTheRecordedBytesUnchangedIncludingPaddingAndRefusesOtherBytes) {
  auto publisher = Participant::create(testDomain());
  auto subscriber = Participant::create(testDomain());
  ASSERT_TRUE(publisher.has_value() && subscriber.has_value());
  auto writer = CdrWriter::create(publisher.value(), "rt/cdr_writer_test", odometryType(),
                                  Reliability::kReliable, 8);
  ASSERT_TRUE(writer.has_value()) << writer.error().message;
  auto reader = RawReader::create(subscriber.value(), "rt/cdr_writer_test", odometryType(),
                                  Reliability::kReliable, 8);
  ASSERT_TRUE(reader.has_value());
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (writer.value().matchedReaders() == 0 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_EQ(writer.value().matchedReaders(), 1U);

  test::TestPose pose;
  pose.parent = "odom";  // header: 4 + stamp 8 + "odom" (4 + 5) = body offset 17
  std::vector<std::byte> bytes = test::encodeOdometry(pose);
  // Body offsets 17..19 pad child_frame_id's length to 4 bytes: a re-serialising path would
  // write zeros there, so non-zero padding proves the bytes travel as they are.
  for (std::size_t i = 4 + 17; i < 4 + 20; ++i) {
    ASSERT_EQ(bytes[i], std::byte{0});
    bytes[i] = std::byte{0xAA};
  }
  ASSERT_TRUE(writer.value().write(bytes).has_value());
  // A truncated payload and one of another type are refused, and nothing is sent for them.
  const std::vector<std::byte> truncated(bytes.begin(), bytes.begin() + 30);
  const auto bad = writer.value().write(truncated);
  ASSERT_FALSE(bad.has_value());
  EXPECT_EQ(bad.error(), CdrWriteError::kNotDecodable);
  const std::vector<std::byte> cloud = test::encodeCloud(test::makeXyzCloud({1.0F, 2.0F, 3.0F}));
  EXPECT_FALSE(writer.value().write(cloud).has_value());

  // The good sample, however long a loaded machine takes to deliver it; then, reliable and in
  // order on loopback, a refused one would have come right behind it: 0.5 s more finds none.
  const auto received = receive(reader.value(), 1, std::chrono::seconds(10));
  ASSERT_EQ(received.size(), 1U);
  EXPECT_EQ(received[0], bytes);
  EXPECT_TRUE(receive(reader.value(), 1, std::chrono::milliseconds(500)).empty());
}

}  // namespace
}  // namespace raymap::dds
