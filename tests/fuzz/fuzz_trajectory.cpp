// SPDX-License-Identifier: BSD-3-Clause
// Fuzz target: a text trajectory (time x y z [qw qx qy qz]), loaded and queried.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "src/io/trajectory.hpp"
#include "tests/fuzz/fuzz_input_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto trajectory = raymap::io::Trajectory::load(raymap::fuzz::writeInputFile(data, size, ".txt"));
  if (!trajectory) {
    return 0;
  }
  // A loaded trajectory answers every query inside it (poses far out may overflow to
  // infinity: a trajectory's magnitudes are not bounded, only finite).
  const double start = trajectory->startTime();
  const double end = trajectory->endTime();
  std::size_t hint = 0;
  for (int i = 0; i <= 8; ++i) {
    const double t = start + (end - start) * (i / 8.0);
    if (!trajectory->poseAt(t, hint) && trajectory->covers(t)) {
      std::abort();  // inside the trajectory there is always a pose
    }
  }
  return 0;
}
