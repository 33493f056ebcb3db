// SPDX-License-Identifier: BSD-3-Clause
// PeerProcess: DaemonProcess with the peer's arguments, and reading its JSON back.
#include "tests/fastdds/peer_process.hpp"

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <thread>

#include <unistd.h>

#include "tests/support/cli_runner.hpp"

namespace raymap::test {

bool fastDdsPeerBuilt() { return ::access(RAYMAP_FASTDDS_PEER_PATH, X_OK) == 0; }

PeerProcess::PeerProcess(std::uint32_t domain, const std::string& mode,
                         const std::vector<std::string>& args,
                         const std::vector<std::string>& options,
                         const std::vector<std::string>& launcher) {
  std::vector<std::string> all = launcher;
  all.insert(all.end(), {RAYMAP_FASTDDS_PEER_PATH, "--domain", std::to_string(domain), "--output",
                         dir_.file("result.json")});
  all.insert(all.end(), options.begin(), options.end());
  all.push_back(mode);
  all.insert(all.end(), args.begin(), args.end());
  const std::string binary = all.front();
  all.erase(all.begin());
  process_ = std::make_unique<DaemonProcess>(binary, all, std::vector<std::string>{},
                                             dir_.file("peer.log"));
}

std::optional<int> PeerProcess::finish(std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (process_->running() && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const auto stopped = process_->stop(SIGTERM, kStopWait);
  if (!stopped) {
    return std::nullopt;
  }
  return stopped->first;
}

std::optional<Json> PeerProcess::result() const {
  if (!std::filesystem::exists(dir_.file("result.json"))) {
    return std::nullopt;
  }
  const std::string text = readFile(dir_.file("result.json"));
  std::printf("raymap-fastdds-peer: %s", text.c_str());  // the figures, for the test's log
  return parseJson(text);
}

std::string PeerProcess::log() const { return readFile(dir_.file("peer.log")); }

std::optional<double> numberAt(const Json& value, const std::vector<std::string>& path) {
  const Json* at = findPath(value, path);
  if (at == nullptr || !at->is_number()) {
    return std::nullopt;
  }
  return at->get<double>();
}

std::optional<std::string> textAt(const Json& value, const std::vector<std::string>& path) {
  const Json* at = findPath(value, path);
  if (at == nullptr || !at->is_string()) {
    return std::nullopt;
  }
  return at->get<std::string>();
}

std::vector<std::string> textsAt(const Json& value, const std::vector<std::string>& path) {
  const Json* at = findPath(value, path);
  if (at == nullptr || !at->is_array()) {
    return {};
  }
  std::vector<std::string> out;
  for (const Json& item : *at) {
    // Numbers as the peer writes them (integers: "120"), texts as they are.
    out.push_back(item.is_string() ? item.get<std::string>() : item.dump());
  }
  return out;
}

}  // namespace raymap::test
