#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Makes an arm64 Debian 12 root in DIR for the arm64 cross build and its emulated tests:
#
#   tools/arm64-root.sh DIR            the project's build and test dependencies, unpacked
#                                      (mmdebstrap --variant=extract: no package scripts run, so
#                                      nothing is emulated): the cross build's system root and the
#                                      library prefix qemu runs the tests with
#   tools/arm64-root.sh --library DIR  the same for the map library alone (no Cyclone DDS, CLI11,
#                                      libsystemd, OpenSSL, OctoMap): CI's arm64 stage
#   tools/arm64-root.sh --bare DIR     a bare minimal Debian 12 (--variant=minbase, its package
#                                      scripts run under qemu)
#   tools/arm64-root.sh --host-tools   only what the host needs (below)
#
# Each root is cached as a tarball in $RAYMAP_CHROOT_CACHE (default ~/.cache/raymap) and unpacked
# from there afterwards; $RAYMAP_DEBIAN_MIRROR overrides http://deb.debian.org/debian. Installs
# what it needs on the host (mmdebstrap, qemu-user-static, binfmt-support, the cross compiler)
# and registers qemu's aarch64 handler with the kernel (binfmt_misc), so that an arm64 program
# the tests start runs like a native one. Needs root.
set -euo pipefail

variant=extract
list=full
case "${1:-}" in
  --bare) variant=minbase; shift ;;
  --library) list=library; shift ;;
  --host-tools) list=none; shift ;;
esac
if [ "$list" = none ]; then
  [ $# -eq 0 ] || { echo "usage: $0 --host-tools" >&2; exit 2; }
else
  [ $# -eq 1 ] || { echo "usage: $0 [--library|--bare] DIR" >&2; exit 2; }
  dir=$1
fi

# The arm64 packages of tools/setup-debian.sh's list that the cross build links or its tests run
# against (not the host's tools: cmake, idlc, node, clang …; not OpenCL, CUDA or Python).
library_packages=(
  libc6-dev libstdc++-12-dev zlib1g-dev libzstd-dev libpng-dev libeigen3-dev libyaml-cpp-dev
  nlohmann-json3-dev libgtest-dev libgmock-dev libboost-dev liblz4-dev libsqlite3-dev
)
dev_packages=("${library_packages[@]}" libcli11-dev liboctomap-dev cyclonedds-dev libsystemd-dev
  libssl-dev)
if [ "$list" = library ]; then
  dev_packages=("${library_packages[@]}")
fi

host_tools=(mmdebstrap qemu-user-static binfmt-support crossbuild-essential-arm64)
missing=()
for p in "${host_tools[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "arm64-root: installing ${missing[*]}"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
fi

# qemu's handler in the kernel: an arm64 executable started by a test (the command line, raymapd)
# runs under qemu-aarch64 like a native program; QEMU_LD_PREFIX points it at the root. Where the
# kernel's binfmt_misc cannot be reached (a container without it) only that is lost: test
# programs themselves run through ctest's emulator; tools/check-arm64.sh X86_BUILD says so.
if [ ! -e /proc/sys/fs/binfmt_misc/qemu-aarch64 ]; then
  if ! mountpoint -q /proc/sys/fs/binfmt_misc; then
    mount -t binfmt_misc binfmt_misc /proc/sys/fs/binfmt_misc 2>/dev/null || true
  fi
  update-binfmts --enable qemu-aarch64 2>/dev/null || update-binfmts --import qemu-aarch64 \
    2>/dev/null || true
fi
if [ ! -e /proc/sys/fs/binfmt_misc/qemu-aarch64 ]; then
  echo "arm64-root: warning: qemu-aarch64 is not registered with binfmt_misc: arm64 programs" \
    "started by other programs will not run" >&2
fi

if [ "$list" = none ]; then
  exit 0
fi

cache_dir=${RAYMAP_CHROOT_CACHE:-$HOME/.cache/raymap}
mirror=${RAYMAP_DEBIAN_MIRROR:-http://deb.debian.org/debian}
if [ "$variant" = extract ]; then
  # The list is part of the name: a changed list makes a new root.
  tag=$(printf '%s\n' "${dev_packages[@]}" | sha256sum | cut -c1-12)
  cache=$cache_dir/debian12-arm64-dev-$tag.tar.gz
  include=$(IFS=,; echo "${dev_packages[*]}")
else
  cache=$cache_dir/debian12-arm64-minbase.tar.gz
  include=""
fi
if [ ! -f "$cache" ]; then
  echo "== mmdebstrap --variant=$variant --architectures=arm64 bookworm (cached in $cache)"
  mkdir -p "$cache_dir"
  log=$(mktemp /var/tmp/raymap-mmdebstrap.XXXXXX)
  part=$cache_dir/.part-$$.tar.gz  # mmdebstrap writes a tarball for a name ending in .tar.gz
  if ! mmdebstrap --variant="$variant" --architectures=arm64 ${include:+--include="$include"} \
      bookworm "$part" "$mirror" >"$log" 2>&1; then
    tail -20 "$log" >&2
    rm -f "$part" "$log"
    exit 1
  fi
  rm -f "$log"
  mv "$part" "$cache"
fi
rm -rf "$dir"
mkdir -p "$dir"
tar -C "$dir" -xzf "$cache"
# Links to absolute paths (libz.so -> /lib/aarch64-linux-gnu/libz.so.1.2.13) would lead into the
# host's file system when the root is a cross build's system root: made relative, inside the root.
root=$(cd "$dir" && pwd)
find "$root" -path "$root/dev" -prune -o -type l -lname '/*' -print0 | while IFS= read -r -d '' link; do
  target=$(readlink "$link")
  ln -sfn "$(realpath -m --relative-to="$(dirname "$link")" "$root$target")" "$link"
done
echo "arm64-root: $dir ($variant)"
