// SPDX-License-Identifier: BSD-3-Clause
// `raymap security`: SROS2 keystores, enclaves and permissions, as `ros2 security` writes them.
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "src/security/keystore/keystore_layout.hpp"
#include "src/security/keystore/keystore_writer.hpp"
#include "src/security/security_config.hpp"
#include "tools/raymap/commands.hpp"

namespace raymap::cli {
namespace {

namespace fs = std::filesystem;
using security::DomainRange;
using security::EnclaveOptions;

constexpr int kMaxDays = 36500;  // 100 years: far inside what a certificate's time can hold

/// The options shared by the subcommands that write documents.
struct DocumentFlags {
  int domain = -1;      ///< --domain N; -1: not given
  std::string domains;  ///< --domains MIN-MAX; empty: not given
  int days = 3650;
};

struct SecurityFlags {
  std::string keystore;
  std::string enclave;      ///< create-enclave NAME, create-permissions --enclave NAME
  std::string policy;       ///< create-permissions POLICY.yaml
  std::string common_name;  ///< create-keystore --common-name
  DocumentFlags document;
};

/// "MIN-MAX" as a range of domain ids.
Result<DomainRange> parseDomains(const std::string& text) {
  const std::size_t dash = text.find('-');
  auto bad = [&] {
    return fail(ErrorCode::kInvalidArgument,
                "--domains \"" + text + "\": not MIN-MAX with 0 <= MIN <= MAX <= " +
                    std::to_string(security::kMaxKeystoreDomainId) + " (e.g. 0-10)");
  };
  if (dash == std::string::npos) {
    return bad();
  }
  const std::string parts[2] = {text.substr(0, dash), text.substr(dash + 1)};
  unsigned long values[2] = {0, 0};
  for (int i = 0; i < 2; ++i) {
    char* end = nullptr;
    errno = 0;
    values[i] = std::strtoul(parts[i].c_str(), &end, 10);
    if (parts[i].empty() || parts[i].front() == '-' || parts[i].front() == '+' || errno != 0 ||
        *end != '\0') {
      return bad();
    }
  }
  if (values[0] > values[1] || values[1] > security::kMaxKeystoreDomainId) {
    return bad();
  }
  return DomainRange{static_cast<std::uint32_t>(values[0]), static_cast<std::uint32_t>(values[1])};
}

/// --domain, --domains, else $ROS_DOMAIN_ID (else 0), as sros2.
Result<DomainRange> chosenDomains(const DocumentFlags& flags) {
  if (flags.domain >= 0) {
    const auto domain = static_cast<std::uint32_t>(flags.domain);
    return DomainRange{domain, domain};
  }
  if (!flags.domains.empty()) {
    return parseDomains(flags.domains);
  }
  return security::defaultDomainRange();
}

void addDocumentOptions(CLI::App* c, DocumentFlags& flags, const char* what) {
  CLI::Option* domain =
      c->add_option(
           "--domain", flags.domain,
           std::string("The one DDS domain ") + what + " cover (default: $ROS_DOMAIN_ID, else 0)")
          ->check(CLI::Range(0, static_cast<int>(security::kMaxKeystoreDomainId)));
  c->add_option("--domains", flags.domains,
                std::string("A range of DDS domains ") + what + " cover, MIN-MAX (e.g. 0-10)")
      ->excludes(domain);
  c->add_option("--days", flags.days,
                "Days a new certificate is valid for, from now (it starts a day ago; default "
                "3650)")
      ->check(CLI::Range(1, kMaxDays));
}

void printPaths(const fs::path& base, const std::vector<const char*>& files) {
  for (const char* file : files) {
    std::printf("%s\n", (base / file).c_str());
  }
}

/// Whether enclave `name` already has its identity (so writing it keeps key and certificate).
bool hasIdentity(const std::string& keystore, const std::string& name) {
  if (!security::checkEnclaveName(name)) {
    return false;
  }
  const fs::path folder = security::enclaveFolder(keystore, name);
  std::error_code error;
  return fs::is_regular_file(folder / security::enclave_files::kKey, error) &&
         fs::is_regular_file(folder / security::enclave_files::kCert, error);
}

int runCreateKeystore(const SecurityFlags& f) {
  const char* command = "security create-keystore";
  auto domains = chosenDomains(f.document);
  if (!domains) {
    printError(command, domains.error().message);
    return kExitUsage;
  }
  security::KeystoreOptions options;
  options.domains = *domains;
  options.ca_validity = security::validityForDays(f.document.days);
  if (!f.common_name.empty()) {
    options.common_name = f.common_name;
  }
  if (auto made = security::createKeystore(f.keystore, options); !made) {
    printError(command, made.error().message);
    return kExitFailure;
  }
  namespace files = security::keystore_files;
  printPaths(f.keystore, {files::kCaCert, files::kIdentityCaCert, files::kPermissionsCaCert,
                          files::kCaKey, files::kIdentityCaKey, files::kPermissionsCaKey,
                          files::kGovernanceXml, files::kGovernanceP7s});
  return kExitOk;
}

Result<EnclaveOptions> enclaveOptions(const DocumentFlags& flags) {
  auto domains = chosenDomains(flags);
  if (!domains) {
    return Unexpected(std::move(domains).error());
  }
  EnclaveOptions options;
  options.domains = *domains;
  options.validity = security::validityForDays(flags.days);
  return options;
}

int runCreateEnclave(const SecurityFlags& f) {
  const char* command = "security create-enclave";
  auto options = enclaveOptions(f.document);
  if (!options) {
    printError(command, options.error().message);
    return kExitUsage;
  }
  const bool kept = hasIdentity(f.keystore, f.enclave);
  if (auto made = security::createEnclave(f.keystore, f.enclave, *options); !made) {
    printError(command, made.error().message);
    return kExitFailure;
  }
  namespace files = security::enclave_files;
  const fs::path folder = security::enclaveFolder(f.keystore, f.enclave);
  if (!kept) {
    printPaths(folder, {files::kKey, files::kCert});
  }
  printPaths(folder, {files::kIdentityCaCert, files::kPermissionsCaCert, files::kGovernanceP7s,
                      files::kPermissionsXml, files::kPermissionsP7s});
  return kExitOk;
}

/// The policy's grants, or only --enclave's.
Result<std::vector<security::EnclaveGrant>> chosenGrants(const SecurityFlags& f) {
  auto grants = security::readPolicyFile(f.policy);
  if (!grants || f.enclave.empty()) {
    return grants;
  }
  for (security::EnclaveGrant& grant : *grants) {
    if (grant.enclave == f.enclave) {
      return std::vector<security::EnclaveGrant>{std::move(grant)};
    }
  }
  return fail(ErrorCode::kInvalidArgument,
              "--enclave " + f.enclave + ": not in the policy file " + f.policy);
}

int runCreatePermissions(const SecurityFlags& f) {
  const char* command = "security create-permissions";
  auto options = enclaveOptions(f.document);
  if (!options) {
    printError(command, options.error().message);
    return kExitUsage;
  }
  auto grants = chosenGrants(f);
  if (!grants) {
    printError(command, grants.error().message);
    return kExitFailure;
  }
  for (const security::EnclaveGrant& grant : *grants) {
    const bool kept = hasIdentity(f.keystore, grant.enclave);
    if (auto written = security::writePermissions(f.keystore, grant, *options); !written) {
      printError(command, written.error().message);
      return kExitFailure;
    }
    const fs::path p7s = security::enclaveFolder(f.keystore, grant.enclave) /
                         security::enclave_files::kPermissionsP7s;
    std::printf("%s: %s (%zu publish, %zu subscribe topics%s)\n", grant.enclave.c_str(),
                p7s.c_str(), grant.publish.size(), grant.subscribe.size(),
                kept ? "" : "; new enclave: key.pem, cert.pem");
  }
  return kExitOk;
}

int runListEnclaves(const SecurityFlags& f) {
  auto names = security::listEnclaves(f.keystore);
  if (!names) {
    printError("security list-enclaves", names.error().message);
    return kExitFailure;
  }
  for (const std::string& name : *names) {
    std::printf("%s\n", name.c_str());
  }
  return kExitOk;
}

void addKeystoreArgument(CLI::App* c, SecurityFlags& flags) {
  c->add_option("keystore", flags.keystore, "The keystore folder (ROS_SECURITY_KEYSTORE)")
      ->required();
}

}  // namespace

void addSecurityCommand(CLI::App& app, int* exit_code) {
  CLI::App* security = app.add_subcommand(
      "security", "SROS2 keystores for DDS Security (as `ros2 security` writes them)");
  security->require_subcommand(1);

  auto keystore = std::make_shared<SecurityFlags>();
  CLI::App* c = security->add_subcommand("create-keystore",
                                         "Create a keystore: its CA and signed governance");
  addKeystoreArgument(c, *keystore);
  addDocumentOptions(c, keystore->document, "the governance will");
  c->add_option("--common-name", keystore->common_name, "The CA's common name (default sros2CA)");
  c->callback([keystore, exit_code] { *exit_code = runCreateKeystore(*keystore); });

  auto enclave = std::make_shared<SecurityFlags>();
  c = security->add_subcommand(
      "create-enclave", "Create an enclave (key, certificate, permissions allowing everything)");
  addKeystoreArgument(c, *enclave);
  c->add_option("name", enclave->enclave, "The enclave (/raymap/raymapd)")->required();
  addDocumentOptions(c, enclave->document, "its permissions");
  c->callback([enclave, exit_code] { *exit_code = runCreateEnclave(*enclave); });

  auto permissions = std::make_shared<SecurityFlags>();
  c = security->add_subcommand("create-permissions",
                               "Write and sign the permissions of a policy file's enclaves");
  addKeystoreArgument(c, *permissions);
  c->add_option("policy", permissions->policy, "The policy file (YAML)")->required();
  c->add_option("--enclave", permissions->enclave, "Only this enclave of the policy");
  addDocumentOptions(c, permissions->document, "the permissions");
  c->callback([permissions, exit_code] { *exit_code = runCreatePermissions(*permissions); });

  auto list = std::make_shared<SecurityFlags>();
  c = security->add_subcommand("list-enclaves", "List a keystore's enclaves");
  addKeystoreArgument(c, *list);
  c->callback([list, exit_code] { *exit_code = runListEnclaves(*list); });
}

}  // namespace raymap::cli
