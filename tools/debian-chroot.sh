#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Sourced by the scripts that test raymap on a bare Debian 12 (tools/device-kit-chroot.sh,
# tools/check-deb.sh): debian_chroot_create unpacks a fresh minimal root file system
# (debootstrap --variant=minbase bookworm, cached as a tarball in $RAYMAP_CHROOT_CACHE, default
# ~/.cache/raymap; $RAYMAP_DEBIAN_MIRROR overrides http://deb.debian.org/debian) into a new
# directory, sets $chroot_root to it and arranges for it to be unmounted and removed on exit.
# `debian_chroot_create arm64` makes an arm64 one instead (tools/arm64-root.sh --bare: its
# programs run under qemu-user-static through binfmt_misc). Needs root (chroot, mount) and
# debootstrap (installed with apt-get when missing).

debian_chroot_cleanup() {
  [ -n "${chroot_root:-}" ] || return 0
  umount "$chroot_root/dev/pts" 2>/dev/null || true
  umount "$chroot_root/dev/shm" 2>/dev/null || true
  umount "$chroot_root/proc" 2>/dev/null || true
  # Only once nothing is mounted inside is the tree removed.
  if ! grep -q " $chroot_root/" /proc/mounts; then
    rm -rf "$chroot_root"
  fi
}

debian_chroot_create() {
  local arch=${1:-}
  local cache_dir=${RAYMAP_CHROOT_CACHE:-$HOME/.cache/raymap}
  local cache=$cache_dir/debian12-minbase.tar.gz
  local mirror=${RAYMAP_DEBIAN_MIRROR:-http://deb.debian.org/debian}
  if [ "$arch" != arm64 ] && [ ! -f "$cache" ]; then
    if ! command -v debootstrap >/dev/null; then
      apt-get update -qq
      DEBIAN_FRONTEND=noninteractive apt-get install -y -qq debootstrap >/dev/null
    fi
    echo "== debootstrap --variant=minbase bookworm (cached in $cache)"
    mkdir -p "$cache_dir"
    local fresh
    fresh=$(mktemp -d /var/tmp/raymap-debootstrap.XXXXXX)
    if ! debootstrap --variant=minbase bookworm "$fresh" "$mirror" >"$fresh.log" 2>&1; then
      tail -20 "$fresh.log" >&2
      rm -rf "$fresh" "$fresh.log"
      return 1
    fi
    rm -f "$fresh.log"
    tar -C "$fresh" -czf "$cache.part" .
    mv "$cache.part" "$cache"
    rm -rf "$fresh"
  fi
  chroot_root=$(mktemp -d /var/tmp/raymap-chroot.XXXXXX)
  trap debian_chroot_cleanup EXIT
  if [ "$arch" = arm64 ]; then
    "$(dirname "${BASH_SOURCE[0]}")/arm64-root.sh" --bare "$chroot_root" >/dev/null
  else
    tar -C "$chroot_root" -xzf "$cache"
  fi
  mount -t proc proc "$chroot_root/proc"
  mkdir -p "$chroot_root/dev/shm"
  mount -t tmpfs -o size=256m tmpfs "$chroot_root/dev/shm"
  # apt-get logs through a pseudo-terminal.
  mkdir -p "$chroot_root/dev/pts"
  mount -t devpts -o newinstance,ptmxmode=0666 devpts "$chroot_root/dev/pts" 2>/dev/null || true
}
