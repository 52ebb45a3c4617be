#!/usr/bin/env bash
# ThreadSanitizer run of every CPU test: the viewer's threads (render worker, comparison, path
# export, scene loading) and the CPU renderer's OpenMP regions. A Clang build in build-tsan/:
# GCC's OpenMP runtime hides its barriers from TSan, which then reports races that are not
# there; LLVM's libomp announces them through its Archer tool. Any report fails its test.
# Arguments go to ctest (e.g. -R Viewer). Sets up its packages as tools/test.sh does.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export FLASHGS_EXTRA_PACKAGES="clang libomp-dev"
export CC=clang CXX=clang++
export FLASHGS_BUILD_DIR="${FLASHGS_TSAN_BUILD_DIR:-$root/build-tsan}"
export FLASHGS_CMAKE_ARGS="-DFLASHGS_SANITIZE_THREAD=ON -DFLASHGS_WITH_CUDA=OFF"
bash "$root/tools/setup.sh"

archer="$(dirname "$(readlink -f "$(command -v clang)")")/../lib/libarcher.so"
if [ ! -f "$archer" ]; then
  echo "tsan.sh: $archer not found: libomp's Archer tool tells TSan about OpenMP's barriers" >&2
  exit 1
fi
export OMP_TOOL_LIBRARIES="$archer"
# Libraries built without TSan (libomp, Mesa, GLFW) are left out: their own locking is invisible to it.
export TSAN_OPTIONS="ignore_noninstrumented_modules=1 halt_on_error=1 ${TSAN_OPTIONS:-}"
cd "$FLASHGS_BUILD_DIR"
ctest --output-on-failure -j "$(nproc)" "$@"
