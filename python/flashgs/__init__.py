"""FlashGS from Python: load a 3D Gaussian Splatting scene, make cameras, render frames.

    import flashgs
    scene = flashgs.load_scene("scene/point_cloud.ply")
    cameras = flashgs.load_cameras("scene/cameras.json")
    image, stats = flashgs.render(scene, cameras[0])      # (H, W, 3) float32 numpy array

The compiled part (flashgs._flashgs) holds the scene, the cameras, the options and the
backends; this file adds `render`, which keeps one Renderer per backend.
"""

import threading

from ._flashgs import (  # noqa: F401  (the package's API)
    Camera,
    Error,
    __version__,
    FrameStats,
    Renderer,
    RenderOptions,
    Scene,
    SplatKernel,
    StageTimes,
    has_cuda,
    load_cameras,
    load_scene,
)

__all__ = [
    "Camera", "Error", "FrameStats", "Renderer", "RenderOptions", "Scene", "SplatKernel", "StageTimes",
    "has_cuda", "load_cameras", "load_scene", "render",
]

_renderers = {}
_renderers_lock = threading.Lock()


def _renderer(backend):
    """The Renderer kept for `backend`, made on first use (a CUDA backend keeps its uploaded scene)."""
    with _renderers_lock:
        if backend not in _renderers:
            _renderers[backend] = Renderer(backend)
        return _renderers[backend]


def render(scene, camera, width=None, height=None, backend="auto", options=None, output="numpy", **switches):
    """Renders `camera` (or each of a sequence of cameras) of `scene`.

    Returns (image, stats): the image an (H, W, 3) float32 array, row 0 at the top, and a
    FrameStats (pairs, culled counts, per-stage times in `stats.times`, per-tile pair counts with
    collect_tile_counts=True); a list of such pairs for a sequence of cameras. width/height
    resize the camera with its field of view kept (one alone keeps the aspect ratio). Keywords
    are RenderOptions (algorithm, kernel, tau, background, sh_degree, each switch, fp16_*) set on
    top of `options`. Bad values raise flashgs.Error with the CLI's one-line message.

    output: "numpy" (the image in host memory) or "torch": a torch tensor on the device the
    frame was rendered on; from the CUDA backend it never leaves the GPU (Renderer.render_into
    writes it into a tensor allocated on the current CUDA device).
    """
    if output not in ("numpy", "torch"):
        raise Error(f'output: expected "numpy" or "torch", got {output!r}')
    renderer = _renderer(backend)
    if output == "numpy":
        return renderer.render(scene, camera, width=width, height=height, options=options, **switches)
    import torch  # only for output="torch"

    def one(cam):
        if not renderer.name.startswith("cuda"):
            image, stats = renderer.render(scene, cam, width=width, height=height, options=options, **switches)
            return torch.from_numpy(image), stats
        w, h = Renderer.frame_size(cam, width, height)
        image = torch.empty((h, w, 3), dtype=torch.float32, device="cuda")
        stats = renderer.render_into(scene, cam, image, width=width, height=height, options=options, **switches)
        return image, stats

    if isinstance(camera, Camera):
        return one(camera)
    return [one(cam) for cam in camera]
