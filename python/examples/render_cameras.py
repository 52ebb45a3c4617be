"""Renders a scene's cameras with flash and with the 3DGS baseline and prints, per camera, the
pairs, the frame times and the PSNR of flash against the baseline.

    PYTHONPATH=build/python python3 python/examples/render_cameras.py ../shared/scenes/pc_biker --every 6
"""

import argparse
import math
import pathlib
import time

import numpy as np

import flashgs


def psnr(a, b):
    """PSNR in dB of two images with values in [0, 1] (clamped as they would be displayed)."""
    mse = float(np.mean((np.clip(a, 0, 1) - np.clip(b, 0, 1)) ** 2, dtype=np.float64))
    return math.inf if mse == 0 else 10 * math.log10(1.0 / mse)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scene", help="a scene file or folder (its cameras.json is used)")
    parser.add_argument("--cameras", help="cameras.json (default: the one in the scene's folder)")
    parser.add_argument("--every", type=int, default=1, help="render every Nth camera")
    parser.add_argument("--width", type=int, help="render width (height follows the aspect ratio)")
    parser.add_argument("--backend", default="auto", choices=["auto", "cpu", "cuda"])
    args = parser.parse_args()

    scene = flashgs.load_scene(args.scene)
    folder = pathlib.Path(args.scene)
    cameras_path = args.cameras or str((folder if folder.is_dir() else folder.parent) / "cameras.json")
    cameras = flashgs.load_cameras(cameras_path)[:: max(args.every, 1)]
    renderer = flashgs.Renderer(args.backend)
    print(f"{args.scene}: {len(scene)} Gaussians, SH degree {scene.sh_degree}, kernel {scene.kernel}, "
          f"{len(cameras)} cameras on {renderer.name}")

    scores = []
    for camera in cameras:
        began = time.perf_counter()
        flash, stats = renderer.render(scene, camera, width=args.width)
        flash_s = time.perf_counter() - began
        began = time.perf_counter()
        base, base_stats = renderer.render(scene, camera, width=args.width, algorithm="baseline")
        base_s = time.perf_counter() - began
        scores.append(psnr(flash, base))
        print(f"{camera.name:>12} {flash.shape[1]}x{flash.shape[0]}  pairs {stats.kv_pairs:>9} vs "
              f"{base_stats.kv_pairs:>9}  flash {flash_s * 1e3:8.2f} ms (stages {stats.times.total_ms:7.2f})  "
              f"baseline {base_s * 1e3:8.2f} ms  PSNR {scores[-1]:6.2f} dB")
    finite = [s for s in scores if math.isfinite(s)]
    print(f"PSNR flash vs baseline: mean {np.mean(finite) if finite else math.inf:.2f} dB, "
          f"worst {min(scores):.2f} dB over {len(scores)} cameras")


if __name__ == "__main__":
    main()
