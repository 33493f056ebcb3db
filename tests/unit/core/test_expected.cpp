// SPDX-License-Identifier: BSD-3-Clause
// Expected<T, E>: values, errors, moves.
#include <memory>
#include <string>

#include "raymap/error.hpp"
#include "raymap/expected.hpp"
#include <gtest/gtest.h>

namespace raymap {
namespace {

Expected<int, std::string> half(int v) {
  if (v % 2 != 0) {
    return Unexpected(std::string("odd"));
  }
  return v / 2;
}

TEST(Expected, HoldsValueOrError) {
  const auto ok = half(8);
  ASSERT_TRUE(ok.has_value());
  EXPECT_EQ(*ok, 4);
  const auto bad = half(3);
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error(), "odd");
  EXPECT_EQ(bad.value_or(-1), -1);
}

TEST(Expected, MovesOwningValues) {
  Expected<std::unique_ptr<int>, std::string> a = std::make_unique<int>(7);
  Expected<std::unique_ptr<int>, std::string> b = std::move(a);
  ASSERT_TRUE(b.has_value());
  EXPECT_EQ(**b, 7);
  b = Unexpected(std::string("gone"));
  EXPECT_EQ(b.error(), "gone");
}

TEST(Expected, VoidCarriesOnlyErrors) {
  Expected<void, Error> ok;
  EXPECT_TRUE(ok);
  Expected<void, Error> bad = fail(ErrorCode::kIo, "cannot open x");
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().code, ErrorCode::kIo);
  EXPECT_STREQ(toString(bad.error().code), "io");
}

TEST(ExpectedDeathTest, WrongAlternativeAborts) {
  const auto bad = half(3);
  EXPECT_DEATH((void)bad.value(), "precondition violated");
}

}  // namespace
}  // namespace raymap
