// SPDX-License-Identifier: BSD-3-Clause
// PeerProcess: DaemonProcess with the peer's arguments, and reading its JSON back.
#include "tests/fastdds/peer_process.hpp"

#include <cmath>
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

std::optional<JsonValue> PeerProcess::result() const {
  if (!std::filesystem::exists(dir_.file("result.json"))) {
    return std::nullopt;
  }
  const std::string text = readFile(dir_.file("result.json"));
  std::printf("raymap-fastdds-peer: %s", text.c_str());  // the figures, for the test's log
  return parseJson(text);
}

std::string PeerProcess::log() const { return readFile(dir_.file("peer.log")); }

std::optional<double> numberAt(const JsonValue& value, const std::vector<std::string>& path) {
  const JsonValue* at = &value;
  for (const std::string& key : path) {
    at = at->find(key);
    if (at == nullptr) {
      return std::nullopt;
    }
  }
  if (at->kind != JsonValue::Kind::kNumber) {
    return std::nullopt;
  }
  return at->number;
}

std::vector<std::string> textsAt(const JsonValue& value, const std::vector<std::string>& path) {
  const JsonValue* at = &value;
  for (const std::string& key : path) {
    at = at->find(key);
    if (at == nullptr) {
      return {};
    }
  }
  std::vector<std::string> out;
  for (const JsonValue& item : at->items) {
    out.push_back(item.kind == JsonValue::Kind::kNumber ? std::to_string(std::llround(item.number))
                                                        : item.text);
  }
  return out;
}

}  // namespace raymap::test
