// SPDX-License-Identifier: BSD-3-Clause
// The checks of an SROS2 enclave's files before Cyclone DDS's security plugins read them, so
// that a bad file is refused with its name and the reason (Cyclone itself only fails to create
// the participant, and logs why).
#pragma once

#include <cstdint>
#include <ctime>
#include <filesystem>
#include <span>
#include <string>

#include "raymap/error.hpp"

#include "src/dds/entities.hpp"
#include "src/security/permissions_document.hpp"
#include "src/security/security_config.hpp"

namespace raymap::security {

/// @brief The folder holding an enclave's files: `enclave_dir` when set, else
/// <keystore>/enclaves/<enclave without its leading '/'> (SROS2's layout).
std::filesystem::path enclaveFolder(const SecurityConfig& config);

/// @brief The six files of an enclave folder (absolute paths; SROS2's names).
dds::SecurityFiles enclaveFilesIn(const std::filesystem::path& folder);

/// @brief What a successful check found.
struct EnclaveCheck {
  std::string subject;                    ///< the identity, e.g. "CN=/raymap/raymapd"
  std::time_t certificate_not_after = 0;  ///< when the identity certificate expires
  std::time_t permissions_not_after = 0;  ///< when the grant expires
};

/// @brief Checks what Cyclone's plugins will check, at time `now` (seconds since the epoch):
/// every file readable; the certificates parse and are valid; the identity certificate is
/// signed by the identity CA and the private key is its own; the governance and the permissions
/// are signed by the permissions CA; the governance covers `domain`; the permissions grant the
/// certificate's subject, are valid, and allow each of `needs` on `domain`.
/// @return the identity and expiry times, or an error naming the file and the reason (the first
/// problem found). Start-up only (reads files).
Result<EnclaveCheck> checkEnclave(const dds::SecurityFiles& files, std::uint32_t domain,
                                  std::span<const TopicNeed> needs, std::time_t now);

/// @brief A time as "2036-12-04 18:00:00 UTC".
std::string utcText(std::time_t seconds);

}  // namespace raymap::security
