#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# clang-tidy over raymap with the checks in .clang-tidy (docs/static-analysis.md).
#   tools/clang-tidy.sh [--build DIR] --ci       every file of the clean folders: zero findings
#   tools/clang-tidy.sh [--build DIR] --all      the whole tree: findings per folder, compared
#                                                with the ratchet tools/clang-tidy-baseline.txt
#   tools/clang-tidy.sh [--build DIR] --all --update-baseline   lower the ratchet after fixes
#   tools/clang-tidy.sh [--build DIR] FILE...    these files (findings in any project header)
# DIR is a Clang build with compile_commands.json (default build/asan, the asan preset: CI builds
# it first). Clean folders (tools/clang-tidy-clean.txt) must stay at zero findings, their own
# headers included; the ratchet's counts may only fall. Runs two files at a time.
set -euo pipefail
cd "$(dirname "$0")/.."
build=build/asan
mode=files
update=0
files=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build=$2; shift 2 ;;
    --ci) mode=ci; shift ;;
    --all) mode=all; shift ;;
    --update-baseline) update=1; shift ;;
    -*) echo "clang-tidy.sh: unknown option $1" >&2; exit 2 ;;
    *) files+=("$1"); shift ;;
  esac
done
db="$build/compile_commands.json"
if [ ! -f "$db" ]; then
  echo "clang-tidy.sh: no $db: build a Clang preset first (cmake --preset asan && cmake --build --preset asan)" >&2
  exit 2
fi
tidy=$(command -v clang-tidy-14 || command -v clang-tidy || true)
if [ -z "$tidy" ]; then
  echo "clang-tidy.sh: clang-tidy is not installed (apt-get install clang-tidy)" >&2
  exit 2
fi
# The project's own translation units in the compile database (not idlc's or CMake's output).
project_files() {
  python3 -c '
import json, os, sys
root = os.getcwd() + "/"
seen = set()
for entry in json.load(open(sys.argv[1])):
    path = os.path.normpath(os.path.join(entry["directory"], entry["file"]))
    if path.startswith(root) and "/build/" not in path[len(root) - 1:] and path.endswith(".cpp"):
        rel = path[len(root):]
        if rel not in seen:
            seen.add(rel)
            print(rel)
' "$db" | sort
}
clean_folders=$(grep -v '^\s*#' tools/clang-tidy-clean.txt | sed '/^\s*$/d')
# Runs clang-tidy on the files on stdin, two at a time; prints every finding as
# "path:line:col: message [check]" (paths relative to the source tree), sorted and unique.
run_tidy() {
  local header_filter=$1
  xargs -r -P 2 -n 1 "$tidy" -p "$build" --quiet --header-filter="$header_filter" 2>/dev/null |
    grep -E '^/.*:[0-9]+:[0-9]+: (warning|error): ' | sed "s|^$PWD/||" | sort -u || true
}
case "$mode" in
  ci)
    regex="^$PWD/($(echo "$clean_folders" | paste -sd'|'))/"
    list=$(project_files | grep -E "^($(echo "$clean_folders" | paste -sd'|'))/" || true)
    echo "clang-tidy: $(echo "$list" | wc -l) files of the clean folders: $(echo $clean_folders)"
    findings=$(echo "$list" | run_tidy "$regex")
    ;;
  all)
    # A unity build's database names its generated unity files, not the sources they include:
    # the test programs and the CLI would be left out without a word.
    if grep -q '/Unity/unity_' "$db"; then
      echo "clang-tidy.sh: $build is a unity build; --all needs one without (docs/static-analysis.md):" >&2
      echo "  cmake --preset asan -B build/tidy -DRAYMAP_UNITY_BUILD=OFF && cmake --build build/tidy --target raymap_dds_types" >&2
      echo "  tools/clang-tidy.sh --build build/tidy --all" >&2
      exit 2
    fi
    list=$(project_files)
    echo "clang-tidy: the whole tree, $(echo "$list" | wc -l) files"
    findings=$(echo "$list" | run_tidy "^$PWD/(src|include|platform|tools|tests|examples)/")
    ;;
  files)
    [ ${#files[@]} -gt 0 ] || { echo "usage: see the top of tools/clang-tidy.sh" >&2; exit 2; }
    findings=$(printf '%s\n' "${files[@]}" | run_tidy "^$PWD/(src|include|platform|tools|tests|examples)/")
    ;;
esac
if [ -n "$findings" ]; then
  echo "$findings"
  echo "== findings per check"
  echo "$findings" | sed -n 's/.*\[\([A-Za-z0-9.-]*\).*\]$/\1/p' | sort | uniq -c | sort -rn
fi
count=$(echo -n "$findings" | grep -c . || true)
if [ "$mode" = all ]; then
  # Findings per top-level folder (two levels under src/), against the ratchet.
  counts=$(echo -n "$findings" | sed -E 's|^((src\|tests)/[^/]+\|[^/]+)/.*|\1|' | sort | uniq -c |
    awk '{print $2, $1}')
  status=0
  while read -r folder n; do
    [ -n "$folder" ] || continue
    allowed=$(awk -v f="$folder" '$1 == f {print $2}' tools/clang-tidy-baseline.txt)
    if [ -z "$allowed" ] || [ "$n" -gt "$allowed" ]; then
      echo "clang-tidy: $folder has $n findings, the ratchet allows ${allowed:-0}" >&2
      status=1
    fi
  done <<<"$counts"
  if [ "$update" -eq 1 ]; then
    { echo "# clang-tidy findings per folder (tools/clang-tidy.sh --all); may only fall."
      echo "$counts"; } >tools/clang-tidy-baseline.txt
    echo "clang-tidy: ratchet updated: $count findings"
    exit 0
  fi
  echo "clang-tidy: $count findings"
  exit $status
fi
if [ "$count" -gt 0 ]; then
  echo "clang-tidy: $count findings" >&2
  exit 1
fi
echo "clang-tidy: no findings"
