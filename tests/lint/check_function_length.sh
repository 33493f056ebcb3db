#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Functions in src/, platform/ and tools/ stay within 80 lines (issue 55: long functions are split
# into named steps). Universal Ctags finds each function's first and last line. The functions
# that were longer when the rule came are listed in tests/lint/long_functions.txt with their
# length: such a function may shrink but not grow, a function not listed may not pass 80 lines,
# and a listed one that is now short (or gone) must leave the list, so the list only shrinks.
#   tests/lint/check_function_length.sh [ROOT]            check
#   tests/lint/check_function_length.sh [ROOT] --update   rewrite the list (only to shrink it)
set -euo pipefail
root=${1:-.}
mode=${2:-check}
cd "$root"
limit=80
list=tests/lint/long_functions.txt
if ! command -v ctags >/dev/null || ! ctags --version | grep -q Universal; then
  echo "check_function_length: skipped: needs Universal Ctags (apt-get install universal-ctags)" >&2
  exit 77
fi
# "path name lines" of every function over the limit (lambdas are part of their function; the
# longest of overloads sharing a name counts).
measured=$(find src platform tools -type f \( -name '*.cpp' -o -name '*.hpp' \) | sort |
  ctags -L - --languages=C++ --c++-kinds=f --fields=+ne -f - |
  awk -F'\t' -v limit="$limit" '
    $1 !~ /^__anon/ {
      line = 0; end = 0
      for (i = 4; i <= NF; i++) {
        if ($i ~ /^line:/) line = substr($i, 6) + 0
        if ($i ~ /^end:/) end = substr($i, 5) + 0
      }
      if (line > 0 && end >= line) {
        n = end - line + 1
        key = $2 " " $1
        if (n > limit && n > longest[key]) longest[key] = n
      }
    }
    END { for (k in longest) print k, longest[k] }' | sort)
if [ "$mode" = "--update" ]; then
  {
    echo "# Functions over $limit lines when the rule came (tests/lint/check_function_length.sh):"
    echo "# path function lines. Split them into named steps; this list may only shrink."
    echo "$measured"
  } > "$list"
  echo "wrote $list ($(echo "$measured" | grep -c . || true) functions)"
  exit 0
fi
status=0
declare -A allowed
while read -r path name lines; do
  [ -z "$path" ] || [ "${path:0:1}" = "#" ] && continue
  allowed["$path $name"]=$lines
done < "$list"
declare -A seen
while read -r path name lines; do
  [ -z "$path" ] && continue
  key="$path $name"
  seen["$key"]=1
  if [ -z "${allowed[$key]:-}" ]; then
    echo "function length: $path: $name is $lines lines (at most $limit): split it into named steps"
    status=1
  elif [ "$lines" -gt "${allowed[$key]}" ]; then
    echo "function length: $path: $name grew to $lines lines (listed at ${allowed[$key]}, limit $limit)"
    status=1
  fi
done <<< "$measured"
for key in "${!allowed[@]}"; do
  if [ -z "${seen[$key]:-}" ]; then
    echo "function length: $key is now within $limit lines (or gone): remove it from $list"
    status=1
  fi
done
exit $status
