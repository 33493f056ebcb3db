#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Checks that dependencies point one way: kernels/common <- src/core <- platform <- src/map <-
# src/heightmap, src/sim <- src/io, src/device/staging <- src/device/opencl, src/device/cuda <-
# src/device (the backend factory); src/msgs (ROS 2 messages, no transport) <- src/pipeline,
# src/bag, src/dds <- src/service <- tools; src/dds, src/sim <- src/driver (ROS-like endpoints,
# simulated sensors) <- src/replay (recordings played over DDS) <- tools;
# src/config (YAML reading) and src/record (the record log format) depend on core only.
# Includes are written relative to the repository root, so grep can tell.
set -euo pipefail
root=${1:-.}
cd "$root"
status=0
check() {  # check <folder> <regex of forbidden include prefixes> <why>
  local hits
  hits=$(grep -rnE "#include \"($2)" "$1" --include='*.h' --include='*.hpp' --include='*.cpp' --include='*.cl' --include='*.cu' || true)
  if [ -n "$hits" ]; then
    echo "layering: $1 must not include $2 ($3):"
    echo "$hits"
    status=1
  fi
}
check kernels/common 'src/|platform/|tools/|tests/' 'device code depends on nothing'
check src/core 'src/map|src/io|src/sim|platform/|tools/|tests/' 'core is the base'
check platform 'src/map|src/io|src/sim|tools/|tests/' 'platform depends only on core'
check src/map 'src/io|src/sim|tools/|tests/' 'the map does not know files or tools'
check src/heightmap 'src/io|src/sim|src/device/|tools/|tests/' 'height maps read the map only; writers live in src/io'
check src/io 'src/sim|tools/|tests/' 'file formats do not know scenes or tools'
check src/sim 'src/io|tools/|tests/' 'scenes produce rays, not files'
check src/config 'src/map|src/io|src/sim|src/dds|src/pipeline|src/service|platform/|tools/|tests/' 'configuration reading depends only on core'
check src/record 'src/map|src/io|src/sim|src/dds|src/pipeline|src/service|platform/|tools/|tests/' 'the log format knows bytes, not DDS'
check src/msgs 'src/map|src/io|src/sim|src/dds|src/pipeline|src/service|src/bag|src/device/|platform/|tools/|tests/|dds/|ddsc/' 'message codecs need no transport, map or files'
check src/dds 'src/sim|src/device/|src/pipeline|src/service|tools/|tests/' 'DDS I/O knows messages, not the pipeline'
check src/pipeline 'src/sim|src/device/|src/dds/|src/service|tools/|tests/' 'the pipeline runs any backend through src/map/backend.hpp, and needs no DDS'
check src/bag 'src/sim|src/device/|src/dds/|src/service|tools/|tests/' 'bags are read without DDS'
check src/service 'src/sim|src/driver|src/replay|tools/|tests/' 'the service does not know scenes, its test drivers or tools'
check src/driver 'src/pipeline|src/service|src/device/|src/replay|tools/|tests/' 'endpoints that act like ROS 2 nodes know messages and scenes, not the service'
check src/replay 'src/sim|src/pipeline|src/service|src/device/|tools/|tests/' 'playing recordings needs files, bags and DDS, not the service or tools'
check kernels/device 'src/|platform/|tools/|tests/' 'device code depends only on kernels/'
check src/device 'src/sim|src/dds|src/pipeline|src/service|tools/|tests/' 'backends run maps; they know no messages, pipeline or tools'
check src/device/staging 'src/io|src/sim|src/device/opencl|src/device/cuda|src/device/backend|tools/|tests/' 'shared device-backend logic is API-agnostic'
check src/device/opencl 'src/sim|src/device/cuda|src/device/backend|tools/|tests/' 'a backend does not know scenes, tools or the other API'
check src/device/cuda 'src/sim|src/device/opencl|src/device/backend|tools/|tests/' 'a backend does not know scenes, tools or the other API'
check kernels/cuda 'src/|platform/|tools/|tests/' 'CUDA entry points depend only on kernels/'
# The library (raymap::raymap) builds without the service's and the tools' dependencies (libpng
# writes height maps as PNG, src/io/png_writer.cpp): none of
# its code includes DDS, CLI11 or systemd, nor the folders built only with them. It reads rosbag2
# bags (src/bag, src/msgs, src/pipeline: yaml-cpp, lz4, SQLite, Boost.Lockfree) and YAML
# configurations (src/config), so those are allowed (the tools' JSON, nlohmann/, is not); src/sim/scene_file.* is the tools' (scene files).
library_folders="include src/core src/map src/io src/heightmap src/device src/mapper src/record src/msgs src/pipeline src/bag platform"
for folder in $library_folders; do
  hits=$(grep -rnE '#include [<"](CLI/|dds/|systemd/|nlohmann/|src/dds/|src/security/|src/service/|src/sim/scene_file|tools/)' \
    "$folder" --include='*.hpp' --include='*.cpp' --include='*.h' | grep -v '^platform/linux/notify.cpp:' || true)
  if [ -n "$hits" ]; then
    echo "layering: the library ($folder) must build without the service's and tools' dependencies:"
    echo "$hits"
    status=1
  fi
done
# The public headers (include/raymap, installed) include only each other, Eigen and the standard
# library.
hits=$(grep -rnE '#include "(src|platform|kernels|tools|tests)/' include || true)
if [ -n "$hits" ]; then
  echo "layering: a public header includes an internal one:"
  echo "$hits"
  status=1
fi
check src/mapper 'src/sim|src/dds|src/pipeline|src/service|tools/|tests/' 'the facade runs maps and backends only'
# Only kernels/common headers may use C-style guards; everything else is #pragma once.
for f in $(find src platform tools tests include examples -name '*.hpp'); do
  grep -q '^#pragma once' "$f" || { echo "header without #pragma once: $f"; status=1; }
done
# Every source file starts with an SPDX line.
for f in $(find src platform tools tests kernels include examples -name '*.hpp' -o -name '*.cpp' -o -name '*.h' -o -name '*.cl' -o -name '*.cu'); do
  head -1 "$f" | grep -q 'SPDX-License-Identifier' || { echo "missing SPDX line: $f"; status=1; }
done
exit $status
