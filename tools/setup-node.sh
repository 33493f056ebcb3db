#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Installs the Node.js rosbag test harness (tests/rosbag/node): Debian's nodejs, npm and python3
# when missing, then the npm packages pinned by its package-lock.json; a no-op when up to date.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
harness="$root/tests/rosbag/node"

missing=()
command -v node >/dev/null 2>&1 || missing+=(nodejs)
command -v npm >/dev/null 2>&1 || missing+=(npm)
command -v python3 >/dev/null 2>&1 || missing+=(python3)  # write_db3.py writes the .db3 fixtures
if [ ${#missing[@]} -ne 0 ]; then
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    sudo="sudo"
  fi
  echo "setup-node: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}" >/dev/null
fi

# node_modules is current when it was installed from this very lock file and package.json.
stamp="$harness/node_modules/.raymap-setup-stamp"
want="$(cat "$harness/package-lock.json" "$harness/package.json" | sha256sum | cut -d' ' -f1)"
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  exit 0
fi
echo "setup-node: npm ci in tests/rosbag/node"
npm ci --prefix "$harness" --no-audit --no-fund
echo "$want" >"$stamp"
