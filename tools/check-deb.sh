#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Builds the Debian package from a Release build directory (cpack -G DEB) and proves it on a bare
# Debian 12: a fresh minimal root file system (tools/debian-chroot.sh) where apt-get installs the
# package and the Depends: dpkg-shlibdeps computed; there `raymap --version` and
# `raymapd --check-config /etc/raymapd/raymapd.yaml` must run, the unit, headers and CMake package
# must be in place, and removing and purging the package must take its files away. A package
# for another architecture (an arm64 cross build, docs/arm64.md) is proven the same way on a bare
# Debian 12 of its own architecture, its programs run under qemu-user-static.
#   tools/check-deb.sh BUILD_DIR      (needs root, network access to the Debian archive)
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -ne 1 ] || [ ! -f "$1/CPackConfig.cmake" ]; then
  echo "usage: tools/check-deb.sh BUILD_DIR  (a configured and built raymap build directory)" >&2
  exit 2
fi
build=$(cd "$1" && pwd)
if [ "$(id -u)" -ne 0 ]; then
  echo "check-deb: needs root (chroot and mount)" >&2
  exit 1
fi

# A cross build's Depends: dpkg-shlibdeps names the packages of the libraries the programs link
# from the build host's dpkg database, so the arm64 builds of those libraries are installed here
# beside the host's own (Debian multiarch; nothing of the host's changes).
if grep -q '^RAYMAP_ARM64_ROOT:' "$build/CMakeCache.txt"; then
  arm64_runtime=(libc6 libstdc++6 libgcc-s1 libssl3 libddsc0debian liblz4-1 libpng16-16
    libsqlite3-0 libyaml-cpp0.7 zlib1g libzstd1)
  dpkg --add-architecture arm64
  if ! dpkg-query -W "${arm64_runtime[@]/%/:arm64}" >/dev/null 2>&1; then
    echo "== the arm64 runtime libraries for dpkg-shlibdeps (multiarch)"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${arm64_runtime[@]/%/:arm64}" >/dev/null
  fi
fi

echo "== cpack -G DEB in $build"
rm -f "$build"/raymap_*.deb
(cd "$build" && cpack -G DEB >"$build/cpack.log" 2>&1) || { tail -30 "$build/cpack.log" >&2; exit 1; }
deb=$(ls "$build"/raymap_*.deb)
arch=$(dpkg-deb -f "$deb" Architecture)
echo "package: $deb ($(du -h "$deb" | cut -f1), $arch)"
depends=$(dpkg-deb -f "$deb" Depends)
echo "Depends: $depends"
for needed in adduser libddsc libyaml-cpp libzstd1 libpng16-16 libsqlite3 libstdc++6 libc6; do
  if [[ $depends != *"$needed"* ]]; then
    echo "check-deb: Depends lacks $needed (dpkg-shlibdeps did not run?)" >&2
    exit 1
  fi
done
contents=$(dpkg-deb -c "$deb")
for path in ./usr/bin/raymap ./usr/bin/raymapd ./usr/lib/systemd/system/raymapd.service \
  ./etc/raymapd/raymapd.yaml ./etc/raymapd/cyclonedds.xml ./usr/include/raymap/mapper.hpp \
  ./usr/include/raymap/version.hpp ./usr/lib/cmake/raymap/raymapConfig.cmake \
  ./usr/share/raymap/cyclonedds-realtime-receive.xml ./usr/bin/raymap-load \
  ./usr/share/raymap/scenes/yard.yaml; do
  grep -q " $path\$" <<<"$contents" || { echo "check-deb: the package lacks $path" >&2; exit 1; }
done

# shellcheck source=tools/debian-chroot.sh
. tools/debian-chroot.sh
if [ "$arch" = "$(dpkg --print-architecture)" ]; then
  debian_chroot_create
elif [ "$arch" = arm64 ]; then
  debian_chroot_create arm64
else
  echo "check-deb: no bare Debian 12 for a $arch package here (amd64 and arm64 only)" >&2
  exit 1
fi
root=$chroot_root
cp /etc/resolv.conf "$root/etc/resolv.conf"
cp "$deb" "$root/tmp/raymap.deb"
in_root() {
  chroot "$root" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin HOME=/root \
    DEBIAN_FRONTEND=noninteractive "$@"
}
echo "== apt-get install ./raymap.deb on a minimal Debian 12 ($arch)"
in_root apt-get update -qq
in_root apt-get install -y -qq --no-install-recommends /tmp/raymap.deb >"$build/deb-install.log" 2>&1 ||
  { tail -30 "$build/deb-install.log" >&2; exit 1; }
in_root raymap --version
in_root raymapd --check-config /etc/raymapd/raymapd.yaml
in_root raymap-load --help >/dev/null
if [ -d "$root/usr/lib/python3/dist-packages/raymap" ]; then
  # The Python module with Debian's python3 and NumPy (Recommends:), mapping a ring of points
  # (-B: no __pycache__ left for the removal below to find).
  in_root apt-get install -y -qq --no-install-recommends python3-numpy >"$build/deb-python.log" 2>&1 ||
    { tail -30 "$build/deb-python.log" >&2; exit 1; }
  in_root python3 -B -c 'import numpy as np, raymap
a = np.linspace(0, 2 * np.pi, 360, endpoint=False)
m = raymap.Mapper()
m.integrate(np.stack([5 * np.cos(a), 5 * np.sin(a), 0 * a], 1), np.eye(4))
m.flush()
assert m.counts()["voxels_occupied"] > 100, m.counts()
print("import raymap", raymap.__version__, m.counts())'
fi
grep -q '^ExecStart=/usr/bin/raymapd --config /etc/raymapd/raymapd.yaml' \
  "$root/usr/lib/systemd/system/raymapd.service" ||
  { echo "check-deb: the installed unit does not start /usr/bin/raymapd" >&2; exit 1; }
in_root getent passwd raymapd >/dev/null || { echo "check-deb: no raymapd user" >&2; exit 1; }

echo "== apt-get remove, then purge"
in_root apt-get remove -y -qq raymap >/dev/null
for gone in usr/bin/raymap usr/bin/raymapd usr/include/raymap/mapper.hpp \
  usr/lib/python3/dist-packages/raymap; do
  [ ! -e "$root/$gone" ] || { echo "check-deb: /$gone survived removal" >&2; exit 1; }
done
[ -f "$root/etc/raymapd/raymapd.yaml" ] ||
  { echo "check-deb: removal (not purge) deleted the configuration" >&2; exit 1; }
in_root apt-get purge -y -qq raymap >/dev/null
[ ! -e "$root/etc/raymapd/raymapd.yaml" ] ||
  { echo "check-deb: purge left /etc/raymapd/raymapd.yaml" >&2; exit 1; }
echo "check-deb: $(basename "$deb") installs, runs, removes and purges on a bare Debian 12"
