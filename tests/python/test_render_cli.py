"""flashgs.render against `flashgs render`: the same scene, camera and options give the same float
image, bit for bit (the CLI's PFM), and the same pair count."""

import re

import numpy as np
import pytest

import flashgs
from support import DEMO_SCENE, read_pfm, shared_scene

# (CLI flags, the same as render() keywords)
CASES = [
    ([], {}),
    (["-a", "baseline"], {"algorithm": "baseline"}),
    (["--kernel", "antialiased=0.1", "--no-tight-bbox"], {"kernel": "antialiased=0.1", "tight_bbox": False}),
    (["--no-opacity-radius", "--no-exact-tile-test", "--tau", "0.02"],
     {"opacity_radius": False, "exact_tile_test": False, "tau": 0.02}),
    (["--background", "0.2,0.4,1", "--sh-degree", "0", "--fp16-sh", "--fp16-shape"],
     {"background": (0.2, 0.4, 1.0), "sh_degree": 0, "fp16_sh": True, "fp16_shape": True}),
]


def cli_frame(cli, tmp_path, scene_path, camera, size, flags):
    output = tmp_path / "cli.pfm"
    done = cli("render", scene_path, "-c", camera, "-r", size, "--backend", "cpu", *flags, "-o", output)
    pairs = int(re.search(r"^kv pairs:\s+(\d+)", done.stdout, re.M).group(1))
    return read_pfm(output), pairs


def assert_same_bits(a, b):
    assert a.shape == b.shape
    different = a.view(np.uint32) != b.view(np.uint32)
    assert not different.any(), f"{different.any(axis=2).sum()} pixels differ, largest {np.abs(a - b).max()}"


@pytest.mark.parametrize("flags,switches", CASES, ids=[" ".join(c[0]) or "flash" for c in CASES])
def test_demo_scene_equals_the_cli(cli, tmp_path, demo_scene, demo_cameras, flags, switches):
    expected, pairs = cli_frame(cli, tmp_path, DEMO_SCENE, 4, "320x180", flags)
    image, stats = flashgs.render(demo_scene, demo_cameras[4], width=320, height=180, backend="cpu", **switches)
    assert_same_bits(image, expected)
    assert stats.kv_pairs == pairs


@pytest.mark.parametrize("name", ["pc_biker", "kacytran_try", "formats/biker.spz", "formats/playbot_sog"])
def test_real_scenes_equal_the_cli(cli, tmp_path, name):
    path = shared_scene(name)
    cameras_path = shared_scene("pc_playbot" if "playbot" in name else "pc_biker" if "biker" in name else name)
    flags = [] if "/" not in name else ["--cameras", cameras_path / "cameras.json"]
    output = tmp_path / "cli.pfm"
    cli("render", path, "-c", 5, "-r", "480x270", "--backend", "cpu", *flags, "-o", output)
    cameras = flashgs.load_cameras(str(cameras_path / "cameras.json"))
    image, _ = flashgs.render(flashgs.load_scene(str(path)), cameras[5], width=480, height=270, backend="cpu")
    assert_same_bits(image, read_pfm(output))


def test_explicit_camera_equals_the_cli(cli, tmp_path, demo_scene):
    output = tmp_path / "cli.pfm"
    cli("render", DEMO_SCENE, "--eye", "0.5,-1.5,-3", "--look-at", "0,0,0.2", "--fov", "50", "-r", "200x150",
        "--backend", "cpu", "-o", output)
    camera = flashgs.Camera.look_at(eye=[0.5, -1.5, -3], target=[0, 0, 0.2], width=200, height=150, fov=50)
    image, _ = flashgs.render(demo_scene, camera, backend="cpu")
    assert_same_bits(image, read_pfm(output))


def test_the_gil_is_released_while_rendering(demo_scene, demo_cameras):
    # With a switch interval of minutes, this thread runs while the render thread holds the GIL
    # only if the render lets it go: `done` is then still False when it looks.
    import sys
    import threading

    started, done = threading.Event(), []
    renderer = flashgs.Renderer("cpu")

    def render():
        started.set()
        renderer.render(demo_scene, demo_cameras[0], width=1280, height=720)
        done.append(True)

    interval = sys.getswitchinterval()
    sys.setswitchinterval(600)
    try:
        worker = threading.Thread(target=render)
        worker.start()
        started.wait()
        seen_done = bool(done)
    finally:
        sys.setswitchinterval(interval)
    worker.join()
    assert not seen_done and done
