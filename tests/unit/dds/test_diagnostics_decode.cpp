// SPDX-License-Identifier: BSD-3-Clause
// decodeDiagnosticArray: what DiagnosticsMessage sends (through Cyclone) decodes back; both byte
// orders; truncated, malformed and random bytes are refused safely.
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "src/dds/diagnostics_message.hpp"
#include "src/dds/topic_types.hpp"
#include "src/msgs/diagnostics_decode.hpp"
#include "tests/unit/dds/cdr_test_writer.hpp"
#include "tests/unit/dds/loopback_bytes.hpp"

namespace raymap::dds {

using namespace msgs;  // the ROS 2 message codecs (src/msgs) these tests exercise
namespace {

/// Three statuses as raymapd reports them, one without values.
std::vector<std::byte> cycloneDiagnosticsBytes() {
  DiagnosticsMessage message(4, 8);
  message.begin(1'700'000'001'000'000'123LL);
  const int pipeline =
      message.addStatus(kDiagnosticWarn, "raymapd: pipeline", "dropping input", "raymapd");
  message.addValue(pipeline, "backend", "%s", "cpu");
  message.addValue(pipeline, "clouds_received", "%d", 1234);
  message.addValue(pipeline, "last_cloud_error", "%s", "");
  const int map = message.addStatus(kDiagnosticOk, "raymapd: height map", "ok", "raymapd");
  message.addValue(map, "publish_rate_hz", "%.2f", 5.0);
  message.addStatus(kDiagnosticStale, "raymapd: real time", "", "");
  auto bytes =
      test::cyclonesBytes("rt/decode_test_diagnostics", diagnosticArrayType(), {message.sample()});
  return bytes.empty() ? std::vector<std::byte>{} : bytes.front();
}

std::vector<std::byte> encodeHandDiagnostics(bool little_endian) {
  test::CdrTestWriter w(little_endian);
  w.i32(10);
  w.u32(20);
  w.string("diag_frame");
  w.u32(2);
  w.u8(kDiagnosticError);
  w.string("motor");
  w.string("over temperature");
  w.string("m1");
  w.u32(2);
  w.string("temperature_c");
  w.string("91.5");
  w.string("limit_c");
  w.string("85");
  w.u8(7);  // not a defined level: passed on as it is
  w.string("odd");
  w.string("");
  w.string("");
  w.u32(0);
  return w.data();
}

TEST(DecodeDiagnosticArray, WhatDiagnosticsMessageSendsDecodesBack) {
  const std::vector<std::byte> cdr = cycloneDiagnosticsBytes();
  ASSERT_FALSE(cdr.empty());

  const auto decoded = decodeDiagnosticArray(cdr);

  ASSERT_TRUE(decoded.has_value()) << toString(decoded.error());
  EXPECT_EQ(decoded->stamp_ns, 1'700'000'001'000'000'123LL);
  EXPECT_EQ(decoded->frame_id, "");
  ASSERT_EQ(decoded->statuses.size(), 3U);
  const DecodedDiagnosticStatus& pipeline = decoded->statuses[0];
  EXPECT_EQ(pipeline.level, kDiagnosticWarn);
  EXPECT_EQ(pipeline.name, "raymapd: pipeline");
  EXPECT_EQ(pipeline.message, "dropping input");
  EXPECT_EQ(pipeline.hardware_id, "raymapd");
  ASSERT_EQ(pipeline.values.size(), 3U);
  EXPECT_EQ(pipeline.values[0].key, "backend");
  EXPECT_EQ(pipeline.values[0].value, "cpu");
  EXPECT_EQ(pipeline.values[1].key, "clouds_received");
  EXPECT_EQ(pipeline.values[1].value, "1234");
  EXPECT_EQ(pipeline.values[2].value, "");
  ASSERT_EQ(decoded->statuses[1].values.size(), 1U);
  EXPECT_EQ(decoded->statuses[1].values[0].value, "5.00");
  EXPECT_EQ(decoded->statuses[2].level, kDiagnosticStale);
  EXPECT_TRUE(decoded->statuses[2].values.empty());
}

TEST(DecodeDiagnosticArray, ReadsBothByteOrders) {
  for (const bool little_endian : {true, false}) {
    const auto decoded = decodeDiagnosticArray(encodeHandDiagnostics(little_endian));
    ASSERT_TRUE(decoded.has_value()) << toString(decoded.error());
    EXPECT_EQ(decoded->stamp_ns, 10'000'000'020LL);
    EXPECT_EQ(decoded->frame_id, "diag_frame");
    ASSERT_EQ(decoded->statuses.size(), 2U);
    EXPECT_EQ(decoded->statuses[0].level, kDiagnosticError);
    ASSERT_EQ(decoded->statuses[0].values.size(), 2U);
    EXPECT_EQ(decoded->statuses[0].values[1].key, "limit_c");
    EXPECT_EQ(decoded->statuses[0].values[1].value, "85");
    EXPECT_EQ(decoded->statuses[1].level, 7);
    EXPECT_EQ(decoded->statuses[1].name, "odd");
  }
}

TEST(DecodeDiagnosticArray, RefusesEveryTruncation) {
  const std::vector<std::byte> cdr = encodeHandDiagnostics(true);
  ASSERT_TRUE(decodeDiagnosticArray(cdr).has_value());
  for (std::size_t size = 0; size < cdr.size(); ++size) {
    const auto decoded = decodeDiagnosticArray(std::span<const std::byte>(cdr.data(), size));
    ASSERT_FALSE(decoded.has_value()) << "a prefix of " << size << " bytes decoded";
    EXPECT_EQ(decoded.error(),
              size < 4 ? DiagnosticsError::kBadEncapsulation : DiagnosticsError::kTruncated)
        << size;
  }
}

TEST(DecodeDiagnosticArray, RefusesMalformedAndAbsurdInput) {
  // a status count far beyond what the bytes can hold
  test::CdrTestWriter huge;
  huge.i32(0);
  huge.u32(0);
  huge.string("");
  huge.u32(0x7FFFFFFFU);
  huge.u32(0);
  EXPECT_EQ(decodeDiagnosticArray(huge.data()).error(), DiagnosticsError::kTruncated);
  // a name whose last byte is not the NUL
  test::CdrTestWriter no_nul;
  no_nul.i32(0);
  no_nul.u32(0);
  no_nul.string("");
  no_nul.u32(1);
  no_nul.u8(0);
  no_nul.u32(3);
  for (const char c : std::string("abc")) {
    no_nul.u8(static_cast<std::uint8_t>(c));
  }
  for (int i = 0; i < 8; ++i) {
    no_nul.u32(0);
  }
  EXPECT_EQ(decodeDiagnosticArray(no_nul.data()).error(), DiagnosticsError::kMalformed);
  // not CDR
  const std::vector<std::byte> xml = {std::byte{'<'}, std::byte{'?'}, std::byte{'x'},
                                      std::byte{'m'}, std::byte{'l'}};
  EXPECT_EQ(decodeDiagnosticArray(xml).error(), DiagnosticsError::kBadEncapsulation);
}

TEST(DecodeDiagnosticArray, SurvivesRandomAndMutatedBytes) {
  const std::vector<std::byte> good = encodeHandDiagnostics(true);
  std::mt19937 random(99);
  for (int round = 0; round < 3000; ++round) {
    std::vector<std::byte> cdr;
    if (round % 2 == 0) {
      cdr.resize(4 + random() % 300);
      for (std::byte& b : cdr) {
        b = static_cast<std::byte>(random() & 0xFF);
      }
      cdr[0] = std::byte{0};
      cdr[1] = std::byte{static_cast<std::uint8_t>(random() & 1)};
    } else {
      cdr = good;
      for (int flips = 0; flips < 3; ++flips) {
        cdr[4 + random() % (cdr.size() - 4)] = static_cast<std::byte>(random() & 0xFF);
      }
    }
    static_cast<void>(decodeDiagnosticArray(cdr));  // must not crash or read out of bounds
  }
  SUCCEED();
}

TEST(DiagnosticLevelName, NamesTheFourLevels) {
  EXPECT_STREQ(diagnosticLevelName(kDiagnosticOk), "OK");
  EXPECT_STREQ(diagnosticLevelName(kDiagnosticWarn), "WARN");
  EXPECT_STREQ(diagnosticLevelName(kDiagnosticError), "ERROR");
  EXPECT_STREQ(diagnosticLevelName(kDiagnosticStale), "STALE");
  EXPECT_STREQ(diagnosticLevelName(4), "LEVEL?");
  EXPECT_STREQ(toString(DiagnosticsError::kTruncated), "truncated");
}

}  // namespace
}  // namespace raymap::dds
