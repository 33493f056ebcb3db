// SPDX-License-Identifier: BSD-3-Clause
#include "tests/support/golden_manifest.hpp"

#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace raymap::test {

std::map<std::string, std::string> readSha256Manifest(const std::string& path) {
  std::map<std::string, std::string> out;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string sha;
    std::string name;
    if (words >> sha >> name) {
      out[name] = sha;
    }
  }
  return out;
}

std::string sha256OfFile(const std::string& path) {
  const std::string command = "sha256sum -- '" + path + "'";
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) {
    return {};
  }
  std::array<char, 65> hex{};
  const std::size_t read = std::fread(hex.data(), 1, 64, pipe);
  const int status = ::pclose(pipe);
  return read == 64 && status == 0 ? std::string(hex.data(), 64) : std::string();
}

}  // namespace raymap::test
