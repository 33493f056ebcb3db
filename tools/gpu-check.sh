#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The GPU check on a workstation with an NVIDIA GPU, the Debian packages and nvcc: builds the
# device kit from this checkout and runs it in place (docs/device-kit.md). The same runner as on
# the lent GPU machines, so the two give the same tables.
#   tools/gpu-check.sh [DATA_DIR] [OUT_DIR] [run.sh options, e.g. --only tests --budget 600]
# DATA_DIR: the shared data (default ../shared/data); OUT_DIR: the results (default
# build/gpu-check). Environment: RAYMAP_CUDA_ARCHITECTURES (default "87-real;90"; e.g. 89 for an
# Ada workstation card). Exit status: run.sh's (0 passed, 1 a check failed, 77 no CUDA device).
set -euo pipefail
cd "$(dirname "$0")/.."
data=${1:-../shared/data}
out=${2:-build/gpu-check}
shift $(($# < 2 ? $# : 2))
RAYMAP_KIT_DATA=$data tools/device-kit.sh build/gpu-check-kit
mkdir -p "$out"
OUT=$(cd "$out" && pwd) build/gpu-check-kit/run.sh "$@"
