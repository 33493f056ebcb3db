// SPDX-License-Identifier: BSD-3-Clause
// main() of the device test executables whose every test needs the device (CUDA): without one it
// prints why and exits 77, which CTest reports as skipped. Listing the tests (CTest's discovery)
// works on any machine.
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "tests/device/device_under_test.hpp"

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  if (!GTEST_FLAG_GET(list_tests)) {
    const std::string why = raymap::test::deviceUnderTest().unavailable();
    if (!why.empty()) {
      std::printf("skipped: %s\n", why.c_str());
      return 77;
    }
  }
  return RUN_ALL_TESTS();
}
