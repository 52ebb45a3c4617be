#!/usr/bin/env bash
# Installs the Debian packages the build needs (as root, or through sudo) and configures +
# builds into build/. Sourced by tools/run.sh and tools/test.sh; safe to run again.
# FLASHGS_EXTRA_PACKAGES, FLASHGS_BUILD_DIR and FLASHGS_CMAKE_ARGS let tools/tsan.sh reuse it.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

packages=(build-essential cmake ninja-build pkg-config
          libglm-dev libopenimageio-dev openimageio-tools libcli11-dev nlohmann-json3-dev libgtest-dev
          libglfw3-dev libimgui-dev libgl-dev libx11-dev libxtst-dev xvfb xauth libgl1-mesa-dri
          libhwy-dev libwebp-dev libpng-dev zlib1g-dev libzstd-dev
          python3-dev python3-pybind11 python3-numpy python3-pytest python3-venv ${FLASHGS_EXTRA_PACKAGES:-})
missing=()
for p in "${packages[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
if [ ${#missing[@]} -gt 0 ]; then
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  echo "installing: ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# The CUDA toolkit is optional: with nvcc the CUDA backend is built (for the architectures in
# FLASHGS_CUDA_ARCHS, default 90 = H100), without it the CPU backend alone.
if ! command -v nvcc >/dev/null && [ -x /usr/local/cuda/bin/nvcc ]; then export CUDACXX=/usr/local/cuda/bin/nvcc; fi
# The Python module is built for Debian's python3, whose numpy and pytest the packages above
# install (another python3 may come first on the PATH).
python=()
[ -x /usr/bin/python3 ] && python=(-DPython_EXECUTABLE=/usr/bin/python3)
build="${FLASHGS_BUILD_DIR:-$root/build}"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CUDA_ARCHITECTURES="${FLASHGS_CUDA_ARCHS:-90}" "${python[@]}" ${FLASHGS_CMAKE_ARGS:-} >/dev/null
cmake --build "$build" -j "$(nproc)"
