"""The scene's and the camera's arrays through the module: views, round trips, gsplat's layout."""

import gc

import numpy as np
import pytest

import flashgs
from support import DEMO_SCENE


def test_scene_arrays_are_readonly_views_of_the_loaded_scene(demo_scene):
    n = len(demo_scene)
    assert n > 1000 and demo_scene.sh_degree == 1
    shapes = {"means": (n, 3), "quats": (n, 4), "scales": (n, 3), "opacities": (n,), "sh_dc": (n, 3),
              "sh_rest": (n, 3, 3), "sh": (n, 4, 3)}
    for name, shape in shapes.items():
        array = getattr(demo_scene, name)
        assert array.shape == shape and array.dtype == np.float32, name
        assert np.isfinite(array).all(), name
    # Views: the same memory each time, never written.
    assert np.shares_memory(demo_scene.means, demo_scene.means)
    with pytest.raises(ValueError):
        demo_scene.means[0, 0] = 1.0
    assert np.allclose(np.linalg.norm(demo_scene.quats, axis=1), 1.0, atol=1e-6)
    assert (demo_scene.opacities >= 0).all() and (demo_scene.opacities <= 1).all()
    assert (demo_scene.scales > 0).all()
    np.testing.assert_array_equal(demo_scene.sh[:, 0], demo_scene.sh_dc)
    np.testing.assert_array_equal(demo_scene.sh[:, 1:], demo_scene.sh_rest)


def test_a_view_keeps_its_scene_alive():
    scene = flashgs.load_scene(str(DEMO_SCENE))
    expected = np.array(scene.means)
    means = scene.means
    del scene
    gc.collect()
    np.testing.assert_array_equal(means, expected)


def test_from_arrays_round_trips_a_loaded_scene_and_renders_the_same(demo_scene, demo_cameras):
    copy = flashgs.Scene.from_arrays(demo_scene.means, demo_scene.quats, demo_scene.scales, demo_scene.opacities,
                                     demo_scene.sh)
    for name in ("means", "quats", "scales", "opacities", "sh_dc", "sh_rest", "sh"):
        np.testing.assert_array_equal(getattr(copy, name), getattr(demo_scene, name), err_msg=name)
    assert copy.sh_degree == demo_scene.sh_degree and copy.load_report is None
    a, _ = flashgs.render(demo_scene, demo_cameras[3], width=160, height=90, backend="cpu")
    b, _ = flashgs.render(copy, demo_cameras[3], width=160, height=90, backend="cpu")
    assert np.array_equal(a.view(np.uint32), b.view(np.uint32))


def test_from_arrays_takes_float64_lists_and_dc_only_colours():
    scene = flashgs.Scene.from_arrays(means=[[0.0, 0.0, 2.0], [0.5, 0.0, 3.0]],
                                      quats=np.array([[2.0, 0, 0, 0], [0, 0, 0, 1.0]]),
                                      scales=np.full((2, 3), 0.1), opacities=[[0.5], [0.9]],
                                      sh=np.zeros((2, 3)), kernel="antialiased=0.1")
    assert len(scene) == 2 and scene.sh_degree == 0 and scene.sh_rest.shape == (2, 0, 3)
    np.testing.assert_array_equal(scene.quats[0], [1, 0, 0, 0])  # normalised
    np.testing.assert_array_equal(scene.opacities, np.float32([0.5, 0.9]))
    assert scene.kernel == flashgs.SplatKernel.antialiased(0.1) and scene.kernel_source


def test_save_and_load_round_trip(tmp_path, demo_scene):
    path = tmp_path / "copy.ply"
    demo_scene.save(str(path))
    back = flashgs.load_scene(str(path))
    assert back.load_report["format"] == "INRIA PLY"
    np.testing.assert_array_equal(back.means, demo_scene.means)
    np.testing.assert_array_equal(back.sh, demo_scene.sh)
    # The file keeps log scales and logit opacities: the activations round to within float steps.
    np.testing.assert_allclose(back.scales, demo_scene.scales, rtol=1e-6)
    np.testing.assert_allclose(back.opacities, demo_scene.opacities, rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(back.quats, demo_scene.quats, atol=1e-7)


def test_camera_viewmat_and_K_round_trip(demo_cameras):
    camera = demo_cameras[7]
    again = flashgs.Camera.from_viewmat(camera.viewmat, camera.K, camera.width, camera.height)
    for name in ("width", "height", "fx", "fy", "cx", "cy"):
        assert getattr(again, name) == getattr(camera, name), name
    np.testing.assert_array_equal(again.rotation, camera.rotation)
    np.testing.assert_allclose(again.position, camera.position, rtol=1e-6, atol=1e-6)
    viewmat = camera.viewmat
    np.testing.assert_array_equal(viewmat[3], [0, 0, 0, 1])
    np.testing.assert_allclose(viewmat[:3, :3] @ camera.position + viewmat[:3, 3], 0, atol=1e-5)


def test_gsplat_intrinsics_put_a_gaussian_on_the_pixel_they_project_it_to():
    # One small Gaussian off the axis; gsplat's K (pixel centres at +0.5) says where it lands.
    point = np.array([0.3, -0.2, 0.0])
    scene = flashgs.Scene.from_arrays([point], [[1, 0, 0, 0]], [[0.004] * 3], [1.0], [[[3.0, 3.0, 3.0]]])
    camera = flashgs.Camera.look_at(eye=[0, 0, -4], target=[0, 0, 0], width=101, height=80, fov=40)
    projected = camera.K @ (camera.viewmat @ np.append(point, 1.0))[:3]
    u, v = projected[:2] / projected[2]
    image, _ = flashgs.render(scene, camera, backend="cpu")
    y, x = np.unravel_index(np.argmax(image[..., 0]), image.shape[:2])
    assert (x, y) == (int(np.floor(u)), int(np.floor(v)))


def test_batched_cameras_equal_single_frames(demo_scene, demo_cameras):
    frames = flashgs.render(demo_scene, demo_cameras[:3], width=96, height=54, backend="cpu")
    assert len(frames) == 3
    for camera, (image, stats) in zip(demo_cameras[:3], frames):
        single, single_stats = flashgs.render(demo_scene, camera, width=96, height=54, backend="cpu")
        assert np.array_equal(image, single) and stats.kv_pairs == single_stats.kv_pairs


def test_stats_hold_pairs_stage_times_and_tile_counts(demo_scene, demo_cameras):
    image, stats = flashgs.render(demo_scene, demo_cameras[0], width=320, height=180, backend="cpu",
                                  collect_tile_counts=True)
    assert image.shape == (180, 320, 3) and image.dtype == np.float32
    counts = stats.tile_pair_counts
    assert counts.shape == (stats.tiles_y, stats.tiles_x) == (12, 20)
    assert counts.sum() == stats.kv_pairs > 0 and counts.max() == stats.max_tile_pairs
    assert stats.gaussians == len(demo_scene) and 0 < stats.visible <= stats.gaussians
    times = stats.times.as_dict()
    assert set(times) == {"project", "emit", "sort", "ranges", "blend", "total"}
    assert all(t >= 0 for t in times.values()) and times["total"] > 0
    _, plain = flashgs.render(demo_scene, demo_cameras[0], width=320, height=180, backend="cpu")
    assert plain.tile_pair_counts is None


def test_options_hold_every_switch_of_the_table():
    switches = flashgs.RenderOptions.switches()
    assert len(switches) >= 10
    options = flashgs.RenderOptions()
    for switch in switches:
        assert getattr(options, switch["name"]) is True
        changed = options.replace(**{switch["name"]: False})
        assert getattr(changed, switch["name"]) is False and changed.label == "flash-no_" + switch["name"]
    assert flashgs.RenderOptions(algorithm="baseline").label == "baseline"
    assert flashgs.RenderOptions(kernel="antialiased").kernel == flashgs.SplatKernel.antialiased()
    assert flashgs.RenderOptions().kernel == "auto"


def test_type_stubs_name_every_option():
    import pathlib
    stub = (pathlib.Path(flashgs.__file__).parent / "__init__.pyi").read_text()
    for name in flashgs.RenderOptions.names():
        assert f"    {name}: " in stub, f"__init__.pyi lacks RenderOptions.{name}"


class FakeCudaArray:
    """An object that says it lives on a CUDA device at an address no device has."""

    def __init__(self, shape, typestr="<f4", strides=None):
        self.__cuda_array_interface__ = {"shape": shape, "typestr": typestr, "data": (0x10, False),
                                         "strides": strides, "version": 3}


def test_cuda_arrays_are_read_through_their_interface():
    good = dict(means=np.zeros((2, 3)), quats=np.tile([1.0, 0, 0, 0], (2, 1)), scales=np.full((2, 3), 0.1),
                opacities=np.full(2, 0.5), sh=np.zeros((2, 1, 3)))
    with pytest.raises(flashgs.Error, match=r"means: a CUDA array must be contiguous float32 \(it is <f8;"):
        flashgs.Scene.from_arrays(**{**good, "means": FakeCudaArray((2, 3), "<f8")})
    with pytest.raises(flashgs.Error, match=r"means: .*strided"):
        flashgs.Scene.from_arrays(**{**good, "means": FakeCudaArray((2, 3), strides=(24, 4))})
    # A well-formed one reaches the copy, which fails without a device (or without CUDA in the build).
    expected = "means: cannot copy the CUDA array" if flashgs.has_cuda else "means: a CUDA array, but this build"
    with pytest.raises(flashgs.Error, match=expected):
        flashgs.Scene.from_arrays(**{**good, "means": FakeCudaArray((2, 3), strides=(12, 4))})


def test_render_into_checks_the_array_before_the_backend(demo_scene, demo_cameras):
    camera = demo_cameras[0]
    w, h = flashgs.Renderer.frame_size(camera, width=64)
    image, _ = flashgs.render(demo_scene, camera, width=64, backend="cpu")
    assert image.shape == (h, w, 3)  # frame_size is the size render() makes
    cpu = flashgs.Renderer("cpu")
    with pytest.raises(flashgs.Error, match=r"out: expected a CUDA array \(e.g. a torch tensor on the GPU\), got ndarray"):
        cpu.render_into(demo_scene, camera, np.zeros((h, w, 3), np.float32), width=64)
    with pytest.raises(flashgs.Error, match=rf"out: expected shape \({h}, {w}, 3\) for the frame, got \(2, 3\)"):
        cpu.render_into(demo_scene, camera, FakeCudaArray((2, 3)), width=64)
    read_only = FakeCudaArray((h, w, 3))
    read_only.__cuda_array_interface__["data"] = (0x10, True)
    with pytest.raises(flashgs.Error, match="out: the CUDA array is read-only"):
        cpu.render_into(demo_scene, camera, read_only, width=64)
    with pytest.raises(flashgs.Error, match=r'out: the cpu .*backend renders into host memory; a CUDA array needs backend="cuda"'):
        cpu.render_into(demo_scene, camera, FakeCudaArray((h, w, 3)), width=64)
    with pytest.raises(flashgs.Error, match='output: expected "numpy" or "torch", got \'cupy\''):
        flashgs.render(demo_scene, camera, backend="cpu", output="cupy")
