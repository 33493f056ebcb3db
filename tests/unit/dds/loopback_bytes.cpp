// SPDX-License-Identifier: BSD-3-Clause
// Writer -> RawReader in one participant on loopback.
#include "tests/unit/dds/loopback_bytes.hpp"

#include <chrono>
#include <thread>

#include <gtest/gtest.h>
#include <unistd.h>

#include "src/dds/entities.hpp"

namespace raymap::dds::test {

std::uint32_t decoderTestDomain() { return 150U + static_cast<std::uint32_t>(getpid() % 40); }

std::vector<std::vector<std::byte>> cyclonesBytes(const char* topic,
                                                  const dds_topic_descriptor_t* descriptor,
                                                  const std::vector<const void*>& samples) {
  auto participant = Participant::create(decoderTestDomain());
  if (!participant) {
    ADD_FAILURE() << participant.error().message;
    return {};
  }
  const auto depth = static_cast<std::int32_t>(samples.size() + 1);
  auto writer = Writer::create(*participant, topic, descriptor, Reliability::kReliable, depth);
  auto reader = RawReader::create(*participant, topic, descriptor, Reliability::kReliable, depth);
  if (!writer || !reader) {
    ADD_FAILURE() << "cannot create the writer or reader of " << topic;
    return {};
  }
  // Ends as soon as the samples are back; the bound is for a loaded machine.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (writer->matchedReaders() == 0 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  for (const void* sample : samples) {
    if (!writer->write(sample)) {
      ADD_FAILURE() << "write on " << topic << " failed";
      return {};
    }
  }
  std::vector<std::vector<std::byte>> bytes;
  while (bytes.size() < samples.size() && std::chrono::steady_clock::now() < deadline) {
    const int taken =
        reader->takeEach([&bytes](std::span<const std::byte> cdr,
                                  std::int64_t) { bytes.emplace_back(cdr.begin(), cdr.end()); },
                         16);
    if (taken <= 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }
  if (bytes.size() != samples.size()) {
    ADD_FAILURE() << "got " << bytes.size() << " of " << samples.size() << " samples on " << topic;
    return {};
  }
  return bytes;
}

}  // namespace raymap::dds::test
