"""Helpers of the Python module's tests: where the scenes are, a PFM reader, the CLI's error line."""

import os
import pathlib

import numpy as np
import pytest

REPOSITORY = pathlib.Path(__file__).resolve().parents[2]
DEMO_SCENE = REPOSITORY / "assets" / "demo" / "point_cloud.ply"
DEMO_CAMERAS = REPOSITORY / "assets" / "demo" / "cameras.json"


def shared_scene(name):
    """A folder of ../shared/scenes (FLASHGS_SHARED_SCENES), or a skip where it is absent."""
    root = pathlib.Path(os.environ.get("FLASHGS_SHARED_SCENES", REPOSITORY.parent / "shared" / "scenes"))
    if not (root / name).exists():
        pytest.skip(f"{root / name} is absent (the real scenes live in ../shared/scenes)")
    return root / name


def read_pfm(path):
    """A PFM file as an (H, W, 3) float32 array, row 0 at the top."""
    data = pathlib.Path(path).read_bytes()
    fields = data.split(b"\n", 3)
    assert fields[0] == b"PF", f"{path}: not a colour PFM"
    width, height = map(int, fields[1].split())
    scale = float(fields[2])
    pixels = np.frombuffer(fields[3], dtype="<f4" if scale < 0 else ">f4", count=width * height * 3)
    return pixels.reshape(height, width, 3)[::-1].astype(np.float32)


def error_line(stderr):
    """The message of the CLI's `error: ...` line."""
    lines = [line for line in stderr.splitlines() if line.startswith("error: ")]
    assert len(lines) == 1, f"expected one error line, got:\n{stderr}"
    return lines[0][len("error: "):]
