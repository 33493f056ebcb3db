// SPDX-License-Identifier: BSD-3-Clause
// ROS 2's security variables as raymap reads them, enclave names, and the grants of a
// permissions document.
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#include "src/security/permissions_document.hpp"
#include "src/security/security_config.hpp"

namespace raymap::security {
namespace {

/// Sets (or unsets, for nullptr) the ROS_SECURITY_* variables for one test.
class SecurityEnvironment : public ::testing::Test {
 protected:
  void TearDown() override {
    for (const char* name : kNames) {
      ::unsetenv(name);
    }
  }
  static void set(const char* name, const char* value) { ::setenv(name, value, 1); }
  static constexpr const char* kNames[] = {"ROS_SECURITY_ENABLE", "ROS_SECURITY_KEYSTORE",
                                           "ROS_SECURITY_ENCLAVE_OVERRIDE",
                                           "ROS_SECURITY_STRATEGY"};
};

TEST_F(SecurityEnvironment, OffUnlessEnableIsTrue) {
  auto unset = securityFromEnvironment(kToolsEnclave);
  ASSERT_TRUE(unset);
  EXPECT_FALSE(unset->enabled);
  set("ROS_SECURITY_ENABLE", "false");
  EXPECT_FALSE(securityFromEnvironment(kToolsEnclave)->enabled);
  set("ROS_SECURITY_ENABLE", "1");
  auto bad = securityFromEnvironment(kToolsEnclave);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("ROS_SECURITY_ENABLE=1: must be true or false"),
            std::string::npos);
}

TEST_F(SecurityEnvironment, ReadsKeystoreEnclaveAndStrategyAsRos2Does) {
  set("ROS_SECURITY_ENABLE", "true");
  auto no_keystore = securityFromEnvironment(kToolsEnclave);
  ASSERT_FALSE(no_keystore);
  EXPECT_NE(no_keystore.error().message.find("ROS_SECURITY_KEYSTORE is not set"),
            std::string::npos);
  set("ROS_SECURITY_KEYSTORE", "/etc/keystore");
  auto defaults = securityFromEnvironment(kDaemonEnclave);
  ASSERT_TRUE(defaults);
  EXPECT_TRUE(defaults->enabled);
  EXPECT_EQ(defaults->keystore, "/etc/keystore");
  EXPECT_EQ(defaults->enclave, "/raymap/raymapd");
  EXPECT_EQ(defaults->strategy, Strategy::kPermissive);  // rcl's default
  set("ROS_SECURITY_ENCLAVE_OVERRIDE", "/robot/mapper");
  set("ROS_SECURITY_STRATEGY", "Enforce");
  auto chosen = securityFromEnvironment(kDaemonEnclave);
  ASSERT_TRUE(chosen);
  EXPECT_EQ(chosen->enclave, "/robot/mapper");
  EXPECT_EQ(chosen->strategy, Strategy::kEnforce);
  set("ROS_SECURITY_STRATEGY", "enforce");
  auto misspelt = securityFromEnvironment(kDaemonEnclave);
  ASSERT_FALSE(misspelt);
  EXPECT_NE(misspelt.error().message.find("ROS_SECURITY_STRATEGY: \"enforce\""), std::string::npos);
  set("ROS_SECURITY_STRATEGY", "Enforce");
  set("ROS_SECURITY_ENCLAVE_OVERRIDE", "robot/mapper");
  auto relative = securityFromEnvironment(kDaemonEnclave);
  ASSERT_FALSE(relative);
  EXPECT_NE(relative.error().message.find("ROS_SECURITY_ENCLAVE_OVERRIDE"), std::string::npos);
}

TEST(EnclaveName, FollowsRos2NamespaceRules) {
  EXPECT_TRUE(checkEnclaveName("/raymap/raymapd"));
  EXPECT_TRUE(checkEnclaveName("/a_1"));
  for (const char* bad : {"", "/", "a/b", "/a//b", "/a/", "/a-b", "/a/../b", "/1a"}) {
    EXPECT_FALSE(checkEnclaveName(bad)) << bad;
  }
}

constexpr const char* kPermissions = R"(<?xml version="1.0" encoding="UTF-8"?>
<dds>
  <permissions>
    <grant name="/other">
      <subject_name>CN=/other</subject_name>
      <validity><not_before>2020-01-01T00:00:00</not_before><not_after>2030-01-01T00:00:00</not_after></validity>
      <allow_rule><domains><id>0</id></domains><publish><topics><topic>*</topic></topics></publish></allow_rule>
      <default>DENY</default>
    </grant>
    <grant name="/planner">
      <subject_name>CN=/planner</subject_name>
      <validity>
        <not_before>2020-05-01T00:00:00</not_before>
        <not_after>2030-05-01T12:30:00+02:00</not_after>
      </validity>
      <deny_rule>
        <domains><id>3</id></domains>
        <subscribe><topics><topic>rt/secret</topic></topics></subscribe>
      </deny_rule>
      <allow_rule>
        <domains><id_range><min>0</min><max>5</max></id_range></domains>
        <publish><topics><topic>rt/plan</topic></topics></publish>
        <subscribe><topics><topic>rt/*</topic></topics></subscribe>
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
)";

TEST(PermissionsGrant, TheFirstMatchingRuleDecidesThenTheDefault) {
  auto grant = PermissionsGrant::find(kPermissions, "CN = /planner");
  ASSERT_TRUE(grant) << grant.error().message;
  EXPECT_TRUE(grant->allows(3, "rt/height_map", TopicUse::kSubscribe));
  EXPECT_FALSE(grant->allows(3, "rt/secret", TopicUse::kSubscribe));  // denied before allowed
  EXPECT_TRUE(grant->allows(2, "rt/secret", TopicUse::kSubscribe));   // the deny is domain 3's
  EXPECT_TRUE(grant->allows(0, "rt/plan", TopicUse::kPublish));
  EXPECT_FALSE(grant->allows(0, "rt/points", TopicUse::kPublish));        // default DENY
  EXPECT_FALSE(grant->allows(6, "rt/height_map", TopicUse::kSubscribe));  // outside the range
  EXPECT_EQ(grant->notBefore(), 1588291200);
  EXPECT_EQ(grant->notAfter(), 1903869000 - 7200);
}

TEST(PermissionsGrant, ASubjectWithoutAGrantNamesThoseGranted) {
  auto grant = PermissionsGrant::find(kPermissions, "CN=/raymap/raymapd");
  ASSERT_FALSE(grant);
  EXPECT_NE(grant.error().message.find("it grants \"CN=/other\", \"CN=/planner\""),
            std::string::npos)
      << grant.error().message;
}

TEST(PermissionsGrant, GovernanceDomains) {
  constexpr const char* kGovernance =
      "<dds><domain_access_rules><domain_rule><domains><id>4</id><id_range><min>10</min>"
      "<max>12</max></id_range></domains></domain_rule></domain_access_rules></dds>";
  EXPECT_TRUE(governanceCoversDomain(kGovernance, 4));
  EXPECT_TRUE(governanceCoversDomain(kGovernance, 11));
  EXPECT_FALSE(governanceCoversDomain(kGovernance, 5));
  EXPECT_FALSE(governanceCoversDomain(kGovernance, 13));
}

TEST(IsoTime, ParsesWhatPermissionsDocumentsWrite) {
  EXPECT_EQ(*parseIsoTime("1970-01-02T00:00:00"), 86400);
  EXPECT_EQ(*parseIsoTime("1970-01-02T00:00:00Z"), 86400);
  EXPECT_EQ(*parseIsoTime("1970-01-02T00:00:00.123+01:00"), 86400 - 3600);
  EXPECT_FALSE(parseIsoTime("1970-01-02 00:00:00"));
  EXPECT_FALSE(parseIsoTime("soon"));
}

}  // namespace
}  // namespace raymap::security
