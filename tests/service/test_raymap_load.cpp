// SPDX-License-Identifier: BSD-3-Clause
// raymap-load as a user runs it (issue 52, M6): on the domain ROS_DOMAIN_ID names, with its
// default scene found from any working directory.
#include <optional>
#include <string>

#include <gtest/gtest.h>

#include "tests/service/service_fixture.hpp"
#include "tests/support/cli_runner.hpp"
#include "tests/support/json_doc.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::test {
namespace {

/// The first number named `key` in raymap-load's JSON report, its nested objects included (-1
/// when there is none). A report that is not JSON is a test failure.
double loadReportNumber(const std::string& report, const std::string& key) {
  const std::optional<Json> json = parseJson(report);
  const Json* value = json ? findFirst(*json, key) : nullptr;
  return value != nullptr && value->is_number() ? value->get<double>() : -1.0;
}

TEST(RaymapLoad, PublishesOnTheDomainOfRosDomainIdWithItsDefaultSceneFromAnyFolder) {
  // Before: domain 0 whatever ROS_DOMAIN_ID said, and "config/scenes/yard.yaml" relative to the
  // working directory (not found outside the source tree).
  const std::uint32_t domain = uniqueDomain();
  RunningDaemon daemon(serviceConfig(domain), false);
  ASSERT_TRUE(daemon.notify.waitFor("READY=1", kStartWait).has_value()) << daemon.log();
  const TempDir elsewhere;
  const RunResult r = runProgram(
      {"/bin/sh", "-c",
       "cd '" + elsewhere.path().string() + "' && ROS_DOMAIN_ID=" + std::to_string(domain) +
           " exec '" + RAYMAP_LOAD_PATH + "' --beams 16 --columns 512 --warmup 2 --duration 3"});
  ASSERT_EQ(r.exit_code, 0) << describe(r) << daemon.log();
  EXPECT_GT(loadReportNumber(r.out, "maps_received"), 0.0) << r.out;
  EXPECT_GT(loadReportNumber(r.out, "clouds_received"), 0.0) << r.out;
  expectCleanStop(daemon);
}

TEST(RaymapLoad, ABadRosDomainIdIsRefusedNamingIt) {
  const RunResult r = runProgram(
      {"/bin/sh", "-c",
       std::string("ROS_DOMAIN_ID=robot7 exec '") + RAYMAP_LOAD_PATH + "' --duration 1"});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_TRUE(contains(r.err, "ROS_DOMAIN_ID=\"robot7\" is not a domain id")) << describe(r);
}

}  // namespace
}  // namespace raymap::test
