"""torch tensors into Scene.from_arrays: CPU tensors as numpy sees them, CUDA tensors (through
__cuda_array_interface__) where this build has the CUDA backend and a device."""

import numpy as np
import pytest

import flashgs

torch = pytest.importorskip("torch")


def tensors_of(scene, device):
    return [torch.from_numpy(np.array(getattr(scene, name))).to(device)
            for name in ("means", "quats", "scales", "opacities", "sh")]


def assert_same_scene(a, b):
    for name in ("means", "quats", "scales", "opacities", "sh"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


def test_cpu_tensors(demo_scene):
    assert_same_scene(flashgs.Scene.from_arrays(*tensors_of(demo_scene, "cpu")), demo_scene)


def test_a_tensor_that_requires_grad_is_named():
    means = torch.zeros((1, 3), requires_grad=True)
    with pytest.raises(flashgs.Error, match="means: expected an array of numbers"):
        flashgs.Scene.from_arrays(means, [[1, 0, 0, 0]], [[1, 1, 1]], [1], [[0, 0, 0]])


@pytest.mark.skipif(not flashgs.has_cuda, reason="this build has no CUDA backend")
def test_cuda_tensors_render_as_their_host_copies(demo_scene, demo_cameras):
    if not torch.cuda.is_available():
        pytest.skip("torch sees no CUDA device")
    scene = flashgs.Scene.from_arrays(*tensors_of(demo_scene, "cuda"))
    assert_same_scene(scene, demo_scene)
    a, _ = flashgs.render(scene, demo_cameras[2], width=320, height=180, backend="cuda")
    b, _ = flashgs.render(demo_scene, demo_cameras[2], width=320, height=180, backend="cuda")
    assert np.array_equal(a, b)
    strided = torch.zeros((4, 6), device="cuda")[:, :3]
    with pytest.raises(flashgs.Error, match="means: a CUDA array must be contiguous float32"):
        flashgs.Scene.from_arrays(strided, *tensors_of(demo_scene, "cuda")[1:])
