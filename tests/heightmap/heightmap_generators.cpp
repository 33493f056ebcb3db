// SPDX-License-Identifier: BSD-3-Clause
#include "tests/heightmap/heightmap_generators.hpp"

#include <map>
#include <memory>
#if defined(RAYMAP_HAVE_OPENCL)
#include "src/device/opencl/opencl_heightmap.hpp"
#endif
#if defined(RAYMAP_HAVE_CUDA)
#include "src/device/cuda/cuda_heightmap.hpp"
#endif

namespace raymap::test {

std::vector<std::string> heightmapGeneratorNames() {
  std::vector<std::string> names{"cpu"};
#if defined(RAYMAP_HAVE_OPENCL)
  names.emplace_back("opencl");
#endif
#if defined(RAYMAP_HAVE_CUDA)
  names.emplace_back("cuda");
#endif
  return names;
}

heightmap::HeightmapGenerator* heightmapGenerator(const std::string& name, std::string* why) {
  struct Entry {
    std::unique_ptr<heightmap::HeightmapGenerator> generator;
    std::string why;
  };
  static std::map<std::string, Entry> created;
  auto found = created.find(name);
  if (found == created.end()) {
    Entry entry;
    if (name == "cpu") {
      entry.generator = heightmap::makeCpuHeightmapGenerator();
    }
#if defined(RAYMAP_HAVE_OPENCL)
    if (name == "opencl") {
      auto g = createOpenClHeightmapGenerator({});
      if (g) {
        entry.generator = std::move(*g);
      } else {
        entry.why = g.error().message;
      }
    }
#endif
#if defined(RAYMAP_HAVE_CUDA)
    if (name == "cuda") {
      auto g = createCudaHeightmapGenerator({});
      if (g) {
        entry.generator = std::move(*g);
      } else {
        entry.why = g.error().message;
      }
    }
#endif
    if (!entry.generator && entry.why.empty()) {
      entry.why = "not built";
    }
    found = created.emplace(name, std::move(entry)).first;
  }
  *why = found->second.why;
  return found->second.generator.get();
}

}  // namespace raymap::test
