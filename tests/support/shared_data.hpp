// SPDX-License-Identifier: BSD-3-Clause
// The shared real data sets (../shared/data): which files they are, reading their rays and
// walking them scan by scan.
#pragma once

#include <cstddef>
#include <filesystem>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include "src/map/map_params.hpp"
#include "src/map/ray.hpp"

namespace raymap::test {

/// @brief One data set of the shared data folder.
struct DataSet {
  const char* name;
  const char* file;        ///< under sharedDataDir()
  const char* trajectory;  ///< point clouds: under sharedDataDir(); nullptr for ray clouds
};

/// @brief Every shared data set, in the order of docs/benchmarks.md.
std::span<const DataSet> sharedDataSets();

/// @brief One data set under one semantics: the parameter of the agreement tests.
struct DataCase {
  DataSet data;
  Semantics semantics;
};
void PrintTo(const DataCase& c, std::ostream* os);

/// @brief Every data set under both semantics.
std::vector<DataCase> dataCases();

/// @brief A test name for a case: "<data>_<semantics>", other characters replaced by '_'.
std::string dataCaseName(const DataCase& c);

/// @brief The files of a data set: empty when present, else why not (the test skips with it).
struct DataFiles {
  std::filesystem::path file;
  std::filesystem::path trajectory;  ///< empty for ray clouds
  std::string missing;
};
DataFiles dataFiles(const DataSet& data);

/// @brief Reads every ray of a file (with `trajectory` unless it is empty), failing the test on a
/// read error. @return the rays, or nothing after a failure.
std::vector<Ray> loadRays(const std::filesystem::path& file,
                          const std::filesystem::path& trajectory);

/// @brief Calls `fn` on every run of rays with equal scan index (the data sets are ordered by
/// scan).
template <class Fn>
void forEachScan(std::span<const Ray> rays, Fn&& fn) {
  std::size_t begin = 0;
  while (begin < rays.size()) {
    std::size_t end = begin + 1;
    while (end < rays.size() && rays[end].scan == rays[begin].scan) {
      ++end;
    }
    fn(rays.subspan(begin, end - begin));
    begin = end;
  }
}

}  // namespace raymap::test
