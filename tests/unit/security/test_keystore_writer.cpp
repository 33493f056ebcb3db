// SPDX-License-Identifier: BSD-3-Clause
// The SROS2 keystore writer: the layout, modes and links sros2 makes, certificates that verify
// against the CA, .p7s documents that verify (in-process and with the openssl program) and carry
// the XML, policy files, and calls that fail leaving nothing behind.
#include <chrono>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <openssl/pem.h>
#include <openssl/x509v3.h>
#include <sys/stat.h>
#include <unistd.h>

#include "src/security/keystore/keystore_writer.hpp"
#include "src/security/openssl_handles.hpp"
#include "tests/support/cli_runner.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::security {
namespace {

namespace fs = std::filesystem;
using test::readFile;
using test::writeText;

constexpr const char* kEnclave = "/raymap/raymapd";
constexpr double kSecondsPerDay = 24 * 60 * 60;

// ---- helpers: OpenSSL checks written independently of the writer ----

X509Ptr readCertificate(const fs::path& file) {
  const std::string text = readFile(file.string());
  BioPtr in = memoryBio(text);
  return X509Ptr(PEM_read_bio_X509(in.get(), nullptr, nullptr, nullptr));
}

/// The content of an S/MIME signed document when it verifies against `ca_file`, as
/// `openssl smime -verify -text -CAfile` checks it; nullopt otherwise.
std::optional<std::string> verifiedContent(const std::string& p7s, const fs::path& ca_file) {
  BioPtr in = memoryBio(p7s);
  BIO* content = nullptr;
  Pkcs7Ptr signature(SMIME_read_PKCS7(in.get(), &content));
  BioPtr content_owner(content);
  X509StorePtr store(X509_STORE_new());
  X509Ptr ca = readCertificate(ca_file);
  BioPtr out(BIO_new(BIO_s_mem()));
  const bool ok =
      signature && content && ca && X509_STORE_add_cert(store.get(), ca.get()) == 1 &&
      PKCS7_verify(signature.get(), nullptr, store.get(), content, out.get(), PKCS7_TEXT) == 1;
  takeOpensslErrors();
  return ok ? std::optional<std::string>(bioText(out.get())) : std::nullopt;
}

/// `text` with CRLF line ends made LF (S/MIME's text mode signs canonical CRLF lines).
std::string unixLines(std::string text) {
  for (std::size_t at = text.find("\r\n"); at != std::string::npos; at = text.find("\r\n", at)) {
    text.erase(at, 1);
  }
  return text;
}

bool verifiesAgainst(const X509Ptr& certificate, const fs::path& ca_file) {
  X509Ptr ca = readCertificate(ca_file);
  X509StorePtr store(X509_STORE_new());
  X509StoreCtxPtr context(X509_STORE_CTX_new());
  const bool ok =
      certificate && ca && X509_STORE_add_cert(store.get(), ca.get()) == 1 &&
      X509_STORE_CTX_init(context.get(), store.get(), certificate.get(), nullptr) == 1 &&
      X509_verify_cert(context.get()) == 1;
  takeOpensslErrors();
  return ok;
}

mode_t modeOf(const fs::path& path) {
  struct stat info {};
  EXPECT_EQ(::lstat(path.c_str(), &info), 0) << path;
  return info.st_mode & 07777;
}

/// Seconds from now to `time` (negative: in the past).
double secondsFromNow(const ASN1_TIME* time) {
  int days = 0;
  int seconds = 0;
  EXPECT_EQ(ASN1_TIME_diff(&days, &seconds, nullptr, time), 1);
  return static_cast<double>(days) * kSecondsPerDay + seconds;
}

/// The <topic> entries of the first <publish> or <subscribe> element of a permissions document.
std::vector<std::string> topicsOf(const std::string& xml, const std::string& element) {
  const std::size_t begin = xml.find("<" + element + ">");
  const std::size_t end = xml.find("</" + element + ">");
  std::vector<std::string> topics;
  if (begin == std::string::npos || end == std::string::npos) {
    return topics;
  }
  for (std::size_t at = xml.find("<topic>", begin); at < end; at = xml.find("<topic>", at)) {
    at += 7;
    topics.push_back(xml.substr(at, xml.find("</topic>", at) - at));
  }
  return topics;
}

/// Every path under `root` with its kind and content (or link target): a snapshot to compare.
std::map<std::string, std::string> snapshot(const fs::path& root) {
  std::map<std::string, std::string> entries;
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    const std::string key = entry.path().lexically_relative(root).string();
    if (entry.is_symlink()) {
      entries[key] = "link " + fs::read_symlink(entry.path()).string();
    } else if (entry.is_regular_file()) {
      entries[key] = "file " + readFile(entry.path().string());
    } else {
      entries[key] = "folder";
    }
  }
  return entries;
}

class KeystoreWriterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    keystore_ = temp_.path() / "keystore";
    options_.domains = {0, 0};
    ASSERT_TRUE(createKeystore(keystore_, options_));
  }

  fs::path enclave(const std::string& relative) const { return keystore_ / "enclaves" / relative; }
  void makeEnclave(const char* name = kEnclave) {
    auto made = createEnclave(keystore_, name, enclave_options_);
    ASSERT_TRUE(made) << made.error().message;
  }
  fs::path policy(const std::string& text) const {
    fs::path file = temp_.path() / "policy.yaml";
    writeText(file.string(), text);
    return file;
  }

  test::TempDir temp_;
  fs::path keystore_;
  KeystoreOptions options_;
  EnclaveOptions enclave_options_;
};

// ---- keystore ----

TEST_F(KeystoreWriterTest, CreateKeystoreWritesSros2Layout) {
  for (const char* file : {"public/ca.cert.pem", "private/ca.key.pem", "enclaves/governance.xml",
                           "enclaves/governance.p7s"}) {
    EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(keystore_ / file))) << file;
  }
  EXPECT_EQ(fs::read_symlink(keystore_ / "public/identity_ca.cert.pem"), "ca.cert.pem");
  EXPECT_EQ(fs::read_symlink(keystore_ / "public/permissions_ca.cert.pem"), "ca.cert.pem");
  EXPECT_EQ(fs::read_symlink(keystore_ / "private/identity_ca.key.pem"), "ca.key.pem");
  EXPECT_EQ(fs::read_symlink(keystore_ / "private/permissions_ca.key.pem"), "ca.key.pem");
  EXPECT_EQ(modeOf(keystore_ / "private"), 0700U);
  EXPECT_EQ(modeOf(keystore_ / "private/ca.key.pem"), 0600U);
  EXPECT_EQ(
      readFile((keystore_ / "private/ca.key.pem").string()).rfind("-----BEGIN PRIVATE KEY", 0), 0U)
      << "PKCS#8, unencrypted";
  std::vector<std::string> hidden;
  for (const auto& entry : fs::recursive_directory_iterator(keystore_)) {
    if (entry.path().filename().string().front() == '.') {
      hidden.push_back(entry.path().string());
    }
  }
  EXPECT_TRUE(hidden.empty()) << "temporary files left: " << hidden.front();
}

TEST_F(KeystoreWriterTest, CaIsSelfSignedP256WithCriticalPathlen1) {
  X509Ptr ca = readCertificate(keystore_ / "public/ca.cert.pem");
  ASSERT_TRUE(ca);
  EXPECT_EQ(subjectText(ca.get()), "CN=sros2CA");
  EXPECT_EQ(X509_NAME_cmp(X509_get_subject_name(ca.get()), X509_get_issuer_name(ca.get())), 0);
  EXPECT_EQ(X509_get_version(ca.get()), 2);
  EXPECT_NE(X509_get_extension_flags(ca.get()) & EXFLAG_CA, 0U);
  EXPECT_EQ(X509_get_pathlen(ca.get()), 1);
  const int at = X509_get_ext_by_NID(ca.get(), NID_basic_constraints, -1);
  ASSERT_GE(at, 0);
  EXPECT_EQ(X509_EXTENSION_get_critical(X509_get_ext(ca.get(), at)), 1);
  EXPECT_EQ(X509_get_signature_nid(ca.get()), NID_ecdsa_with_SHA256);
  char group[64] = {};
  ASSERT_EQ(EVP_PKEY_get_group_name(X509_get0_pubkey(ca.get()), group, sizeof group, nullptr), 1);
  EXPECT_STREQ(group, "prime256v1");
  EXPECT_NEAR(secondsFromNow(X509_get0_notBefore(ca.get())), -kSecondsPerDay, 60);
  EXPECT_NEAR(secondsFromNow(X509_get0_notAfter(ca.get())), 3650 * kSecondsPerDay, 60);
  EXPECT_TRUE(verifiesAgainst(ca, keystore_ / "public/identity_ca.cert.pem"));
}

TEST_F(KeystoreWriterTest, GovernanceP7sVerifiesAndCarriesTheXml) {
  const std::string xml = readFile((keystore_ / "enclaves/governance.xml").string());
  const std::string p7s = readFile((keystore_ / "enclaves/governance.p7s").string());
  const auto content = verifiedContent(p7s, keystore_ / "public/permissions_ca.cert.pem");
  ASSERT_TRUE(content);
  EXPECT_EQ(unixLines(*content), xml);
  EXPECT_NE(p7s.find("micalg=\"sha-256\""), std::string::npos) << p7s;
  for (const char* part :
       {"<id>0</id>", "<allow_unauthenticated_participants>false<",
        "<enable_join_access_control>true<", "<discovery_protection_kind>ENCRYPT<",
        "<liveliness_protection_kind>ENCRYPT<", "<rtps_protection_kind>SIGN<",
        "<topic_expression>*</topic_expression>", "<enable_read_access_control>true<",
        "<enable_write_access_control>true<", "<metadata_protection_kind>ENCRYPT<",
        "<data_protection_kind>ENCRYPT<"}) {
    EXPECT_NE(xml.find(part), std::string::npos) << part;
  }
}

TEST_F(KeystoreWriterTest, TamperedDocumentDoesNotVerify) {
  std::string p7s = readFile((keystore_ / "enclaves/governance.p7s").string());
  const std::size_t at = p7s.find("<rtps_protection_kind>SIGN<");
  ASSERT_NE(at, std::string::npos);
  p7s.replace(at, 26, "<rtps_protection_kind>NONE<");
  EXPECT_FALSE(verifiedContent(p7s, keystore_ / "public/permissions_ca.cert.pem"));
}

TEST(KeystoreWriter, DomainRangeBecomesIdRange) {
  test::TempDir temp;
  KeystoreOptions options;
  options.domains = {3, 7};
  ASSERT_TRUE(createKeystore(temp.path() / "k", options));
  const std::string xml = readFile((temp.path() / "k/enclaves/governance.xml").string());
  EXPECT_TRUE(test::contains(xml, "<id_range>"));
  EXPECT_TRUE(test::contains(xml, "<min>3</min>"));
  EXPECT_TRUE(test::contains(xml, "<max>7</max>"));
  EXPECT_EQ(xml.find("<id>"), std::string::npos) << xml;
}

TEST_F(KeystoreWriterTest, ExistingKeystoreIsRefusedAndUntouched) {
  const auto before = snapshot(keystore_);
  auto again = createKeystore(keystore_, options_);
  ASSERT_FALSE(again);
  EXPECT_TRUE(test::contains(again.error().message, keystore_.string()));
  EXPECT_TRUE(test::contains(again.error().message, "already holds a keystore"));
  EXPECT_EQ(snapshot(keystore_), before);
}

// ---- enclaves ----

TEST_F(KeystoreWriterTest, EnclaveHasIdentityLinksAndPermissions) {
  makeEnclave();
  const fs::path folder = enclave("raymap/raymapd");
  EXPECT_EQ(modeOf(folder / "key.pem"), 0600U);
  EXPECT_EQ(fs::read_symlink(folder / "identity_ca.cert.pem"),
            "../../../public/identity_ca.cert.pem");
  EXPECT_EQ(fs::read_symlink(folder / "permissions_ca.cert.pem"),
            "../../../public/permissions_ca.cert.pem");
  EXPECT_EQ(fs::read_symlink(folder / "governance.p7s"), "../../governance.p7s");
  EXPECT_EQ(readFile((folder / "governance.p7s").string()),
            readFile((keystore_ / "enclaves/governance.p7s").string()));
  X509Ptr cert = readCertificate(folder / "cert.pem");
  ASSERT_TRUE(cert);
  EXPECT_EQ(subjectText(cert.get()), "CN=/raymap/raymapd");
  EXPECT_TRUE(verifiesAgainst(cert, folder / "identity_ca.cert.pem"));
  EXPECT_EQ(X509_get_extension_flags(cert.get()) & EXFLAG_CA, 0U);
  EXPECT_NEAR(secondsFromNow(X509_get0_notBefore(cert.get())), -kSecondsPerDay, 60);
}

TEST_F(KeystoreWriterTest, DefaultPermissionsAllowEverythingAndVerify) {
  makeEnclave();
  const fs::path folder = enclave("raymap/raymapd");
  const std::string xml = readFile((folder / "permissions.xml").string());
  const auto content = verifiedContent(readFile((folder / "permissions.p7s").string()),
                                       folder / "permissions_ca.cert.pem");
  ASSERT_TRUE(content);
  EXPECT_EQ(unixLines(*content), xml);
  const std::vector<std::string> all = {"rt/*", "rq/*", "rr/*", "ros_discovery_info"};
  EXPECT_EQ(topicsOf(xml, "publish"), all);
  EXPECT_EQ(topicsOf(xml, "subscribe"), all);
  EXPECT_TRUE(test::contains(xml, "<grant name=\"/raymap/raymapd\">"));
  EXPECT_TRUE(test::contains(xml, "<subject_name>CN=/raymap/raymapd</subject_name>"));
  EXPECT_TRUE(test::contains(xml, "<default>DENY</default>"));
  // The validity is the certificate's, in ISO 8601 UTC.
  X509Ptr cert = readCertificate(folder / "cert.pem");
  ASSERT_TRUE(cert);
  std::tm tm{};
  ASSERT_EQ(ASN1_TIME_to_tm(X509_get0_notAfter(cert.get()), &tm), 1);
  char text[32];
  std::strftime(text, sizeof text, "<not_after>%Y-%m-%dT%H:%M:%S</not_after>", &tm);
  EXPECT_TRUE(test::contains(xml, text));
}

TEST_F(KeystoreWriterTest, ExistingEnclaveKeepsItsIdentity) {
  makeEnclave();
  const fs::path folder = enclave("raymap/raymapd");
  const std::string key = readFile((folder / "key.pem").string());
  const std::string cert = readFile((folder / "cert.pem").string());
  enclave_options_.domains = {4, 4};
  makeEnclave();
  EXPECT_EQ(readFile((folder / "key.pem").string()), key);
  EXPECT_EQ(readFile((folder / "cert.pem").string()), cert);
  EXPECT_TRUE(test::contains(readFile((folder / "permissions.xml").string()), "<id>4</id>"));
}

TEST_F(KeystoreWriterTest, ListEnclavesIsSorted) {
  makeEnclave("/zeta");
  makeEnclave(kEnclave);
  makeEnclave("/raymap");
  auto names = listEnclaves(keystore_);
  ASSERT_TRUE(names) << names.error().message;
  EXPECT_EQ(*names, (std::vector<std::string>{"/raymap", "/raymap/raymapd", "/zeta"}));
}

TEST_F(KeystoreWriterTest, InvalidEnclaveNamesAreRefused) {
  const auto before = snapshot(keystore_);
  for (const char* name :
       {"", "raymap", "/", "/a//b", "/a/", "/a/../b", "/a/./b", "/a b", "/a-b", "/1abc", "/x/..",
        "/aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa"}) {
    auto made = createEnclave(keystore_, name, enclave_options_);
    ASSERT_FALSE(made) << name;
    EXPECT_TRUE(test::contains(made.error().message, "\"" + std::string(name) + "\""));
  }
  EXPECT_EQ(snapshot(keystore_), before);
}

// ---- policy files ----

constexpr const char* kPolicy = R"(# which enclave may publish or subscribe which ROS 2 topics
enclaves:
  /raymap/raymapd:
    publish: [/height_map, /diagnostics]
    subscribe: [/points, /odom, /tf, /tf_static, /height_map]
  /nav2/planner:
    subscribe: [/height_map]
)";

TEST_F(KeystoreWriterTest, PolicyBecomesGrantsWithDdsNames) {
  auto grants = readPolicyFile(policy(kPolicy));
  ASSERT_TRUE(grants) << grants.error().message;
  ASSERT_EQ(grants->size(), 2U);
  EXPECT_EQ((*grants)[0].enclave, "/raymap/raymapd");
  EXPECT_EQ((*grants)[0].publish, (std::vector<std::string>{"rt/height_map", "rt/diagnostics"}));
  EXPECT_EQ((*grants)[0].subscribe, (std::vector<std::string>{"rt/points", "rt/odom", "rt/tf",
                                                              "rt/tf_static", "rt/height_map"}));
  EXPECT_EQ((*grants)[1].enclave, "/nav2/planner");
  EXPECT_TRUE((*grants)[1].publish.empty());
  EXPECT_EQ((*grants)[1].subscribe, (std::vector<std::string>{"rt/height_map"}));
}

TEST_F(KeystoreWriterTest, PermissionsFromPolicyListExactlyItsTopics) {
  makeEnclave();
  auto grants = readPolicyFile(policy(kPolicy));
  ASSERT_TRUE(grants) << grants.error().message;
  for (const EnclaveGrant& grant : *grants) {
    auto written = writePermissions(keystore_, grant, enclave_options_);
    ASSERT_TRUE(written) << written.error().message;
  }
  const std::string raymapd = readFile(enclave("raymap/raymapd/permissions.xml").string());
  EXPECT_EQ(topicsOf(raymapd, "publish"),
            (std::vector<std::string>{"rt/height_map", "rt/diagnostics", "ros_discovery_info"}));
  EXPECT_EQ(topicsOf(raymapd, "subscribe"),
            (std::vector<std::string>{"rt/points", "rt/odom", "rt/tf", "rt/tf_static",
                                      "rt/height_map", "ros_discovery_info"}));
  // The planner had no folder: it was created with its identity first.
  const fs::path planner = enclave("nav2/planner");
  EXPECT_TRUE(fs::is_regular_file(planner / "key.pem"));
  EXPECT_TRUE(verifiesAgainst(readCertificate(planner / "cert.pem"),
                              keystore_ / "public/identity_ca.cert.pem"));
  const std::string xml = readFile((planner / "permissions.xml").string());
  EXPECT_EQ(topicsOf(xml, "publish"), (std::vector<std::string>{"ros_discovery_info"}));
  EXPECT_EQ(topicsOf(xml, "subscribe"),
            (std::vector<std::string>{"rt/height_map", "ros_discovery_info"}));
  const auto content = verifiedContent(readFile((planner / "permissions.p7s").string()),
                                       keystore_ / "public/permissions_ca.cert.pem");
  ASSERT_TRUE(content);
  EXPECT_EQ(unixLines(*content), xml);
}

TEST_F(KeystoreWriterTest, NamesAreXmlEscaped) {
  makeEnclave();
  const EnclaveGrant grant{kEnclave, {"rt/a<b>&\"c\""}, {}};
  ASSERT_TRUE(writePermissions(keystore_, grant, enclave_options_));
  const std::string xml = readFile(enclave("raymap/raymapd/permissions.xml").string());
  EXPECT_TRUE(test::contains(xml, "<topic>rt/a&lt;b&gt;&amp;&quot;c&quot;</topic>"));
}

struct BadPolicy {
  const char* text;
  std::vector<std::string> parts;  ///< what the message must name
};

TEST_F(KeystoreWriterTest, BadPolicyErrorsNameFileAndEntry) {
  const std::vector<BadPolicy> cases = {
      {"enclaves:\n  /a:\n    publish: [/x]\nenclave: {}\n", {"line 4", "unknown key \"enclave\""}},
      {"enclaves:\n  /a:\n    publsh: [/x]\n", {"line 3", "enclave /a", "unknown key \"publsh\""}},
      {"enclaves:\n  /raymap/raymapd:\n    subscribe: [/odom, points]\n",
       {"line 3", "enclave /raymap/raymapd", "subscribe[1]", "\"points\"", "'/'"}},
      {"enclaves:\n  raymapd:\n    publish: [/x]\n", {"line 2", "\"raymapd\"", "'/'"}},
      {"enclaves:\n  /a:\n    publish: /x\n", {"line 3", "enclave /a: publish", "list"}},
      {"enclaves: [\n", {"not YAML"}},
  };
  for (const BadPolicy& bad : cases) {
    const fs::path file = policy(bad.text);
    auto grants = readPolicyFile(file);
    ASSERT_FALSE(grants) << bad.text;
    EXPECT_TRUE(test::contains(grants.error().message, file.string() + ": "));
    for (const std::string& part : bad.parts) {
      EXPECT_TRUE(test::contains(grants.error().message, part)) << bad.text;
    }
  }
  auto missing = readPolicyFile(temp_.path() / "none.yaml");
  ASSERT_FALSE(missing);
  EXPECT_TRUE(test::contains(missing.error().message,
                             "none.yaml: cannot read the policy file: No such file"));
}

// ---- failures leave nothing behind ----

TEST(KeystoreWriter, FailedCreateKeystoreLeavesNoFolder) {
  test::TempDir temp;
  KeystoreOptions bad_domains;
  bad_domains.domains = {5, 3};
  auto refused = createKeystore(temp.path() / "a/b/k", bad_domains);
  ASSERT_FALSE(refused);
  EXPECT_TRUE(test::contains(refused.error().message, "domains 5-3"));
  KeystoreOptions long_name;
  long_name.common_name = std::string(65, 'c');
  auto failed = createKeystore(temp.path() / "a/b/k", long_name);
  ASSERT_FALSE(failed);
  EXPECT_TRUE(test::contains(failed.error().message, temp.path().string() + "/a/b/k: "));
  EXPECT_TRUE(fs::is_empty(temp.path()));
}

TEST(KeystoreWriter, FailureMidwayRemovesWhatItMade) {
  test::TempDir temp;
  const fs::path keystore = temp.path() / "k";
  fs::create_directory(keystore);
  writeText((keystore / "enclaves").string(), "a file where a folder must go");
  auto failed = createKeystore(keystore, KeystoreOptions{});
  ASSERT_FALSE(failed);
  EXPECT_TRUE(test::contains(failed.error().message, (keystore / "enclaves").string()));
  EXPECT_EQ(snapshot(keystore).size(), 1U) << "only the file that was there";
}

TEST_F(KeystoreWriterTest, FailedEnclaveLeavesNoFolder) {
  fs::remove(keystore_ / "private/ca.key.pem");
  writeText((keystore_ / "private/ca.key.pem").string(), "not a key\n");
  auto failed = createEnclave(keystore_, kEnclave, enclave_options_);
  ASSERT_FALSE(failed);
  EXPECT_TRUE(
      test::contains(failed.error().message, (keystore_ / "private/identity_ca.key.pem").string() +
                                                 ": cannot read the identity CA's key"));
  EXPECT_FALSE(fs::exists(keystore_ / "enclaves/raymap"));
  fs::remove(keystore_ / "private/ca.key.pem");
  auto missing = signWithPermissionsCa(keystore_, "x");
  ASSERT_FALSE(missing);
  EXPECT_TRUE(test::contains(missing.error().message,
                             "private/permissions_ca.key.pem: cannot read the permissions CA's "
                             "key: No such file or directory"));
  auto no_keystore = createEnclave(temp_.path() / "nothing", kEnclave, enclave_options_);
  ASSERT_FALSE(no_keystore);
  EXPECT_TRUE(test::contains(no_keystore.error().message, "nothing: not a keystore"));
  EXPECT_FALSE(fs::exists(temp_.path() / "nothing"));
}

// ---- options ----

/// Sets (or with nullptr unsets) ROS_DOMAIN_ID for one scope and restores it after.
class ScopedDomainId {
 public:
  explicit ScopedDomainId(const char* value) {
    // The test runs on one thread: setenv and getenv do not race here.
    if (const char* old = std::getenv("ROS_DOMAIN_ID")) {
      old_ = old;
    }
    value != nullptr ? ::setenv("ROS_DOMAIN_ID", value, 1) : ::unsetenv("ROS_DOMAIN_ID");
  }
  ~ScopedDomainId() {
    old_ ? ::setenv("ROS_DOMAIN_ID", old_->c_str(), 1) : ::unsetenv("ROS_DOMAIN_ID");
  }
  ScopedDomainId(const ScopedDomainId&) = delete;
  ScopedDomainId& operator=(const ScopedDomainId&) = delete;

 private:
  std::optional<std::string> old_;
};

Result<DomainRange> defaultDomainWith(const char* value) {
  const ScopedDomainId scoped(value);
  return defaultDomainRange();
}

TEST(KeystoreWriter, DefaultDomainIsRosDomainId) {
  auto unset = defaultDomainWith(nullptr);
  auto set = defaultDomainWith("42");
  auto bad = defaultDomainWith("233");
  ASSERT_TRUE(unset && set);
  EXPECT_EQ(unset->min, 0U);
  EXPECT_EQ(unset->max, 0U);
  EXPECT_EQ(set->min, 42U);
  EXPECT_EQ(set->max, 42U);
  ASSERT_FALSE(bad);
  EXPECT_TRUE(test::contains(bad.error().message, "ROS_DOMAIN_ID=\"233\""));
}

TEST(KeystoreWriter, ValidityStartsADayAgo) {
  const auto now = std::chrono::system_clock::now();
  const Validity v = validityForDays(10);
  EXPECT_NEAR(std::chrono::duration<double>(now - v.not_before).count(), kSecondsPerDay, 5.0);
  EXPECT_NEAR(std::chrono::duration<double>(v.not_after - now).count(), 10.0 * kSecondsPerDay, 5.0);
}

// ---- an independent implementation checks ours ----

TEST_F(KeystoreWriterTest, OpensslProgramVerifiesSignaturesAndCertificate) {
  if (!fs::exists("/usr/bin/openssl")) {
    GTEST_SKIP() << "no /usr/bin/openssl (Debian's openssl package)";
  }
  makeEnclave();
  const std::string ca = (keystore_ / "public/permissions_ca.cert.pem").string();
  const std::string folder = enclave("raymap/raymapd").string();
  for (const std::string& p7s :
       {(keystore_ / "enclaves/governance.p7s").string(), folder + "/permissions.p7s"}) {
    const auto run = test::runProgram(
        {"/usr/bin/openssl", "smime", "-verify", "-in", p7s, "-CAfile", ca, "-out", "/dev/null"});
    EXPECT_EQ(run.exit_code, 0) << p7s << "\n" << test::describe(run);
  }
  const auto verify =
      test::runProgram({"/usr/bin/openssl", "verify", "-CAfile",
                        (keystore_ / "public/ca.cert.pem").string(), folder + "/cert.pem"});
  EXPECT_EQ(verify.exit_code, 0) << test::describe(verify);
}

}  // namespace
}  // namespace raymap::security
