#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Fails when a C/C++ source is not formatted with the repository's .clang-format.
set -euo pipefail
cd "$(dirname "$0")/.."
files=$(git ls-files '*.cpp' '*.hpp' '*.h' '*.cu' '*.cuh' '*.cl')
clang-format --dry-run --Werror $files
