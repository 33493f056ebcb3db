// SPDX-License-Identifier: BSD-3-Clause
// Fuzz inputs for readers that take a path: the bytes go to one scratch file per process and
// extension, rewritten for every input.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace raymap::fuzz {

/// @brief Writes `data` to "<dir>/raymap-fuzz-<pid><suffix>" and returns that path. The
/// directory is $RAYMAP_FUZZ_TMPDIR, else /dev/shm when it exists (no disk I/O per input), else
/// $TMPDIR or /tmp. The suffix matters to readers that choose by extension (".ply.gz", ".mcap").
/// The file is removed at exit. Aborts when it cannot be written (the fuzzer's fault, not the
/// input's). Not thread-safe (libFuzzer calls one input at a time).
const std::string& writeInputFile(const std::uint8_t* data, std::size_t size,
                                  const std::string& suffix);

/// @brief A second scratch file beside the first, written once (e.g. a fixed trajectory that
/// the fuzzed point clouds are read with).
const std::string& writeFixedFile(const std::string& name, const std::string& contents);

}  // namespace raymap::fuzz
