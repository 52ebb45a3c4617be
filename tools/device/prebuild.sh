#!/usr/bin/env bash
# Builds the device machine's binaries here (sm_90, without OpenImageIO, which the device lacks)
# into .deps/bin, xz-compressed, with the libraries they need beyond the C library in .deps/lib
# and the sources' stamp (source_stamp.sh). `gpu_check.sh setup` then runs them instead of
# building, when the stamp matches the tree it runs on and they start there.
# Run it in the checkout sent to the GPU machine (not a git worktree elsewhere): the tests
# keep the source tree's absolute paths (the demo scene, ../shared/scenes), and the device
# machine has the tree at the same path; binaries built in /tmp/wt failed every scene test.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${PREBUILD_DIR:-/tmp/flashgs-prebuild}
targets=(app/flashgs tests/test_cuda_render tests/test_stress_gpu tests/test_cpu_simd tests/test_cpu_project_simd)
[ -x /usr/local/cuda/bin/nvcc ] && export CUDACXX=${CUDACXX:-/usr/local/cuda/bin/nvcc}
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CUDA_ARCHITECTURES=90 \
  -DFLASHGS_BUILD_APP=OFF -DOIIO_LIBRARY=OFF -DOIIO_UTIL_LIBRARY=OFF -DOIIO_INCLUDE_DIR=OFF ${FLASHGS_CMAKE_ARGS:-} > /dev/null
ninja -C "$build" "${targets[@]}"
rm -rf "$root/.deps/bin" "$root/.deps/lib"
mkdir -p "$root/.deps/bin" "$root/.deps/lib"
for t in "${targets[@]}"; do xz -T2 -6 -c "$build/$t" > "$root/.deps/bin/$(basename "$t").xz"; done
for t in "${targets[@]}"; do ldd "$build/$t"; done | awk '/=> \// {print $3}' | sort -u | while read -r lib; do
  case $(basename "$lib") in libc.so.*|libm.so.*|libpthread.so.*|libdl.so.*|librt.so.*) ;; *) cp -L "$lib" "$root/.deps/lib/" ;; esac
done
# The GPU timeline library of gpu_check.sh's trace step (CUPTI, which the device machine has).
g++ -O2 -std=c++17 -shared -fPIC -I/usr/local/cuda/include "$root/tools/device/gpu_trace.cpp" -L/usr/local/cuda/lib64 \
  -lcupti -o "$root/.deps/libgputrace.so" || echo "prebuild: no CUPTI here, so no trace step on the device" >&2
# The launch-cost measurement of gpu_check.sh's launch-cost step.
"${CUDACXX:-nvcc}" -O2 -std=c++17 -arch=sm_90 "$root/tools/device/launch_cost.cu" -o "$root/.deps/launch_cost"
bash "$root/tools/device/source_stamp.sh" > "$root/.deps/bin/STAMP"
du -sh "$root/.deps/bin" "$root/.deps/lib"
