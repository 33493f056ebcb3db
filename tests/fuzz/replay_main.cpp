// SPDX-License-Identifier: BSD-3-Clause
// main() for a fuzz target in a build without libFuzzer (GCC, or Clang without RAYMAP_FUZZ): runs
// the target once on every file named (directories: every file in them, in name order). CTest
// runs it over the checked-in seed corpus and the regression inputs, so that every build proves
// they still pass; a crash fails the test (and, in the sanitizer builds, so does any report).
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);
extern "C" __attribute__((weak)) int LLVMFuzzerInitialize(int* argc, char*** argv);

namespace {

std::vector<std::filesystem::path> inputsIn(const std::filesystem::path& path) {
  std::vector<std::filesystem::path> inputs;
  if (std::filesystem::is_directory(path)) {
    for (const auto& entry : std::filesystem::directory_iterator(path)) {
      if (entry.is_regular_file()) {
        inputs.push_back(entry.path());
      }
    }
    std::sort(inputs.begin(), inputs.end());
  } else {
    inputs.push_back(path);
  }
  return inputs;
}

}  // namespace

int main(int argc, char** argv) {
  if (LLVMFuzzerInitialize != nullptr) {
    LLVMFuzzerInitialize(&argc, &argv);
  }
  std::size_t count = 0;
  for (int i = 1; i < argc; ++i) {
    const std::filesystem::path arg(argv[i]);
    if (!std::filesystem::exists(arg)) {
      continue;  // an empty corpus folder is not in git; nothing to run
    }
    for (const auto& input : inputsIn(arg)) {
      std::ifstream file(input, std::ios::binary);
      if (!file) {
        std::fprintf(stderr, "%s: cannot read\n", input.c_str());
        return 1;
      }
      const std::vector<char> bytes((std::istreambuf_iterator<char>(file)),
                                    std::istreambuf_iterator<char>());
      // Through a buffer of exactly the input's size, as libFuzzer passes it, so that reading one
      // byte too far is an AddressSanitizer report here too.
      std::vector<std::uint8_t> exact(bytes.begin(), bytes.end());
      LLVMFuzzerTestOneInput(exact.empty() ? nullptr : exact.data(), exact.size());
      ++count;
    }
  }
  std::printf("ran %zu inputs\n", count);
  return count == 0 ? 1 : 0;
}
