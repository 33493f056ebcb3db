// SPDX-License-Identifier: BSD-3-Clause
// raymap-fastdds-peer as a child process of a test: its JSON result and its log in files.
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tests/service/daemon_process.hpp"
#include "tests/support/json_doc.hpp"
#include "tests/support/temp_dir.hpp"

namespace raymap::test {

/// @brief True when the peer program exists (it is built only with Fast DDS and fastddsgen).
bool fastDdsPeerBuilt();

/// @brief One running raymap-fastdds-peer (killed when destroyed, if still running).
class PeerProcess {
 public:
  /// @brief Starts `raymap-fastdds-peer --domain DOMAIN --output FILE options... MODE args...`,
  /// through `launcher` when one is given (e.g. `ip netns exec NAME`).
  PeerProcess(std::uint32_t domain, const std::string& mode, const std::vector<std::string>& args,
              const std::vector<std::string>& options = {},
              const std::vector<std::string>& launcher = {});
  bool running() { return process_->running(); }
  /// @brief Waits up to `timeout` for the peer to end by itself; then, or with `stop`, sends
  /// SIGTERM (it ends its run early and still reports). @return its exit status; nullopt when
  /// it did not exit even then.
  std::optional<int> finish(std::chrono::milliseconds timeout);
  /// @brief The peer's JSON, or nullopt (the test has failed) when it wrote none or not JSON.
  std::optional<Json> result() const;
  std::string log() const;

 private:
  TempDir dir_;
  std::unique_ptr<DaemonProcess> process_;
};

/// @brief A number of a JSON object by a path of member names ("last_map", "resolution"), or
/// nullopt.
std::optional<double> numberAt(const Json& value, const std::vector<std::string>& path);

/// @brief A string of a JSON object by a path of member names, or nullopt.
std::optional<std::string> textAt(const Json& value, const std::vector<std::string>& path);

/// @brief An array of strings (or numbers, as text) of a JSON object by a path of member names.
std::vector<std::string> textsAt(const Json& value, const std::vector<std::string>& path);

}  // namespace raymap::test
