#!/usr/bin/env bash
# Sets up (packages, build) and runs every test. Real-scene tests use ../shared/scenes when it
# exists and skip otherwise; GPU tests skip without a CUDA device.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/tools/setup.sh"
cd "${FLASHGS_BUILD_DIR:-$root/build}"
# A failed test runs once more (docs/TESTING.md: the live viewer tests drive a real window
# through X on a loaded machine); one that fails twice fails the run.
ctest --output-on-failure --repeat until-pass:2 -j "$(nproc)" "$@"
