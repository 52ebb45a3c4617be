#!/usr/bin/env bash
# Fills .deps (git-ignored, carried to the device machine: `run` with carry [".deps"]) with what
# gpu_check.sh reads there: the real scenes xz-compressed (../shared/scenes, 32 MB), the
# header-only libraries and GoogleTest's sources (for a build on the device when the carried
# binaries do not match the tree), Debian's Highway, and the binaries of prebuild.sh.
# Usage: bash tools/device/make_deps.sh [SCENE...]   (default: the five scenes the GPU tests use)
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
deps=$root/.deps
scenes=$root/../shared/scenes
[ -d "$scenes" ] || { echo "make_deps: $scenes is absent" >&2; exit 1; }
names=("$@")
[ ${#names[@]} -gt 0 ] || names=(pc_biker pc_playbot pc_guitar v3dg_donut kacytran_try)

mkdir -p "$deps/include" "$deps/scenes" "$deps/sysroot/usr/include" "$deps/sysroot/usr/lib/x86_64-linux-gnu/cmake"
for name in "${names[@]}"; do
  mkdir -p "$deps/scenes/$name"
  cp "$scenes/$name/cameras.json" "$deps/scenes/$name/"
  # Compressed once: the archive is kept while the scene file is older than it.
  out=$deps/scenes/$name/point_cloud.ply.xz
  [ "$out" -nt "$scenes/$name/point_cloud.ply" ] || xz -T2 -6 -c "$scenes/$name/point_cloud.ply" > "$out"
done
cp -r /usr/include/glm /usr/include/CLI /usr/include/nlohmann "$deps/include/"
rm -rf "$deps/googletest" && cp -r /usr/src/googletest "$deps/googletest"
cp -r /usr/include/hwy "$deps/sysroot/usr/include/"
cp -a /usr/lib/x86_64-linux-gnu/libhwy*.so* "$deps/sysroot/usr/lib/x86_64-linux-gnu/"
cp -r /usr/lib/x86_64-linux-gnu/cmake/hwy "$deps/sysroot/usr/lib/x86_64-linux-gnu/cmake/"
bash "$root/tools/device/prebuild.sh"
du -sh "$deps"
