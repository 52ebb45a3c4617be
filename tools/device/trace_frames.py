#!/usr/bin/env python3
"""Frames of a gpu_trace.cpp timeline: per flash frame (the counter reset to the blend's end) the
span, the time in kernels, memsets and copies, and what is left (the GPU idle); the latency, from
the host's call that starts the frame's GPU work (the reset's cudaMemsetAsync, or the capture of
the project stage's graph) to the blend's end, which host time moved out of the span still counts
in; then the last frame op by op with the gap after each. Usage: trace_frames.py TRACE..."""
import bisect
import re
import statistics
import sys

FRAME_START_CALLS = ("cudaStreamBeginCapture", "cudaMemsetAsync")


def short(name):
    match = re.search(r"\d+([a-z_]+_kernel)", name) or re.search(r"(Onesweep|Histogram|ExclusiveSum)\w*?Kernel", name)
    return match.group(1) if match and match.lastindex else (match.group(0) if match else name[:40])


def read(path):
    ops, calls = [], []
    for line in open(path):
        kind, start, end, name = (line.rstrip("\n").split(None, 3) + [""])[:4]
        if kind == "api":
            calls.append((int(start), name))
        else:
            ops.append((int(start), int(end), short(name) if kind == "kernel" else kind + " " + name))
    ops.sort()
    calls.sort()
    return ops, calls


def frames(ops):
    found, current = [], None
    for i, op in enumerate(ops):
        # A frame starts with the counters' reset, a memset right before its first kernel.
        if op[2].startswith(("preprocess_kernel", "chunk_list_kernel")) and i > 0 and ops[i - 1][2].startswith("memset"):
            current = [ops[i - 1], op]
        elif current is not None:
            current.append(op)
            if op[2].startswith("blend_"):
                found.append(current)
                current = None
    return found


def frame_start_call(calls, frame):
    """The start of the host call that queued the frame's reset: the last capture begun before
    the reset ran, else the last memset call before it."""
    end = bisect.bisect_left(calls, (frame[0][0], ""))
    recent = calls[max(0, end - 64):end]  # the frame's own calls are the last few before its reset
    for prefix in FRAME_START_CALLS:
        for start, name in reversed(recent):
            if name.startswith(prefix):
                return start
    return None


for path in sys.argv[1:]:
    ops, calls = read(path)
    flash = [f for f in frames(ops) if any(op[2].startswith("blend_warp") for op in f)][-10:]
    if not flash:
        print(path, "no flash frames")
        continue
    span = statistics.median((f[-1][1] - f[0][0]) / 1000 for f in flash)
    busy = statistics.median(sum(op[1] - op[0] for op in f) / 1000 for f in flash)
    starts = [frame_start_call(calls, f) for f in flash]
    latency = [(f[-1][1] - s) / 1000 for f, s in zip(flash, starts) if s is not None]
    shown = f", latency {statistics.median(latency):.1f}" if latency else ""
    print(f"{path}: {len(flash)} frames, median span {span:.1f} us, busy {busy:.1f}, idle {span - busy:.1f}{shown}")
    last = flash[-1]
    for i, op in enumerate(last):
        gap = (last[i + 1][0] - op[1]) / 1000 if i + 1 < len(last) else 0.0
        print(f"  {op[2]:<30} {(op[1] - op[0]) / 1000:7.1f} us, then idle {gap:5.1f}")
