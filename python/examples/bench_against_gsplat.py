"""Times flashgs.render from Python against the stage times the renderer itself measures (what
`flashgs bench` sums), and, where gsplat and a CUDA device are present, against gsplat's
`rasterization` called the same way from this script on the same frames: time per frame and the
PSNR of the two images.

    PYTHONPATH=build/python python3 python/examples/bench_against_gsplat.py ../shared/scenes/pc_biker --every 2
"""

import argparse
import math
import pathlib
import statistics
import time

import numpy as np

import flashgs


def psnr(a, b):
    mse = float(np.mean((np.clip(a, 0, 1) - np.clip(b, 0, 1)) ** 2, dtype=np.float64))
    return math.inf if mse == 0 else 10 * math.log10(1.0 / mse)


def timed(function, repeats):
    """The result of function() and the median of `repeats` wall-clock times in ms (after one warm-up)."""
    result = function()
    times = []
    for _ in range(repeats):
        began = time.perf_counter()
        result = function()
        times.append((time.perf_counter() - began) * 1e3)
    return result, statistics.median(times)


def gsplat_renderer(scene):
    """A function camera -> (image, ms) through gsplat on the GPU, or None where it cannot run."""
    try:
        import torch
        from gsplat import rasterization
    except ImportError as missing:
        print(f"gsplat side by side skipped: {missing}")
        return None
    if not torch.cuda.is_available():
        print("gsplat side by side skipped: torch sees no CUDA device")
        return None
    device = torch.device("cuda")
    tensors = {name: torch.from_numpy(np.array(getattr(scene, name))).to(device)
               for name in ("means", "quats", "scales", "opacities", "sh")}
    mode = scene.kernel.mode

    def render(camera):
        viewmat = torch.from_numpy(camera.viewmat).to(device)[None]
        K = torch.from_numpy(camera.K).to(device)[None]

        def once():
            colors, _, _ = rasterization(tensors["means"], tensors["quats"], tensors["scales"], tensors["opacities"],
                                         tensors["sh"], viewmat, K, camera.width, camera.height,
                                         sh_degree=scene.sh_degree, near_plane=0.2, eps2d=scene.kernel.epsilon,
                                         rasterize_mode=mode)
            torch.cuda.synchronize()
            return colors

        colors, ms = timed(once, 10)
        return colors[0].float().cpu().numpy(), ms

    return render


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scene")
    parser.add_argument("--cameras", help="cameras.json (default: the one in the scene's folder)")
    parser.add_argument("--every", type=int, default=2, help="use every Nth camera")
    parser.add_argument("--backend", default="auto", choices=["auto", "cpu", "cuda"])
    parser.add_argument("--repeats", type=int, default=10, help="timed calls per camera (the median is shown)")
    args = parser.parse_args()

    scene = flashgs.load_scene(args.scene)
    folder = pathlib.Path(args.scene)
    cameras_path = args.cameras or str((folder if folder.is_dir() else folder.parent) / "cameras.json")
    cameras = flashgs.load_cameras(cameras_path)[:: max(args.every, 1)]
    renderer = flashgs.Renderer(args.backend)
    gsplat = gsplat_renderer(scene) if renderer.name.startswith("cuda") else None
    print(f"{args.scene}: {len(scene)} Gaussians on {renderer.name}, {len(cameras)} cameras, kernel {scene.kernel}")
    calls, stages, gsplat_ms, scores = [], [], [], []
    for camera in cameras:
        (image, stats), call_ms = timed(lambda: renderer.render(scene, camera), args.repeats)
        calls.append(call_ms)
        stages.append(stats.times.total_ms)
        line = f"{camera.name:>18}  python call {call_ms:8.3f} ms  stages {stats.times.total_ms:8.3f} ms"
        if gsplat:
            theirs, ms = gsplat(camera)
            gsplat_ms.append(ms)
            scores.append(psnr(image, theirs))
            line += f"  gsplat {ms:8.3f} ms  PSNR {scores[-1]:6.2f} dB"
        print(line)
    print(f"median over cameras: python call {statistics.median(calls):.3f} ms, stage sum "
          f"{statistics.median(stages):.3f} ms (the call adds the host copy of the image and the binding)")
    if gsplat:
        finite = [s for s in scores if math.isfinite(s)] or [math.inf]
        print(f"gsplat: {statistics.median(gsplat_ms):.3f} ms median; PSNR mean {statistics.mean(finite):.2f} dB, "
              f"worst {min(scores):.2f} dB")


if __name__ == "__main__":
    main()
