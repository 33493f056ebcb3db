// SPDX-License-Identifier: BSD-3-Clause
// Reads a fuzzed file as a ray source.
#include "tests/fuzz/ray_source_input.hpp"

#include <array>
#include <cstdlib>

#include "src/io/ray_source.hpp"
#include "tests/fuzz/fuzz_input_file.hpp"

namespace raymap::fuzz {

void readRaySource(const std::string& path) {
  io::RaySourceOptions options;
  // A trajectory covering the times the seeds use (0 to 10 s), with orientations, so that the
  // point-cloud paths (time property, interpolation) are reached as well as the ray clouds.
  options.trajectory_path = writeFixedFile("trajectory.txt",
                                           "# time x y z qw qx qy qz\n"
                                           "-1 0 0 0 1 0 0 0\n"
                                           "5 1 2 0.5 0.9238795 0 0 0.3826834\n"
                                           "11 2 0 1 1 0 0 0\n");
  auto source = io::openRaySource(path, options);
  if (!source) {
    return;
  }
  static std::array<Ray, 1024> rays;
  // Bounded: a header may claim billions of rays, and the data ends long before.
  for (int chunk = 0; chunk < 100'000; ++chunk) {
    auto got = (*source)->read(rays);
    if (!got || *got == 0) {
      return;
    }
    if (*got > rays.size()) {
      std::abort();
    }
  }
}

}  // namespace raymap::fuzz
