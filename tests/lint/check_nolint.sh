#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Every clang-tidy suppression names its checks and says why:
#   code;  // NOLINT(check-name[,other-check]): the reason
#   // NOLINTNEXTLINE(check-name): the reason
# and every check it names is one that .clang-tidy enables (a suppression of a check that never
# runs hides nothing and misleads the reader). NOLINTBEGIN/END are not used.
set -euo pipefail
root=${1:-.}
cd "$root"
status=0
# The checks .clang-tidy enables, as a pattern list ("bugprone-*" stays a prefix).
enabled=$(sed -n '/^Checks:/,/^[A-Za-z]/p' .clang-tidy | grep -E '^\s+[a-z*]' | tr -d ' ,' |
  grep -v '^-')
disabled=$(sed -n '/^Checks:/,/^[A-Za-z]/p' .clang-tidy | grep -E '^\s+-[a-z]' | tr -d ' ,' |
  sed 's/^-//')
check_enabled() {
  local check=$1
  while read -r pattern; do
    [ "$pattern" = "$check" ] && return 1
  done <<<"$disabled"
  while read -r pattern; do
    case "$check" in $pattern) return 0 ;; esac
  done <<<"$enabled"
  return 1
}
while IFS= read -r hit; do
  file=${hit%%:*}
  rest=${hit#*:}
  line=${rest%%:*}
  text=${rest#*:}
  if ! grep -qE 'NOLINT(NEXTLINE)?\([A-Za-z0-9.,-]+\): *[^ ]' <<<"$text"; then
    echo "$file:$line: a NOLINT must name its checks and give a reason: NOLINT(check): why" >&2
    status=1
    continue
  fi
  checks=$(sed -E 's/.*NOLINT(NEXTLINE)?\(([A-Za-z0-9.,-]+)\).*/\2/' <<<"$text" | tr ',' ' ')
  for check in $checks; do
    if ! check_enabled "$check"; then
      echo "$file:$line: NOLINT($check): .clang-tidy does not enable $check" >&2
      status=1
    fi
  done
done < <(grep -rnE 'NOLINT' src include platform tools tests examples kernels \
  --include='*.cpp' --include='*.hpp' --include='*.h' --include='*.cu' --include='*.cl' |
  grep -v '^tests/lint/')
# A NOLINTNEXTLINE covers the next line only: that line must be code, not the rest of a comment
# that a formatter wrapped.
while IFS= read -r hit; do
  echo "${hit%%-*}: NOLINTNEXTLINE is followed by a comment line, so it suppresses nothing" >&2
  status=1
done < <(grep -rn -A1 'NOLINTNEXTLINE' src include platform tools tests examples kernels \
  --include='*.cpp' --include='*.hpp' --include='*.h' --include='*.cu' --include='*.cl' |
  grep -v '^tests/lint/' | grep -E '^[^:]+-[0-9]+-[[:space:]]*//')
exit $status
