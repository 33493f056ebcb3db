#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# clang-tidy really enables every check group .clang-tidy means to (a typo in the file can
# silently disable a whole group), and the settings that make its findings errors are there.
# Exit 77 (skipped) where clang-tidy is not installed.
set -euo pipefail
root=${1:-.}
cd "$root"
tidy=$(command -v clang-tidy-14 || command -v clang-tidy || true)
if [ -z "$tidy" ]; then
  echo "clang-tidy is not installed: skipped"
  exit 77
fi
checks=$("$tidy" --list-checks 2>/dev/null | sed -n 's/^ \+\([a-z].*\)$/\1/p')
status=0
expect() {  # expect GROUP-PREFIX MINIMUM-COUNT
  local n
  n=$(grep -c "^$1" <<<"$checks" || true)
  if [ "$n" -lt "$2" ]; then
    echo "clang-tidy enables $n checks starting with '$1' (expected at least $2)" >&2
    status=1
  fi
}
expect bugprone- 40
expect concurrency- 2
expect performance- 10
expect clang-analyzer- 50
expect cppcoreguidelines- 9
expect modernize- 10
expect google-explicit-constructor 1
expect readability-identifier-naming 1
grep -q "^WarningsAsErrors: '\*'" .clang-tidy || { echo ".clang-tidy: WarningsAsErrors is not '*'" >&2; status=1; }
exit $status
