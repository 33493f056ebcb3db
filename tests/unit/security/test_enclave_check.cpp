// SPDX-License-Identifier: BSD-3-Clause
// The checks of an enclave's files: each way a keystore can be unusable is refused with the
// file and the reason; a good enclave passes; Permissive falls back loudly.
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <unistd.h>

#include "src/security/enclave_check.hpp"
#include "src/security/keystore/keystore_writer.hpp"
#include "src/security/secure_participant.hpp"

namespace raymap::security {
namespace {

namespace fs = std::filesystem;

constexpr std::uint32_t kDomain = 7;

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

/// Replaces a (possibly symlinked) file with a copy of `from`.
void replaceWith(const fs::path& target, const fs::path& from) {
  const std::string bytes = slurp(from);
  fs::remove(target);
  std::ofstream(target, std::ios::binary) << bytes;
}

class EnclaveCheckTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::path(::testing::TempDir()) /
            ("enclave_check_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    keystore_ = root_ / "keystore";
    KeystoreOptions options;
    options.domains = {0, 10};
    ASSERT_TRUE(createKeystore(keystore_, options));
    enclave_options_.domains = {0, 10};
    ASSERT_TRUE(createEnclave(keystore_, "/raymap/raymapd", enclave_options_));
  }
  void TearDown() override { fs::remove_all(root_); }

  dds::SecurityFiles files(const char* enclave = "/raymap/raymapd") const {
    SecurityConfig config;
    config.enabled = true;
    config.keystore = keystore_.string();
    config.enclave = enclave;
    return enclaveFilesIn(enclaveFolder(config));
  }
  static std::time_t now() { return std::time(nullptr); }

  fs::path root_;
  fs::path keystore_;
  EnclaveOptions enclave_options_;
};

TEST_F(EnclaveCheckTest, AGoodEnclavePassesAndNamesItsSubject) {
  const TopicNeed needs[] = {{"rt/points", TopicUse::kSubscribe},
                             {"rt/height_map", TopicUse::kPublish}};
  auto check = checkEnclave(files(), kDomain, needs, now());
  ASSERT_TRUE(check) << check.error().message;
  EXPECT_EQ(check->subject, "CN=/raymap/raymapd");
  EXPECT_GT(check->certificate_not_after, now() + 3000L * 24 * 3600);
  EXPECT_GT(check->permissions_not_after, now() + 3000L * 24 * 3600);
}

TEST_F(EnclaveCheckTest, AMissingFileIsNamedWithWhatItIsFor) {
  fs::remove(keystore_ / "enclaves/raymap/raymapd/key.pem");
  auto check = checkEnclave(files(), kDomain, {}, now());
  ASSERT_FALSE(check);
  EXPECT_NE(check.error().message.find("raymapd/key.pem: cannot read the enclave's private key"),
            std::string::npos)
      << check.error().message;
}

TEST_F(EnclaveCheckTest, AnExpiredCertificateIsRefusedWithItsDate) {
  EnclaveOptions old = enclave_options_;
  const auto t = std::chrono::system_clock::now();
  old.validity = {t - std::chrono::hours(24 * 10), t - std::chrono::hours(24)};
  ASSERT_TRUE(createEnclave(keystore_, "/old", old));
  auto check = checkEnclave(files("/old"), kDomain, {}, now());
  ASSERT_FALSE(check);
  EXPECT_NE(check.error().message.find("old/cert.pem: the identity certificate expired on "),
            std::string::npos)
      << check.error().message;
}

TEST_F(EnclaveCheckTest, ACertificateOfAnotherCaIsRefused) {
  const fs::path other = root_ / "other";
  KeystoreOptions options;
  options.domains = {0, 10};
  options.common_name = "another CA";
  ASSERT_TRUE(createKeystore(other, options));
  ASSERT_TRUE(createEnclave(other, "/raymap/raymapd", enclave_options_));
  for (const char* name : {"cert.pem", "key.pem"}) {
    replaceWith(keystore_ / "enclaves/raymap/raymapd" / name,
                other / "enclaves/raymap/raymapd" / name);
  }
  auto check = checkEnclave(files(), kDomain, {}, now());
  ASSERT_FALSE(check);
  EXPECT_NE(check.error().message.find("raymapd/cert.pem: the identity certificate is not signed "
                                       "by the identity CA"),
            std::string::npos)
      << check.error().message;
}

TEST_F(EnclaveCheckTest, PermissionsSignedByAnotherCaAreRefused) {
  const fs::path other = root_ / "other";
  KeystoreOptions options;
  options.domains = {0, 10};
  ASSERT_TRUE(createKeystore(other, options));
  ASSERT_TRUE(createEnclave(other, "/raymap/raymapd", enclave_options_));
  replaceWith(keystore_ / "enclaves/raymap/raymapd/permissions.p7s",
              other / "enclaves/raymap/raymapd/permissions.p7s");
  auto check = checkEnclave(files(), kDomain, {}, now());
  ASSERT_FALSE(check);
  EXPECT_NE(check.error().message.find("permissions.p7s: the permissions is not signed by the "
                                       "permissions CA"),
            std::string::npos)
      << check.error().message;
}

TEST_F(EnclaveCheckTest, AnEditedSignedDocumentIsRefused) {
  const fs::path p7s = keystore_ / "enclaves/raymap/raymapd/permissions.p7s";
  std::string text = slurp(p7s);
  const std::size_t at = text.find("rt/*");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 4, "rt/x");
  fs::remove(p7s);
  std::ofstream(p7s, std::ios::binary) << text;
  auto check = checkEnclave(files(), kDomain, {}, now());
  ASSERT_FALSE(check);
  EXPECT_NE(check.error().message.find("is not signed by the permissions CA"), std::string::npos)
      << check.error().message;
}

TEST_F(EnclaveCheckTest, AKeyOfAnotherIdentityIsRefused) {
  ASSERT_TRUE(createEnclave(keystore_, "/other", enclave_options_));
  replaceWith(keystore_ / "enclaves/raymap/raymapd/key.pem", keystore_ / "enclaves/other/key.pem");
  auto check = checkEnclave(files(), kDomain, {}, now());
  ASSERT_FALSE(check);
  EXPECT_NE(check.error().message.find("key.pem: the private key is not the one of"),
            std::string::npos)
      << check.error().message;
}

TEST_F(EnclaveCheckTest, ADomainOutsideTheGovernanceIsRefused) {
  auto check = checkEnclave(files(), 42, {}, now());
  ASSERT_FALSE(check);
  EXPECT_NE(check.error().message.find("governance.p7s: the governance does not cover domain 42"),
            std::string::npos)
      << check.error().message;
}

TEST_F(EnclaveCheckTest, PermissionsForAnotherDomainAreRefused) {
  EnclaveOptions other_domain = enclave_options_;
  other_domain.domains = {5, 5};
  ASSERT_TRUE(createEnclave(keystore_, "/elsewhere", other_domain));
  auto check = checkEnclave(files("/elsewhere"), kDomain, {}, now());
  ASSERT_FALSE(check);
  EXPECT_NE(check.error().message.find("elsewhere/permissions.p7s: the permissions of "
                                       "CN=/elsewhere do not cover domain 7"),
            std::string::npos)
      << check.error().message;
}

TEST_F(EnclaveCheckTest, PermissionsNotCoveringATopicNameEachOneRefused) {
  EnclaveGrant grant{"/planner", {"rt/plan"}, {"rt/height_map"}};
  ASSERT_TRUE(writePermissions(keystore_, grant, enclave_options_));
  const TopicNeed needs[] = {{"rt/height_map", TopicUse::kSubscribe},
                             {"rt/points", TopicUse::kPublish},
                             {"rt/height_map", TopicUse::kPublish}};
  auto check = checkEnclave(files("/planner"), kDomain, needs, now());
  ASSERT_FALSE(check);
  EXPECT_NE(check.error().message.find("planner/permissions.p7s: the permissions of CN=/planner on "
                                       "domain 7 do not allow: publish rt/points, publish "
                                       "rt/height_map"),
            std::string::npos)
      << check.error().message;
}

TEST_F(EnclaveCheckTest, EnforceRefusesAndPermissiveFallsBackLoudly) {
  SecurityConfig config;
  config.enabled = true;
  config.keystore = (root_ / "no-such-keystore").string();
  config.enclave = "/raymap/raymapd";
  config.source = "ROS_SECURITY_ENABLE";
  config.strategy = Strategy::kEnforce;
  auto enforced = resolveSecurity(config, kDomain, {}, now());
  ASSERT_FALSE(enforced);
  EXPECT_EQ(enforced.error().message.rfind("ROS_SECURITY_ENABLE (Enforce): ", 0), 0u)
      << enforced.error().message;
  config.strategy = Strategy::kPermissive;
  auto permissive = resolveSecurity(config, kDomain, {}, now());
  ASSERT_TRUE(permissive);
  EXPECT_FALSE(permissive->secure());
  EXPECT_NE(permissive->warning.find("running WITHOUT DDS Security"), std::string::npos);
  EXPECT_NE(permissive->warning.find("no-such-keystore"), std::string::npos);
}

TEST_F(EnclaveCheckTest, AnIdentityExpiringWithinAMonthIsWarnedAbout) {
  EnclaveOptions soon = enclave_options_;
  const auto t = std::chrono::system_clock::now();
  soon.validity = {t - std::chrono::hours(24), t + std::chrono::hours(24 * 5)};
  ASSERT_TRUE(createEnclave(keystore_, "/soon", soon));
  SecurityConfig config;
  config.enabled = true;
  config.keystore = keystore_.string();
  config.enclave = "/soon";
  auto outcome = resolveSecurity(config, kDomain, {}, now());
  ASSERT_TRUE(outcome) << outcome.error().message;
  EXPECT_TRUE(outcome->secure());
  EXPECT_NE(outcome->warning.find("expire on"), std::string::npos) << outcome->warning;
}

}  // namespace
}  // namespace raymap::security
