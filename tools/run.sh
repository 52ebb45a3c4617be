#!/usr/bin/env bash
# Sets up (packages, build) and opens the viewer on the bundled demo scene, or on the scene
# given as argument. Without a display it renders the scene headless to out/render.png.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/tools/setup.sh"
build="${FLASHGS_BUILD_DIR:-$root/build}"
if [ -n "${DISPLAY:-}${WAYLAND_DISPLAY:-}" ] && [ -x "$build/app/flashgs-viewer" ]; then
  exec "$build/app/flashgs-viewer" "$@"
fi
mkdir -p "$root/out"
echo "no display: rendering headless to out/render.png"
"$build/app/flashgs" render "$@" -o "$root/out/render.png"
