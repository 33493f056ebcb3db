#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Lints systemd/raymapd.service: `systemd-analyze verify` must print nothing (it exits 0 even on
# parse errors, so any output fails), and `systemd-analyze security --offline` must rate the
# exposure at most 2.0. Exits 77 (skipped) where systemd-analyze is absent.
set -euo pipefail
root=${1:-.}
unit="$root/systemd/raymapd.service"
max_exposure=2.0
if ! command -v systemd-analyze >/dev/null 2>&1; then
  echo "systemd-analyze not found: skipped"
  exit 77
fi
[ -f "$unit" ] || { echo "missing $unit"; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# verify insists that ExecStart's binary exists and is executable: lint a copy that runs
# /bin/true with the same arguments. The copy keeps the unit's name (security reports it).
sed -E 's|^(ExecStart=[-@:+!]*)[^ ]+|\1/bin/true|' "$unit" > "$work/raymapd.service"
grep -q '^ExecStart=/bin/true' "$work/raymapd.service" || { echo "no ExecStart= in $unit"; exit 1; }
status=0
if ! out=$(cd "$work" && systemd-analyze verify --man=no ./raymapd.service 2>&1) || [ -n "$out" ]; then
  echo "systemd-analyze verify reported:"
  echo "$out"
  status=1
fi
# --threshold=20 so the command itself does not fail; the limit is checked on the number.
report=$(cd "$work" && systemd-analyze security --offline=true --threshold=20 ./raymapd.service 2>&1) || true
line=$(printf '%s\n' "$report" | grep 'Overall exposure level' || true)
exposure=$(printf '%s\n' "$line" | sed -nE 's/.*: ([0-9]+(\.[0-9]+)?).*/\1/p')
if [ -z "$exposure" ]; then
  echo "no exposure level in the output of systemd-analyze security:"
  echo "$report"
  exit 1
fi
if awk -v e="$exposure" -v m="$max_exposure" 'BEGIN { exit !(e > m) }'; then
  echo "exposure $exposure exceeds $max_exposure:"
  printf '%s\n' "$report" | grep -v '✓' || true
  status=1
else
  echo "$line"
fi
exit $status
