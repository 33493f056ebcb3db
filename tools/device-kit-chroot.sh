#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Proves that the device kit runs on a bare machine: a minimal Debian 12 root file system
# (debootstrap --variant=minbase from Debian's archive: none of raymap's packages, no compiler),
# the kit copied in, and its run.sh run inside with chroot. There is no GPU here, so run.sh must
# say "no CUDA device" on its first line, run and pass the CPU parts, and exit 77.
#   tools/device-kit-chroot.sh KIT_DIR [RESULTS_DIR]
# RESULTS_DIR (default build/kit-chroot-results) receives run.sh's results folder.
# RAYMAP_KIT_SECTIONS (e.g. devices,tests,raymapd) runs only those sections of run.sh (--only);
# unset, all of them.
# The root file system is cached as a tarball in $RAYMAP_CHROOT_CACHE (default ~/.cache/raymap)
# and unpacked fresh for each run, so no run sees another's leftovers. Needs root (chroot, mount)
# and debootstrap (installed with apt-get when missing); $RAYMAP_DEBIAN_MIRROR overrides
# http://deb.debian.org/debian. Exit status: 0 when the kit behaved as above, 1 otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 1 ] || [ $# -gt 2 ] || [ ! -x "$1/run.sh" ]; then
  echo "usage: tools/device-kit-chroot.sh KIT_DIR [RESULTS_DIR]  (KIT_DIR from tools/device-kit.sh)" >&2
  exit 2
fi
kit=$(cd "$1" && pwd)
results=${2:-build/kit-chroot-results}
if [ "$(id -u)" -ne 0 ]; then
  echo "device-kit-chroot: needs root (chroot and mount)" >&2
  exit 1
fi
# shellcheck source=tools/debian-chroot.sh
. tools/debian-chroot.sh
debian_chroot_create
root=$chroot_root
# What makes the machine bare: none of the libraries the kit carries is installed.
for lib in libyaml-cpp.so.0.7 libddsc.so.0debian libOpenCL.so.1 libbenchmark.so.1debian libpng16.so.16; do
  if [ -n "$(find "$root/usr/lib" "$root/lib" -name "$lib" 2>/dev/null | head -1)" ]; then
    echo "device-kit-chroot: the root file system has $lib: not a bare machine" >&2
    exit 1
  fi
done
cp -a "$kit" "$root/kit"

echo "== run.sh inside the minimal Debian 12 root file system (no GPU: CUDA parts skip)"
start=$SECONDS
set +e
timeout 600 chroot "$root" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin HOME=/root \
  OUT=/results /kit/run.sh ${RAYMAP_KIT_SECTIONS:+--only "$RAYMAP_KIT_SECTIONS"} 2>&1 |
  tee "$root/run-output.txt"
rc=${PIPESTATUS[0]}
set -e
seconds=$((SECONDS - start))
rm -rf "$results"
mkdir -p "$results"
cp -a "$root/results/." "$results/" 2>/dev/null || true
cp "$root/run-output.txt" "$results/"

first=$(grep -m1 '^\[' "$root/run-output.txt" || true)
status=0
if [[ $first != *"no CUDA device"* ]]; then
  echo "device-kit-chroot: run.sh's first line does not say 'no CUDA device': $first" >&2
  status=1
fi
if [ "$rc" != 77 ]; then
  echo "device-kit-chroot: run.sh exited $rc, not 77 (no CUDA device, CPU parts passed)" >&2
  status=1
fi
echo "device-kit-chroot: run.sh exited $rc after $seconds s; results in $results"
exit $status
