#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Builds the device kit: one folder that runs every GPU check of raymap on a bare x86-64 machine
# with an NVIDIA GPU and its driver and nothing else (no compiler use, no packages, no network).
#   tools/device-kit.sh OUT_DIR
# OUT_DIR gets:
#   bin/     Release executables (raymap, raymapd, raymap-load, raymap-heightmap-bench,
#            raymap-depth-bench and the CUDA and height-map tests), CUDA machine code for sm_87
#            (Orin) and sm_90 (Hopper) plus sm_90 PTX; their RPATH is ../lib
#   lib/     every shared library they need except the C library and the NVIDIA driver
#            (libstdc++ too, so an older distribution runs them)
#   data/    a subset of ../shared/data ($RAYMAP_KIT_DATA) when present, within the size limit
#   config/  the loopback DDS profile, raymapd's configuration and the scene files
#   run.sh, results.sh, bench-lib.sh, checks/   the runner (docs/device-kit.md)
#   KIT.txt  what was built: commit, date, compiler, architectures, contents
# The kit must stay under 56 MiB (with the working tree, about 6.3 MiB, it travels to the GPU
# machine within the device tool's 64 MiB); the script fails otherwise, and when any executable
# needs a library outside the kit (checked with ldd, the kit's RPATH alone). A failed build leaves no
# OUT_DIR behind; an existing OUT_DIR is replaced only when it is an earlier kit.
# Environment: RAYMAP_KIT_BUILD_DIR (default build/device-kit), RAYMAP_KIT_DATA (default
# ../shared/data), RAYMAP_CUDA_ARCHITECTURES (default "87-real;90").
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -ne 1 ] || [ "${1:0:1}" = "-" ]; then
  echo "usage: tools/device-kit.sh OUT_DIR" >&2
  exit 2
fi
out=$1
build=${RAYMAP_KIT_BUILD_DIR:-build/device-kit}
data=${RAYMAP_KIT_DATA:-../shared/data}
arch=${RAYMAP_CUDA_ARCHITECTURES:-87-real;90}
limit_mib=56
if [ -e "$out" ] && [ ! -f "$out/KIT.txt" ] && [ -n "$(ls -A "$out" 2>/dev/null)" ]; then
  echo "device-kit: $out exists and is not a device kit; not replacing it" >&2
  exit 1
fi

tools/setup-debian.sh
nvcc=$(command -v nvcc || true)
[ -n "$nvcc" ] || [ ! -x /usr/local/cuda/bin/nvcc ] || nvcc=/usr/local/cuda/bin/nvcc
if [ -z "$nvcc" ]; then
  echo "device-kit: needs nvcc (the CUDA toolkit) to build the CUDA backend" >&2
  exit 1
fi

targets=(raymap raymapd raymap-load raymap-heightmap-bench raymap-depth-bench test_unit_cuda
  test_cuda_device test_unit_mapper test_cuda_data test_heightmap)
echo "== configure and build ($build: Release, CUDA architectures $arch, warnings as errors)"
# The Python module is left as the build directory has it (CI's: on, so nothing is rebuilt); the
# kit's targets do not include it, and its position-independent libraries cost nothing measurable
# (docs/benchmarks.md, "Python module").
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DRAYMAP_CUDA=ON -DRAYMAP_WERROR=ON \
  -DRAYMAP_BUILD_TESTS=ON -DRAYMAP_BUILD_BENCHMARKS=ON "-DCMAKE_CUDA_ARCHITECTURES=$arch" >/dev/null
cmake --build "$build" --target "${targets[@]}"

stage=$(mktemp -d "$(dirname "$out")/.device-kit.XXXXXX")
trap 'rm -rf "$stage"' EXIT
chmod 755 "$stage"
mkdir -p "$stage/bin" "$stage/lib" "$stage/data" "$stage/config" "$stage/checks"

echo "== executables"
for t in "${targets[@]}"; do
  f=$(find "$build" -name "$t" -type f -perm -u+x -not -path '*/CMakeFiles/*' | head -1)
  [ -n "$f" ] || { echo "device-kit: $t was not built" >&2; exit 1; }
  cp "$f" "$stage/bin/$t"
  strip --strip-unneeded "$stage/bin/$t"
done

echo "== libraries"
# The C library and its parts (every Linux has them, and they must match the kernel's loader),
# and the NVIDIA driver (the machine's own): everything else goes into the kit.
system_lib() {
  case $1 in
    linux-vdso.so.* | ld-linux-*.so.* | libc.so.* | libm.so.* | libpthread.so.* | libdl.so.* | \
      librt.so.* | libresolv.so.* | libutil.so.* | libanl.so.* | libcuda.so.* | libnvidia-*) return 0 ;;
  esac
  return 1
}
for exe in "$stage"/bin/*; do
  ldd "$exe" | while read -r name arrow path _; do
    [ "$arrow" = "=>" ] || continue
    if [ "$path" = "not" ]; then
      echo "device-kit: $(basename "$exe") needs $name, which is not installed here" >&2
      exit 1
    fi
    system_lib "$name" && continue
    [ -e "$stage/lib/$name" ] || cp -L "$path" "$stage/lib/$name"
  done
done
# DT_RPATH (not RUNPATH): it also applies to the libraries' own dependencies, so the kit's
# libstdc++ is the one every library gets.
for exe in "$stage"/bin/*; do
  patchelf --force-rpath --set-rpath '$ORIGIN/../lib' "$exe"
done
for lib in "$stage"/lib/*; do
  patchelf --force-rpath --set-rpath '$ORIGIN' "$lib"
done

echo "== runner, configuration"
cp tools/device-kit/run.sh tools/device-kit/results.sh tools/bench/bench-lib.sh "$stage/"
cp tools/device-kit/checks/*.sh "$stage/checks/"
chmod +x "$stage/run.sh"
cp config/cyclonedds-loopback.xml config/cpu.yaml "$stage/config/"
mkdir -p "$stage/config/scenes"
cp config/scenes/*.yaml "$stage/config/scenes/"
# MapperBytes (test_unit_mapper) compares its maps with the sums recorded here.
mkdir -p "$stage/tests/golden"
cp tests/golden/library_maps.sha256 "$stage/tests/golden/"

size_mib() { du -sm "$1" | cut -f1; }
echo "== data"
# The Ouster scan first (the benchmark's real data), then the others while they fit, leaving
# 2 MiB of the limit free.
if [ -f "$data/PROVENANCE.md" ]; then
  cp "$data/PROVENANCE.md" "$stage/data/"
  for f in ouster/ouster_os1_lb_n3_raycloud.ply.gz octomap/octomap_scan_raycloud.ply.gz \
    3dtk/3dtk_raycloud.ply.gz; do
    [ -f "$data/$f" ] || continue
    need=$(($(stat -c %s "$data/$f") / 1048576 + 1))
    if [ $(($(size_mib "$stage") + need)) -le $((limit_mib - 2)) ]; then
      mkdir -p "$stage/data/$(dirname "$f")"
      cp "$data/$f" "$stage/data/$f"
    else
      echo "device-kit: $f left out (the kit would pass $((limit_mib - 2)) MiB)"
    fi
  done
else
  echo "device-kit: no shared data at $data: the kit's checks use the synthetic scene only"
fi

echo "== checks"
# Every executable resolves every library inside the kit or in the C library, with nothing on
# the search path but the kit's RPATH.
bad=0
for exe in "$stage"/bin/*; do
  while read -r name arrow path _; do
    [ "$arrow" = "=>" ] || continue
    system_lib "$name" && continue
    case $(readlink -f "$path") in
      "$(readlink -f "$stage")"/lib/*) ;;
      *) echo "device-kit: $(basename "$exe") finds $name at $path, outside the kit" >&2; bad=1 ;;
    esac
  done < <(env -u LD_LIBRARY_PATH ldd "$exe")
done
[ "$bad" = 0 ] || exit 1
"$stage/bin/raymap" --version >/dev/null
total=$(size_mib "$stage")
if [ "$total" -ge "$limit_mib" ]; then
  echo "device-kit: the kit is $total MiB, over the $limit_mib MiB limit" >&2
  du -sm "$stage"/* >&2
  exit 1
fi
{
  echo "raymap device kit (docs/device-kit.md): run ./run.sh on the GPU machine"
  echo "commit: $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- . 2>/dev/null || echo '+changes')"
  echo "built: $(date -u +%Y-%m-%dT%H:%M:%SZ)"
  echo "nvcc: $("$nvcc" --version | sed -n 's/.*release \([0-9.]*\).*/\1/p')"
  echo "cuda_architectures: $arch"
  echo "compiler: $(c++ --version | head -1)"
  echo "size_mib: $total"
  echo "executables: $(cd "$stage/bin" && echo *)"
  echo "libraries: $(cd "$stage/lib" && echo *)"
  echo "data: $(cd "$stage/data" && find . -name '*.gz' | sed 's|^\./||' | sort | tr '\n' ' ')"
} >"$stage/KIT.txt"

rm -rf "$out"
mv "$stage" "$out"
trap - EXIT
echo "device kit: $out ($total MiB)"
