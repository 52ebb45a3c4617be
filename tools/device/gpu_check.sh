#!/usr/bin/env bash
# GPU check on the lent device machine: GPU tests, compute-sanitizer, benchmarks, profiles.
# Usage (from the repository root, through the device `run` tool, carrying .deps):
#   tools/device/gpu_check.sh STEP...   steps: setup build tests sanitize bench-quick bench-kernel parity-renders
#                                       bench-ab bench-env bench
#                                       bench-regions bench-large bench-prev bench-cpu bench-scale report profile
#                                       cpu-simd-tests build-prev bench-cpu-prev
#                                       profile-blend profile-sass bench-variants kernel-times trace launch-cost
#                                       build-bg wait-build build-prev-bg bench-prev-cuda
# tools/device/make_deps.sh fills .deps (52 MB; with the tree, just under a call's 64 MiB):
# .deps holds include/ (glm, CLI, nlohmann), googletest/, scenes/NAME/{point_cloud.ply.xz,
# cameras.json}, sysroot/usr with Debian's Highway (include/hwy, lib/x86_64-linux-gnu/{libhwy*.so*,
# cmake/hwy}) and optionally bin/ + lib/ from tools/device/prebuild.sh: binaries built on the
# development machine, which setup runs instead of building when their stamp matches this tree
# and they start here (otherwise it builds everything into build-dev, as `build` does).
set -u
ROOT=$(pwd)
OUT=${OUT:-$ROOT/out}
mkdir -p "$OUT"
BIN=$ROOT/.deps/bin
SCENES=$ROOT/.deps/scenes
log() { echo "== $(date +%T) $*" | tee -a "$OUT/summary.txt"; }

setup() {
  nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm --format=csv | tee "$OUT/device.txt"
  for f in "$SCENES"/*/point_cloud.ply.xz; do
    [ -f "${f%.xz}" ] || xz -d -k -T0 "$f"
  done
  # The carried binaries name the scene and asset folders of the machine they were built on.
  if [ ! -e /work/shared/scenes ]; then mkdir -p /work/shared && ln -sfn "$SCENES" /work/shared/scenes; fi
  if [ ! -e /work/main/assets ]; then mkdir -p /work/main && ln -sfn "$ROOT/assets" /work/main/assets; fi
  ls /work/shared/scenes/ | tr '\n' ' '; echo
  export LD_LIBRARY_PATH=$ROOT/.deps/sysroot/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
  if use_carried_binaries; then
    log "using carried binaries"
  else
    build
  fi
}

# The binaries of tools/device/prebuild.sh, when they were built from this very tree and start
# here (with the libraries carried beside them: only then, so that binaries built here keep the
# machine's own C++ runtime).
use_carried_binaries() {
  if [ ! -f "$BIN/STAMP" ]; then log "no carried binaries; building"; return 1; fi
  if [ "$(cat "$BIN/STAMP")" != "$(bash "$ROOT/tools/device/source_stamp.sh")" ]; then
    log "the carried binaries are of another tree; building"
    return 1
  fi
  # Unpacked outside .deps (build-carried is git-ignored and not carried back and forth).
  local dir=$ROOT/build-carried f
  mkdir -p "$dir"
  for f in "$BIN"/*.xz; do xz -d -c "$f" > "$dir/$(basename "${f%.xz}")" && chmod +x "$dir/$(basename "${f%.xz}")"; done
  local libs=$ROOT/.deps/lib:$LD_LIBRARY_PATH
  if ! LD_LIBRARY_PATH=$libs "$dir/flashgs" --help > /dev/null 2>&1; then
    log "the carried binaries do not start here ($(LD_LIBRARY_PATH=$libs "$dir/flashgs" --help 2>&1 | head -1)); building"
    return 1
  fi
  export LD_LIBRARY_PATH=$libs
  FLASHGS=$dir/flashgs
  TESTS=$dir/test_cuda_render
  STRESS_TESTS=$dir/test_stress_gpu
  TEST_DIR=$dir
}

build() {
  # .deps/sysroot: Debian's Highway (headers, library, CMake config) for the SIMD CPU blend.
  cmake -S . -B build-dev -G Ninja -DCMAKE_BUILD_TYPE=Release -DFLASHGS_HEADER_DEPS_DIR="$ROOT/.deps/include" \
    -DCMAKE_PREFIX_PATH="$ROOT/.deps/sysroot/usr" \
    -DCMAKE_CUDA_ARCHITECTURES=90 -DFLASHGS_BUILD_APP=OFF -DFLASHGS_SHARED_SCENES="$SCENES" \
    -DFLASHGS_GTEST_SOURCE_DIR="$ROOT/.deps/googletest" > "$OUT/build.log" 2>&1 &&
    ninja -C build-dev flashgs test_cuda_render test_stress_gpu test_cpu_simd test_cpu_project_simd >> "$OUT/build.log" 2>&1
  local rc=$?
  log "device build rc=$rc"
  if [ $rc -eq 0 ]; then
    FLASHGS=$ROOT/build-dev/app/flashgs
    TESTS=$ROOT/build-dev/tests/test_cuda_render
    STRESS_TESTS=$ROOT/build-dev/tests/test_stress_gpu
    TEST_DIR=$ROOT/build-dev/tests
  fi
  tail -5 "$OUT/build.log"
}

tests() {  # GPU_TEST_FILTER: a gtest filter (default: every test but the sanitizer frames)
  log "gpu tests"
  "$TESTS" --gtest_filter="${GPU_TEST_FILTER:--CudaSanitizer.*}" 2>&1 | tee "$OUT/gpu_tests.log" | grep -E "^\[  (FAILED|PASSED|SKIPPED) |Failure|expected error" | head -40
  log "gpu tests rc=${PIPESTATUS[0]}"
  if [ -x "$STRESS_TESTS" ]; then
    log "stress gpu tests"
    "$STRESS_TESTS" 2>&1 | tee "$OUT/stress_gpu.log" | grep -E -A6 "^\[  (FAILED|PASSED) |Failure" | head -60
    log "stress gpu rc=${PIPESTATUS[0]}"
  fi
}

sanitize() {  # SANITIZERS: the compute-sanitizer tools (default memcheck racecheck; racecheck of every kernel
  # outgrew 300 s on an H200: RACECHECK_KERNELS="blend_warp_tile preprocess" checks, one run each, only the
  # kernels whose names hold one of those texts, the others run unchecked at full speed, ~2 minutes a run;
  # SANITIZER_TIMEOUT, default 300 s a run)
  export FLASHGS_SANITIZER_SCENE=pc_biker
  local tool kernel kernels
  for tool in ${SANITIZERS:-memcheck racecheck}; do
    kernels=("")
    [ $tool = racecheck ] && [ -n "${RACECHECK_KERNELS:-}" ] && read -r -a kernels <<< "$RACECHECK_KERNELS"
    for kernel in "${kernels[@]}"; do
      local only=() log_name=sanitizer_$tool${kernel:+_$kernel}
      log "compute-sanitizer $tool${kernel:+ (kernels named *$kernel*)}"
      if [ $tool = racecheck ]; then
        export FLASHGS_SANITIZER_QUICK=1
        [ -n "$kernel" ] && only=(--kernel-name "kns=$kernel")
      fi
      timeout "${SANITIZER_TIMEOUT:-300}" compute-sanitizer --tool $tool ${only[@]+"${only[@]}"} --error-exitcode 9 --print-limit 20 \
        "$TESTS" --gtest_filter=CudaSanitizer.* > "$OUT/$log_name.log" 2>&1
      log "sanitizer $tool${kernel:+ ($kernel)} rc=$? $(grep -E 'ERROR SUMMARY|RACECHECK SUMMARY' "$OUT/$log_name.log" | tail -1)"
    done
    if [ $tool = memcheck ]; then  # the sanitizer frames sort per bin; CUB's sort and its list kernels too
      FLASHGS_BIN_SORT=0 timeout 300 compute-sanitizer --tool memcheck --error-exitcode 9 --print-limit 20 \
        "$TESTS" --gtest_filter=CudaSanitizer.* > "$OUT/sanitizer_memcheck_cub_sort.log" 2>&1
      log "sanitizer memcheck, CUB's sort, rc=$? $(grep -E 'ERROR SUMMARY' "$OUT/sanitizer_memcheck_cub_sort.log" | tail -1)"
    fi
  done
}

bench_scene() {  # scene-folder json-name extra-args...
  local dir=$1 name=$2
  shift 2
  "$FLASHGS" bench "$dir/point_cloud.ply" -o "$OUT/$name.json" "$@" 2> "$OUT/$name.err" | tee "$OUT/$name.txt" | tail -22
}

bench_quick() {
  log "bench quick"
  bench_scene "$SCENES/pc_biker" bench_biker_quick --backend cuda -r 1920x1080 --configs baseline,flash --warmup 2 --repeat 5
}

bench_kernel() {  # the classic and the anti-aliased kernel in one run: baseline and flash each, KERNEL_SCENES
  # (default pc_biker pc_playbot) at 1080p and 4K
  for scene in ${KERNEL_SCENES:-pc_biker pc_playbot}; do
    log "bench kernels $scene"
    bench_scene "$SCENES/$scene" bench_kernel_$scene --backend cuda --kernel classic \
      --configs baseline,flash,baseline-antialiased,flash-antialiased
  done
}

parity_renders() {  # our frames for the side-by-side image check against other rasterizers: cameras PARITY_IDS
  # (default 0 10 20) of every scene, 1080p, classic and anti-aliased, as /tmp/parity/SCENE/camID_KERNEL.pfm
  local scene id kernel
  for scene in pc_biker pc_guitar pc_playbot v3dg_donut kacytran_try; do
    mkdir -p /tmp/parity/$scene
    for id in ${PARITY_IDS:-0 10 20}; do
      for kernel in classic antialiased; do
        "$FLASHGS" render "$SCENES/$scene/point_cloud.ply" --backend cuda -c $id -r 1920x1080 --kernel $kernel \
          -o /tmp/parity/$scene/cam${id}_$kernel.pfm > /dev/null || log "parity render $scene $id $kernel failed"
      done
    done
  done
  log "parity renders: $(find /tmp/parity -name '*.pfm' | wc -l) frames in /tmp/parity"
}

bench_ab() {  # flash against flash with one switch off (AB_CONFIG, default flash-no_dense_tiles_first), same run;
  # AB_TILED=0 leaves out the 7 x pc_playbot rows
  for scene in pc_biker pc_playbot; do
    log "bench A/B $scene"
    bench_scene "$SCENES/$scene" bench_ab_$scene --backend cuda -r 1920x1080,3840x2160 \
      --configs flash,${AB_CONFIG:-flash-no_dense_tiles_first} --warmup 2 --repeat 5 | grep -E "^[0-9]+x|^res"
  done
  [ "${AB_TILED:-1}" = 1 ] || return 0
  log "bench A/B 7 x pc_playbot"
  bench_scene "$SCENES/pc_playbot" bench_ab_tile7 --backend cuda --tile 7 -r 1920x1080,3840x2160 \
    --configs flash,${AB_CONFIG:-flash-no_dense_tiles_first} --warmup 2 --repeat 5 | grep -E "^[0-9]+x|^res"
}

bench_env() {  # flash without and with the environment of ENV_AB (e.g. FLASHGS_SORT_KEY_BITS=24), same run;
  # ENV_TILED=1 adds pc_playbot tiled 7 times in memory
  local scene tile
  for scene in pc_biker pc_playbot ${ENV_TILED:+pc_playbot_x7}; do
    tile=""
    [ $scene = pc_playbot_x7 ] && tile="--tile 7"
    log "bench env: $scene, default"
    bench_scene "$SCENES/${scene%_x7}" bench_env_a_$scene --backend cuda $tile -r 1920x1080,3840x2160 --configs flash \
      --warmup 2 --repeat 5 | grep -E "^[0-9]+x|^res"
    log "bench env: $scene, $ENV_AB"
    (export $ENV_AB; bench_scene "$SCENES/${scene%_x7}" bench_env_b_$scene --backend cuda $tile -r 1920x1080,3840x2160 \
      --configs flash --warmup 2 --repeat 5 | grep -E "^[0-9]+x|^res")
  done
}

bench_regions() {  # warp-blend region widths: WIDTHS (default 8 16)
  for width in ${WIDTHS:-8 16}; do
    log "bench region width=$width"
    for scene in pc_biker pc_playbot; do
      FLASHGS_BLEND_REGION_WIDTH=$width bench_scene "$SCENES/$scene" ${TAG:-}bench_w${width}_$scene --backend cuda \
        -r 1920x1080,3840x2160 --configs flash --warmup 2 --repeat 5 | grep -E "^[0-9]+x"
    done
  done
}

bench_large() {  # the warp-emission threshold in tiles: LARGE (default 8 16 32 64)
  for tiles in ${LARGE:-8 16 32 64}; do
    log "bench large box tiles=$tiles"
    for scene in pc_biker pc_playbot; do
      FLASHGS_LARGE_BOX_TILES=$tiles bench_scene "$SCENES/$scene" bench_large${tiles}_$scene --backend cuda \
        -r 1920x1080,3840x2160 --configs flash --warmup 2 --repeat 5 | grep -E "^[0-9]+x"
    done
  done
}

bench() {
  log "bench pc_biker"
  bench_scene "$SCENES/pc_biker" bench_biker --backend cuda -r 1920x1080,3840x2160 --warmup 2 --repeat 5
  log "bench pc_playbot"
  bench_scene "$SCENES/pc_playbot" bench_playbot --backend cuda -r 1920x1080,3840x2160 --warmup 2 --repeat 5
  log "generate 7 x pc_playbot"
  [ -f /tmp/tile7/point_cloud.ply ] || "$FLASHGS" generate tile -i "$SCENES/pc_playbot/point_cloud.ply" -n 7 -o /tmp/tile7 | tail -1
  bench_scene /tmp/tile7 bench_tile7 --backend cuda -r 1920x1080,3840x2160 --configs baseline,flash --warmup 2 --repeat 5
}

bench_cpu() {  # the CPU backend on 1, 2 and every host thread (CPU_THREADS); TAG prefixes the files
  for threads in ${CPU_THREADS:-1 2 $(nproc)}; do
    log "bench cpu ${TAG:-}pc_playbot 1080p, $threads threads"
    OMP_NUM_THREADS=$threads bench_scene "$SCENES/pc_playbot" ${TAG:-}bench_playbot_cpu_t$threads --backend cpu \
      -r 1920x1080 --configs baseline,flash --camera-list 0,10,20 --warmup 1 --repeat 3 | grep -E "^[0-9]+x"
    log "bench cpu ${TAG:-}pc_biker 1280x800, $threads threads"
    OMP_NUM_THREADS=$threads bench_scene "$SCENES/pc_biker" ${TAG:-}bench_biker_cpu_t$threads --backend cpu \
      -r 1280x800 --configs baseline,flash --camera-list 0,10,20 --warmup 1 --repeat 3 | grep -E "^[0-9]+x"
  done
}

build_prev() {  # an earlier tree's flashgs into /tmp/prev/b, for an A/B in the same run: .deps/prev.tar.gz
  # (made with `git archive <commit> -- . ':!docs' ':!assets' | gzip`); CPU backend only unless PREV_CUDA=1
  rm -rf /tmp/prev && mkdir -p /tmp/prev && tar xzf "$ROOT/.deps/prev.tar.gz" -C /tmp/prev &&
    cmake -S /tmp/prev -B /tmp/prev/b -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DFLASHGS_WITH_CUDA=$([ "${PREV_CUDA:-0}" = 1 ] && echo ON || echo OFF) -DCMAKE_CUDA_ARCHITECTURES=90 \
      -DFLASHGS_HEADER_DEPS_DIR="$ROOT/.deps/include" -DCMAKE_PREFIX_PATH="$ROOT/.deps/sysroot/usr" \
      -DFLASHGS_BUILD_APP=OFF -DFLASHGS_BUILD_TESTS=OFF > "$OUT/build_prev.log" 2>&1 &&
    ninja -C /tmp/prev/b flashgs >> "$OUT/build_prev.log" 2>&1
  log "build of the earlier tree rc=$?"
}

cpu_simd_tests() {  # the SIMD kernels against the scalar ones on every target this host runs (AVX-512 here)
  for t in test_cpu_simd test_cpu_project_simd; do
    log "$t"
    "$TEST_DIR/$t" > "$OUT/$t.log" 2>&1
    log "$t rc=$? $(grep -E '^\[  (PASSED|FAILED)' "$OUT/$t.log" | tr '\n' ' ')"
  done
}

bench_prev_cuda() {  # the earlier tree's CUDA flash (build-prev with PREV_CUDA=1) on the bench-ab rows; PREV_CONFIGS (flash)
  for scene in pc_biker pc_playbot; do
    log "bench earlier tree $scene"
    bench_scene "$SCENES/$scene" prev_bench_$scene --backend cuda -r 1920x1080,3840x2160 --configs ${PREV_CONFIGS:-flash} \
      --warmup 2 --repeat 5 | grep -E "^[0-9]+x|^res"
  done
  log "bench earlier tree 7 x pc_playbot"
  bench_scene "$SCENES/pc_playbot" prev_bench_tile7 --backend cuda --tile 7 -r 1920x1080,3840x2160 --configs flash \
    --warmup 2 --repeat 5 | grep -E "^[0-9]+x|^res"
}

bench_variants() {  # flash rows of several builds in one call, for an A/B that noise between calls cannot blur.
  # VARIANTS: "tree" (this tree's flashgs) and NAMEs of .deps/variants/NAME.xz (flashgs of other trees, e.g. from
  # `ninja app/flashgs` in the prebuild folder, xz-compressed); VARIANT_ROWS: scene[:extra bench args] items (default
  # pc_biker pc_playbot pc_playbot:--tile=7); VARIANT_RES (default 1920x1080,3840x2160); environment such as
  # FLASHGS_BIN_SORT=1 applies to every row; VARIANT_CONFIGS: the bench configs (default flash). Prints "== variant
  # scene args" and the bench rows.
  local v bin row scene extra
  mkdir -p /tmp/variants
  for v in ${VARIANTS:-tree}; do
    bin=$FLASHGS
    if [ "$v" != tree ]; then
      bin=/tmp/variants/$v
      [ -x "$bin" ] || { xz -d -c "$ROOT/.deps/variants/$v.xz" > "$bin" && chmod +x "$bin"; } || { log "no variant $v"; continue; }
    fi
    for row in ${VARIANT_ROWS:-pc_biker pc_playbot pc_playbot:--tile=7}; do
      scene=${row%%:*}
      extra=""
      [ "$row" != "$scene" ] && extra=${row#*:}
      echo "== $v $scene ${extra//=/ }"
      "$bin" bench "$SCENES/$scene/point_cloud.ply" --backend cuda -r "${VARIANT_RES:-1920x1080,3840x2160}" \
        --configs "${VARIANT_CONFIGS:-flash}" --warmup 2 --repeat 5 ${extra//=/ } -o /tmp/variant.json 2>&1 |
        grep -E "^[0-9]+x[0-9]+ +flash[-a-z0-9_]* +[0-9]|rror"
    done
  done
}

kernel_times() {  # ncu time of the kernels matching KERNEL_FILTER (default bin_|blend|preprocess) in one frame of
  # each of VARIANTS (as bench_variants), pc_playbot camera 10 at KERNEL_RES: "variant res kernel ns" lines.
  # Enough frames that a filter matching one kernel per frame still reaches the skipped and counted launches.
  local v bin res frames=$(( ${KERNEL_SKIP:-20} + ${KERNEL_COUNT:-4} + 2 ))
  for v in ${VARIANTS:-tree}; do
    bin=$FLASHGS
    [ "$v" != tree ] && bin=/tmp/variants/$v
    [ "$v" != tree ] && [ ! -x "$bin" ] && { xz -d -c "$ROOT/.deps/variants/$v.xz" > "$bin" && chmod +x "$bin"; }
    for res in ${KERNEL_RES:-1920x1080 3840x2160}; do
      timeout 120 ncu --csv --metrics gpu__time_duration.sum -k regex:"${KERNEL_FILTER:-bin_|blend|preprocess}" \
        --launch-skip ${KERNEL_SKIP:-20} --launch-count ${KERNEL_COUNT:-4} "$bin" render \
        "$SCENES/pc_playbot/point_cloud.ply" --backend cuda -c 10 -r "$res" --repeat $frames -o /tmp/p.ppm 2>/dev/null |
        grep gpu__time | awk -F'","' -v v="$v" -v r="$res" '{name=$5; sub(/\(.*/, "", name); t=$NF; gsub(/"/, "", t); print v, r, name, t}'
    done
  done
}

traced() {  # OUTFILE COMMAND...: runs the command under the GPU timeline (tools/device/gpu_trace.cpp, built into
  # .deps/libgputrace.so by prebuild.sh), runtime calls included, its lines written to OUTFILE
  local cupti
  cupti=$(ls -d /usr/local/cuda*/targets/x86_64-linux/lib 2>/dev/null | head -1)
  local out=$1
  shift
  LD_LIBRARY_PATH=$LD_LIBRARY_PATH:$cupti CUDA_INJECTION64_PATH=$ROOT/.deps/libgputrace.so FLASHGS_TRACE_API=1 \
    FLASHGS_TRACE_OUT=$out "$@"
}

trace() {  # the GPU timeline of flash frames of TRACE_SCENES (default pc_biker pc_playbot) at TRACE_RES (default
  # 1920x1080), camera 10: trace_SCENE.txt, and the frames' spans, idle time and gaps (trace_frames.py) in trace.txt;
  # TRACE_BIN: another flashgs (default this tree's)
  local scene bin=${TRACE_BIN:-$FLASHGS}
  [ -f "$ROOT/.deps/libgputrace.so" ] || { log "no .deps/libgputrace.so"; return; }
  for scene in ${TRACE_SCENES:-pc_biker pc_playbot}; do
    traced "$OUT/trace_$scene.txt" "$bin" bench "$SCENES/$scene/point_cloud.ply" --backend cuda \
      -r "${TRACE_RES:-1920x1080}" --configs flash --camera-list 10 --warmup 3 --repeat 10 2>&1 | grep -E "^[0-9]+x.*flash +[0-9]"
    python3 "$ROOT/tools/device/trace_frames.py" "$OUT/trace_$scene.txt" | tee -a "$OUT/trace.txt" | head -1
  done
}

launch_cost() {  # what a frame's first launches cost (tools/device/launch_cost.cu, in .deps), each mode under the
  # GPU timeline and without: launch_cost.txt and trace_launch_MODE.txt
  local mode
  [ -x "$ROOT/.deps/launch_cost" ] && [ -f "$ROOT/.deps/libgputrace.so" ] || { log "no .deps/launch_cost or tracer"; return; }
  for mode in direct nomemset small graph capture; do
    traced "$OUT/trace_launch_$mode.txt" "$ROOT/.deps/launch_cost" $mode | tee -a "$OUT/launch_cost.txt"
    "$ROOT/.deps/launch_cost" $mode | sed 's/^/untraced /' | tee -a "$OUT/launch_cost.txt"
  done
}

bench_scale() {  # pc_playbot copied SCALE_COPIES times in memory (default 20 60 200: 10M, 30M, 100M)
  for copies in ${SCALE_COPIES:-20 60 200}; do
    log "bench scale: $copies x pc_playbot"
    bench_scene "$SCENES/pc_playbot" bench_scale_$copies --backend cuda --tile $copies -r 1920x1080,3840x2160 \
      --configs flash --camera-list 0,10,20 --warmup 1 --repeat 3 | grep -E "^[0-9]+x|Gaussians|error"
  done
}

report() {  # the error-vs-time report of pc_playbot on each backend of REPORT_BACKENDS (default cuda cpu)
  for backend in ${REPORT_BACKENDS:-cuda cpu}; do
    log "report pc_playbot $backend"
    timeout ${REPORT_TIMEOUT:-600} "$FLASHGS" report "$SCENES/pc_playbot/point_cloud.ply" --backend $backend --title pc_playbot \
      -o "$OUT/report_$backend" > "$OUT/report_$backend.txt" 2>&1
    log "report $backend rc=$?"
  done
}

profile() {  # PROFILE_SCENE (pc_playbot), PROFILE_RES (3840x2160)
  log "ncu ${PROFILE_SCENE:-pc_playbot} ${PROFILE_RES:-3840x2160}"
  timeout 240 ncu --set basic -k regex:'preprocess|emit|blend|ranges|duplicate|Onesweep' --launch-skip 20 \
    --launch-count 12 "$FLASHGS" render "$SCENES/${PROFILE_SCENE:-pc_playbot}/point_cloud.ply" --backend cuda -c 10 \
    -r "${PROFILE_RES:-3840x2160}" --repeat 6 -o /tmp/p.ppm > "$OUT/ncu.txt" 2>&1
  log "ncu rc=$?"
  grep -E "^  [a-z_].*\(|Duration|Memory Throughput|Compute \(SM\) Throughput|Registers Per|Achieved Occupancy" "$OUT/ncu.txt" | head -60
}

profile_kernels() {  # each kernel's GPU time in one frame: KERNEL_SCENES, KERNEL_RES, KERNEL_FLAGS (e.g.
  # --no-macro-bins); KERNEL_FILTER (an ncu regex, e.g. 'bin_lists|ranges') times only those kernels
  local skip=30  # launches of the first frames (a filter counts only its kernels' launches)
  [ -n "${KERNEL_FILTER:-}" ] && skip=6
  for scene in ${KERNEL_SCENES:-pc_playbot}; do
    for res in ${KERNEL_RES:-1920x1080 3840x2160}; do
      log "ncu kernel times $scene $res ${KERNEL_FLAGS:-} ${KERNEL_FILTER:-}"
      timeout 120 ncu --metrics gpu__time_duration.sum --cache-control none --clock-control none \
        ${KERNEL_FILTER:+-k regex:$KERNEL_FILTER} --launch-skip $skip \
        --launch-count 12 "$FLASHGS" render "$SCENES/$scene/point_cloud.ply" --backend cuda -c 10 -r "$res" \
        ${KERNEL_FLAGS:-} --repeat 8 -o /tmp/p.ppm > "$OUT/ncu_kernels_${scene}_$res.txt" 2>&1
      grep -E "^  [a-zA-Z_]|gpu__time_duration" "$OUT/ncu_kernels_${scene}_$res.txt" | cut -c1-90
    done
  done
}

profile_blend() {  # one kernel (PROFILE_KERNEL, an ncu regex; default the warp blend) in detail: speed of light,
  # stall reasons, instruction mix, occupancy, memory
  local kernel=${PROFILE_KERNEL:-blend_warp}
  local report=$OUT/ncu_${kernel//[^A-Za-z0-9_]/_}.txt
  log "ncu $kernel ${PROFILE_SCENE:-pc_playbot} ${PROFILE_RES:-1920x1080}"
  timeout 240 ncu --section SpeedOfLight --section WarpStateStats --section SchedulerStats --section InstructionStats \
    --section Occupancy --section LaunchStats --section MemoryWorkloadAnalysis -k regex:"$kernel" --launch-skip 3 \
    --launch-count 1 "$FLASHGS" render "$SCENES/${PROFILE_SCENE:-pc_playbot}/point_cloud.ply" --backend cuda -c 10 \
    -r "${PROFILE_RES:-1920x1080}" --repeat 5 -o /tmp/p.ppm > "$report" 2>&1
  log "ncu rc=$?"
  grep -vE "^==|^\s*$|----" "$report" | tail -90
}

profile_sass() {  # executed instructions per SASS line of PROFILE_KERNELS (binaries built with -lineinfo)
  for kernel in ${PROFILE_KERNELS:-blend_warp}; do
    log "ncu sass $kernel ${PROFILE_SCENE:-pc_playbot} ${PROFILE_RES:-3840x2160}"
    timeout 240 ncu --section SourceCounters --section InstructionStats -k regex:"$kernel" \
      --launch-skip 3 --launch-count 1 -f -o /tmp/sass_profile "$FLASHGS" render \
      "$SCENES/${PROFILE_SCENE:-pc_playbot}/point_cloud.ply" --backend cuda -c 10 -r "${PROFILE_RES:-3840x2160}" \
      --repeat 5 -o /tmp/p.ppm > "$OUT/ncu_sass_run_$kernel.txt" 2>&1
    log "ncu rc=$?"
    ncu --import /tmp/sass_profile.ncu-rep --page source --csv --print-source sass > "$OUT/sass_$kernel.csv" 2>&1
    log "sass lines: $(wc -l < "$OUT/sass_$kernel.csv")"
  done
}

FLASHGS=$BIN/flashgs
TESTS=$BIN/test_cuda_render
STRESS_TESTS=$BIN/test_stress_gpu
TEST_DIR=$ROOT/build-dev/tests
for step in "$@"; do
  case $step in
    setup) setup ;;
    build) build ;;
    build-bg) (build > /dev/null 2>&1) & BUILD_PID=$! ;;  # checks the build on the machine, in parallel
    wait-build) [ -n "${BUILD_PID:-}" ] && wait "$BUILD_PID"; log "$(tail -2 "$OUT/build.log" | tr '\n' ' ')" ;;
    tests) tests ;;
    sanitize) sanitize ;;
    bench-quick) bench_quick ;;
    bench-kernel) bench_kernel ;;
    parity-renders) parity_renders ;;
    bench-ab) bench_ab ;;
    bench-env) bench_env ;;
    bench) bench ;;
    bench-regions) bench_regions ;;
    bench-large) bench_large ;;
    bench-prev) (FLASHGS=$BIN/flashgs_prev TAG=prev_ bench_regions) ;;  # a carried earlier build, to compare
    bench-cpu) bench_cpu ;;
    build-prev) build_prev ;;
    bench-cpu-prev) (FLASHGS=/tmp/prev/b/app/flashgs TAG=prev_ bench_cpu) ;;
    build-prev-bg) (PREV_CUDA=1 build_prev > /dev/null 2>&1) & PREV_PID=$! ;;
    bench-prev-cuda) [ -n "${PREV_PID:-}" ] && wait "$PREV_PID"; (FLASHGS=/tmp/prev/b/app/flashgs bench_prev_cuda) ;;
    cpu-simd-tests) cpu_simd_tests ;;
    bench-scale) bench_scale ;;
    bench-variants) bench_variants ;;
    kernel-times) kernel_times ;;
    trace) trace ;;
    launch-cost) launch_cost ;;
    report) report ;;
    profile) profile ;;
    profile-kernels) profile_kernels ;;
    profile-blend) profile_blend ;;
    profile-sass) profile_sass ;;
    *) echo "unknown step $step" ;;
  esac
done
log "done"
# At most 8 files come back: everything but the summary goes into one archive, logs.tgz, with a
# folder per run of this script in the call (RUN_NAME, default the time), so that a later run's
# files of the same name (trace_SCENE.txt) do not replace an earlier run's. The runs' files wait
# in /tmp/flashgs_runs (outside $OUT: tar fails on an archive that grows inside the folder it reads).
run_dir=/tmp/flashgs_runs/$(date +%H%M%S)${RUN_NAME:+_$RUN_NAME}
mkdir -p "$run_dir"
(cd "$OUT" && find . -maxdepth 1 -type f ! -name summary.txt ! -name logs.tgz ! -name '*.ppm' -exec mv {} "$run_dir"/ \;
  find . -maxdepth 1 -type f -name '*.ppm' -delete
  tar czf /tmp/flashgs_logs.tgz -C /tmp/flashgs_runs . 2>/dev/null && mv /tmp/flashgs_logs.tgz logs.tgz)
