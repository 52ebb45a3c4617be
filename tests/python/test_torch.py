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


def test_torch_output_on_the_cpu_backend_is_the_numpy_image(demo_scene, demo_cameras):
    image, stats = flashgs.render(demo_scene, demo_cameras[1], width=160, backend="cpu", output="torch")
    expected, _ = flashgs.render(demo_scene, demo_cameras[1], width=160, backend="cpu")
    assert isinstance(image, torch.Tensor) and image.device.type == "cpu"
    assert np.array_equal(image.numpy(), expected) and stats.kv_pairs > 0


def cuda_or_skip():
    if not flashgs.has_cuda:
        pytest.skip("this build has no CUDA backend")
    if not torch.cuda.is_available():
        pytest.skip("torch sees no CUDA device")


def test_torch_output_stays_on_the_gpu_and_equals_the_host_image(demo_scene, demo_cameras):
    cuda_or_skip()
    for camera in (demo_cameras[0], demo_cameras[3]):
        on_gpu, stats = flashgs.render(demo_scene, camera, width=333, backend="cuda", output="torch")
        on_host, host_stats = flashgs.render(demo_scene, camera, width=333, backend="cuda")
        assert on_gpu.is_cuda and on_gpu.dtype == torch.float32 and on_gpu.shape == on_host.shape
        assert np.array_equal(on_gpu.cpu().numpy(), on_host)
        assert stats.kv_pairs == host_stats.kv_pairs and stats.times.total_ms > 0


def test_render_into_waits_for_the_work_queued_on_the_tensors_stream(demo_scene, demo_cameras):
    cuda_or_skip()
    camera = demo_cameras[2]
    w, h = flashgs.Renderer.frame_size(camera, width=401)
    expected, _ = flashgs.render(demo_scene, camera, width=401, backend="cuda")
    renderer = flashgs.Renderer("cuda")
    side = torch.cuda.Stream()
    with torch.cuda.stream(side):
        out = torch.zeros((h, w, 3), device="cuda")
        torch.cuda._sleep(50_000_000)  # the stream is busy well past the frame's start
        out.fill_(7.0)  # must land before the frame's copy, or the frame is overwritten
        renderer.render_into(demo_scene, camera, out, width=401)
    assert np.array_equal(out.cpu().numpy(), expected)
    with pytest.raises(flashgs.Error, match="out: a CUDA array must be contiguous float32"):
        renderer.render_into(demo_scene, camera, torch.zeros((w, h, 3), device="cuda").transpose(0, 1), width=401)
