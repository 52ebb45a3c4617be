#!/usr/bin/env bash
# Prints one hash of the sources the device binaries are built from, so that binaries built on
# one machine (tools/device/prebuild.sh) are used on another only for the very same tree.
set -euo pipefail
cd "$(dirname "$0")/../.."
find CMakeLists.txt cuda renderer app tests shaders -type f -print0 | LC_ALL=C sort -z | xargs -0 sha256sum |
  sha256sum | cut -d' ' -f1
