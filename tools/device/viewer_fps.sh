#!/usr/bin/env bash
# Viewer frames per second on the GPU machine: flashgs-viewer plays the camera path under a carried
# Xvfb with NVIDIA's GLX library (CUDA-GL interop path), at 1920x1080 and 3840x2160, and prints
# FPS, frame times and the active frame path (presentation included: every frame is swapped).
#
# Usage, from the repository root through the device `run` tool, carrying .devgl:
#   bash tools/device/viewer_fps.sh [SCENE...]
# SCENE: a PLY file (cameras.json beside it), FILE@K for K tiled copies of it, demo:N for the
# procedural demo scene of N Gaussians (made in memory: nothing to carry), or stream:SET for a LOD
# set (lod-meta.json or its folder) streamed with --stream (its cut handed over as parts; the
# scripted frames wait for each view's chunks). Default:
# demo:3000000, the bundled demo scene, and pc_playbot when a copy is found under .deps/scenes
# or /work/shared/scenes.
# Knobs: FRAMES (timed frames, default 300), WARMUP (default 30), RESOLUTIONS (default
# "1920x1080 3840x2160"), VIEWER (the binary), DEVGL (default .devgl), OUT (default out/).
#
# .devgl must hold (see /work/shared/device-gl/README.md):
#   .devgl/device-gl/   a copy of /work/shared/device-gl
#   .devgl/debs/        bash .devgl/device-gl/fetch-debs.sh .devgl/debs   (~60 MiB)
#   .devgl/bin/flashgs-viewer   built here with CUDA for sm_90 and without OpenImageIO (absent there):
#     cmake -S . -B build-viewer-dev -G Ninja -DCMAKE_BUILD_TYPE=Release -DFLASHGS_WITH_CUDA=ON \
#       -DCMAKE_CUDA_ARCHITECTURES=90 -DFLASHGS_BUILD_TESTS=OFF -DOIIO_LIBRARY=OFF
#     ninja -C build-viewer-dev flashgs-viewer
#     mkdir -p .devgl/bin .devgl/lib && strip -o .devgl/bin/flashgs-viewer build-viewer-dev/app/flashgs-viewer
#     cp -L /usr/lib/x86_64-linux-gnu/libgomp.so.1 .devgl/lib/   # OpenMP runtime, if the machine lacks it
#     cp -L /usr/lib/x86_64-linux-gnu/libhwy.so.1 .devgl/lib/    # Highway (the CPU blend's SIMD dispatch)
# The call sends at most 64 MiB in all: debs + binary + the working tree must fit. They may not
# (debs ~60 MiB, tree ~4-8 MiB, binary ~3 MiB). Carried paths that a later call does not name
# stay on a warm machine (not tried here), so the carry can be split
# over two calls on the same machine:
#   1) carry [".devgl/debs/xroot"] with command "true"   (Xvfb + Mesa: the bulk)
#   2) carry [".devgl/debs/gl", ".devgl/debs/client", ".devgl/device-gl", ".devgl/bin", ".devgl/lib"]
#      with command "bash tools/device/viewer_fps.sh"
set -u
ROOT=$(pwd)
OUT=${OUT:-$ROOT/out}
DEVGL=${DEVGL:-$ROOT/.devgl}
VIEWER=${VIEWER:-$DEVGL/bin/flashgs-viewer}
FRAMES=${FRAMES:-300}
WARMUP=${WARMUP:-30}
RESOLUTIONS=${RESOLUTIONS:-1920x1080 3840x2160}
mkdir -p "$OUT/viewer_fps"
summary="$OUT/viewer_fps/summary.txt"
: > "$summary"
say() { echo "$*" | tee -a "$summary"; }

[ -d "$DEVGL/lib" ] && export LD_LIBRARY_PATH="$DEVGL/lib:${LD_LIBRARY_PATH:-}"
# A 4K window has to fit on the X screen.
export DEVGL_SCREEN=${DEVGL_SCREEN:-3840x2160x24}
# shellcheck source=/dev/null
if ! source "$DEVGL/device-gl/device-setup.sh" "$DEVGL/debs"; then
  say "device-setup.sh failed: no X server, nothing measured"
  exit 1
fi
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader 2>/dev/null | sed 's/^/gpu: /' | tee -a "$summary"
say "GLX vendor: ${__GLX_VENDOR_LIBRARY_NAME:-default}, DISPLAY=$DISPLAY, screen $DEVGL_SCREEN"
if [ ! -x "$VIEWER" ]; then
  say "no viewer binary at $VIEWER (build it as the header of this script says)"
  exit 2
fi
missing=$(ldd "$VIEWER" 2>&1 | grep "not found" || true)
if [ -n "$missing" ]; then
  say "the viewer lacks libraries here:"
  say "$missing"
  exit 2
fi

scenes=("$@")
if [ ${#scenes[@]} -eq 0 ]; then
  scenes=(demo:3000000 "$ROOT/assets/demo/point_cloud.ply")
  for d in "$ROOT/.deps/scenes/pc_playbot" /work/shared/scenes/pc_playbot; do
    if [ -f "$d/point_cloud.ply.xz" ] && [ ! -f "$d/point_cloud.ply" ]; then xz -d -k -T0 "$d/point_cloud.ply.xz" 2>/dev/null; fi
    if [ -f "$d/point_cloud.ply" ]; then scenes+=("$d/point_cloud.ply"); break; fi
  done
fi

# The fallback: a Mesa (llvmpipe) context cannot share with CUDA, so the viewer must pick the
# host-copy path by itself and still show the right pixels.
fallback_log="$OUT/viewer_fps/mesa_fallback.log"
__GLX_VENDOR_LIBRARY_NAME=mesa timeout 300 "$VIEWER" "$ROOT/assets/demo/point_cloud.ply" --size 1280x720 --camera 0 \
  --frames 3 --check-frame --exit > "$fallback_log" 2>&1
say "mesa fallback: exit $? | $(grep -m1 "frame path:" "$fallback_log" | sed 's/.*frame path: //')"
grep -m1 "viewer frame check" "$fallback_log" | sed 's/^/    /' | tee -a "$summary"

run_one() {  # scene-label render-size window-label viewer-args...
  local label=$1 res=$2 window=$3
  shift 3
  local log="$OUT/viewer_fps/$(echo "${label}_${res}_${window}" | tr '/: @,' '_____').log"
  timeout 300 "$VIEWER" "$@" --path --frames "$FRAMES" --warmup "$WARMUP" --no-vsync --exit > "$log" 2>&1
  local rc=$?
  local path frames
  path=$(grep -m1 "frame path:" "$log" | sed 's/.*frame path: //')
  frames=$(grep -m1 "^viewer frames:" "$log")
  if [ $rc -ne 0 ] || [ -z "$frames" ]; then
    printf '%-44s %-10s %-22s %8s  (exit %d; see %s)\n' "$label" "$res" "$window" failed "$rc" "$log" | tee -a "$summary"
    tail -5 "$log" | sed 's/^/    /' | tee -a "$summary"
    return
  fi
  local fps mean p95
  fps=$(echo "$frames" | sed -E 's/.*\| ([0-9.]+) FPS.*/\1/')
  mean=$(echo "$frames" | sed -E 's/.*mean ([0-9.]+) ms.*/\1/')
  p95=$(echo "$frames" | sed -E 's/.*p95 ([0-9.]+) ms.*/\1/')
  printf '%-44s %-10s %-22s %8s %9s %9s  %s\n' "$label" "$res" "$window" "$fps" "$mean" "$p95" "$path" | tee -a "$summary"
  grep -E "^viewer (render:|split)" "$log" | sed 's/^/    /' | tee -a "$summary"
}

for scene in "${scenes[@]}"; do
  case "$scene" in
    demo:*) args=(--generate-demo "${scene#demo:}") ;;
    stream:*) args=("${scene#stream:}" --stream) ;;
    *@*) args=("${scene%@*}" --tile "${scene##*@}") ;;
    *) args=("$scene") ;;
  esac
  label=$(basename "$(dirname "$scene")")/$(basename "$scene")
  [[ "$scene" == demo:* ]] && label=$scene
  # Correctness first: the texture shown (written through interop) must equal the backend's
  # own host image of the same view.
  check_log="$OUT/viewer_fps/$(echo "${label}_check" | tr '/: @,' '_____').log"
  timeout 300 "$VIEWER" "${args[@]}" --size 1920x1080 --camera 0 --frames 5 --check-frame --exit > "$check_log" 2>&1
  say "check $label: exit $? | $(grep -m1 "frame path:" "$check_log" | sed 's/.*frame path: //')"
  grep -m1 "viewer frame check" "$check_log" | sed 's/^/    /' | tee -a "$summary"
  printf '%-44s %-10s %-22s %8s %9s %9s  %s\n' scene render window FPS mean_ms p95_ms "frame path" | tee -a "$summary"
  for res in $RESOLUTIONS; do
    # The window is the render size: Xvfb's copy of every presented frame included.
    run_one "$label" "$res" "window $res" "${args[@]}" --size "$res"
    # Rendered at full size, shown in a 1280x720 window: interop + render + a small present.
    run_one "$label" "$res" "window 1280x720" "${args[@]}" --size 1280x720 --render-size "$res"
    # Panels hidden: what the ImGui pass costs.
    run_one "$label" "$res" "window $res, no UI" "${args[@]}" --size "$res" --no-ui
  done
done
say "logs: $OUT/viewer_fps/"
