"""Bad input raises flashgs.Error (or TypeError for an unknown keyword) with the one line the CLI
prints, and the module keeps working after it."""

import numpy as np
import pytest

import flashgs
from support import DEMO_SCENE, error_line


def test_missing_scene_file_gives_the_cli_message(cli, tmp_path):
    path = tmp_path / "absent.ply"
    expected = error_line(cli("info", path, expect_ok=False).stderr)
    with pytest.raises(flashgs.Error) as raised:
        flashgs.load_scene(str(path))
    assert str(raised.value) == expected and str(path) in expected


def test_a_file_that_is_no_scene_gives_the_cli_message(cli, tmp_path):
    path = tmp_path / "notes.ply"
    path.write_bytes(b"hello\x01 world\n")
    expected = error_line(cli("info", path, expect_ok=False).stderr)
    with pytest.raises(flashgs.Error) as raised:
        flashgs.load_scene(str(path))
    assert str(raised.value) == expected and "not a scene file" in expected
    assert "\\x01" in expected  # file text escaped, as the CLI prints it


def test_bad_cameras_json_gives_the_cli_message(cli, tmp_path):
    path = tmp_path / "cameras.json"
    path.write_text('[{"width": 10, "height": 10, "fx": 5, "fy": 5, "position": [0, 0, 0], '
                    '"rotation": [[1, 0, 0], [0, 2, 0], [0, 0, 1]]}]')
    expected = error_line(cli("render", DEMO_SCENE, "--cameras", path, "-o", tmp_path / "x.pfm",
                              expect_ok=False).stderr)
    with pytest.raises(flashgs.Error) as raised:
        flashgs.load_cameras(str(path))
    assert str(raised.value) == expected and "not orthonormal" in expected


def test_an_unavailable_backend_gives_the_cli_message(cli, tmp_path):
    done = cli("render", "--backend", "cuda", "-r", "8x8", "-o", tmp_path / "x.pfm", expect_ok=False)
    if done.returncode == 0:
        pytest.skip("the CUDA backend works here")
    expected = error_line(done.stderr)
    with pytest.raises(flashgs.Error) as raised:
        flashgs.Renderer("cuda")
    assert str(raised.value) == expected


def test_bad_options_name_the_keyword(demo_scene, demo_cameras):
    cases = [
        ({"tau": 5}, "tau: 5 is outside [1e-06, 0.99]"),
        ({"tau": float("nan")}, "tau: nan is not a finite number"),
        ({"background": (0, 2, 0)}, "background: 2 is outside [0.0, 1.0]"),
        ({"sh_degree": 4}, "sh_degree: 4 is outside [0.0, 3.0]"),
        ({"tight_bbox": 0}, "tight_bbox: expected True or False, got 0"),
        ({"algorithm": "fast"}, "algorithm: expected \"flash\" or \"baseline\", got 'fast'"),
        ({"kernel": "antialiased=99"}, "kernel \"antialiased=99\""),
    ]
    for switches, message in cases:
        with pytest.raises(flashgs.Error) as raised:
            flashgs.render(demo_scene, demo_cameras[0], width=32, height=18, backend="cpu", **switches)
        assert str(raised.value).startswith(message), (switches, str(raised.value))
    with pytest.raises(TypeError, match="unknown render option 'tight_box'; the options are algorithm, kernel"):
        flashgs.RenderOptions(tight_box=False)
    image, _ = flashgs.render(demo_scene, demo_cameras[0], width=32, height=18, backend="cpu")
    assert image.shape == (18, 32, 3)


def test_bad_arrays_name_the_array_and_row():
    good = dict(means=np.zeros((3, 3)), quats=np.tile([1.0, 0, 0, 0], (3, 1)), scales=np.full((3, 3), 0.1),
                opacities=np.full(3, 0.5), sh=np.zeros((3, 1, 3)))
    cases = [
        ("means", np.array([[0, 0, 0], [0, np.nan, 0], [0, 0, 0]]), "means: row 1 holds nan; every value must be finite"),
        ("scales", np.array([[0.1] * 3, [0.1] * 3, [0.1, -1, 0.1]]), "scales: row 2 holds -1.000000; scales must be"),
        ("opacities", np.array([0.5, 1.5, 0.5]), "opacities: row 1 holds 1.500000; opacities must be in [0, 1]"),
        ("quats", np.array([[1.0, 0, 0, 0], [0, 0, 0, 0], [1, 0, 0, 0]]), "quats: row 1 has no direction"),
        ("quats", np.zeros((3, 3)), "quats: expected shape (3, 4), got (3, 3)"),
        ("sh", np.zeros((3, 5, 3)), "sh: expected shape (N, K, 3) with K = 1, 4, 9 or 16"),
        ("means", "a string", "means: expected an array of numbers"),
    ]
    for name, value, message in cases:
        with pytest.raises(flashgs.Error) as raised:
            flashgs.Scene.from_arrays(**{**good, name: value})
        assert str(raised.value).startswith(message), (name, str(raised.value))
    assert len(flashgs.Scene.from_arrays(**good)) == 3


def test_bad_cameras_and_sizes_are_refused(demo_scene, demo_cameras):
    with pytest.raises(flashgs.Error, match="viewmat: rotation is not orthonormal"):
        flashgs.Camera.from_viewmat(np.diag([2.0, 1, 1, 1]), np.eye(3), 10, 10)
    with pytest.raises(flashgs.Error, match="K: fx and fy"):
        flashgs.Camera.from_viewmat(np.eye(4), np.zeros((3, 3)), 10, 10)
    with pytest.raises(flashgs.Error, match=r"width and height must be whole numbers in 1..65536 \(got 0x10\)"):
        flashgs.Camera.look_at([0, 0, -1], [0, 0, 0], width=0, height=10)
    with pytest.raises(flashgs.Error, match="the eye is at the target"):
        flashgs.Camera.look_at([0, 0, 0], [0, 0, 0])
    with pytest.raises(flashgs.Error, match="width, height: 0x0 is not a size"):
        flashgs.render(demo_scene, demo_cameras[0], width=0, height=0, backend="cpu")
    with pytest.raises(flashgs.Error, match="backend: expected"):
        flashgs.Renderer("gpu")
