// SPDX-License-Identifier: BSD-3-Clause
// Scratch files for fuzz inputs.
#include "tests/fuzz/fuzz_input_file.hpp"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>

#include <unistd.h>

namespace raymap::fuzz {
namespace {

std::string scratchDirectory() {
  if (const char* dir = std::getenv("RAYMAP_FUZZ_TMPDIR"); dir != nullptr && *dir != '\0') {
    return dir;
  }
  std::error_code error;
  if (std::filesystem::is_directory("/dev/shm", error)) {
    return "/dev/shm";
  }
  if (const char* dir = std::getenv("TMPDIR"); dir != nullptr && *dir != '\0') {
    return dir;
  }
  return "/tmp";
}

/// The scratch files of this process, removed at exit (std::atexit runs after libFuzzer's
/// final statistics, and when the replay driver returns).
std::map<std::string, std::string>& scratchFiles() {
  static std::map<std::string, std::string> files;  // suffix or name -> path
  return files;
}

void removeScratchFiles() {
  for (const auto& [key, path] : scratchFiles()) {
    std::remove(path.c_str());
  }
}

const std::string& pathFor(const std::string& key) {
  auto& files = scratchFiles();
  auto found = files.find(key);
  if (found == files.end()) {
    if (files.empty()) {
      std::atexit(removeScratchFiles);
    }
    const std::string path =
        scratchDirectory() + "/raymap-fuzz-" + std::to_string(::getpid()) + key;
    found = files.emplace(key, path).first;
  }
  return found->second;
}

void writeOrAbort(const std::string& path, const void* data, std::size_t size) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr || (size > 0 && std::fwrite(data, 1, size, file) != size) ||
      std::fclose(file) != 0) {
    std::perror(path.c_str());
    std::abort();
  }
}

}  // namespace

const std::string& writeInputFile(const std::uint8_t* data, std::size_t size,
                                  const std::string& suffix) {
  const std::string& path = pathFor(suffix);
  writeOrAbort(path, data, size);
  return path;
}

const std::string& writeFixedFile(const std::string& name, const std::string& contents) {
  const std::string& path = pathFor("-" + name);
  writeOrAbort(path, contents.data(), contents.size());
  return path;
}

}  // namespace raymap::fuzz
