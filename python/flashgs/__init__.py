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


def render(scene, camera, width=None, height=None, backend="auto", options=None, **switches):
    """Renders `camera` (or each of a sequence of cameras) of `scene`.

    Returns (image, stats): the image an (H, W, 3) float32 numpy array, row 0 at the top, and a
    FrameStats (pairs, culled counts, per-stage times in `stats.times`, per-tile pair counts with
    collect_tile_counts=True); a list of such pairs for a sequence of cameras. width/height
    resize the camera with its field of view kept (one alone keeps the aspect ratio). Keywords
    are RenderOptions (algorithm, kernel, tau, background, sh_degree, each switch, fp16_*) set on
    top of `options`. Bad values raise flashgs.Error with the CLI's one-line message.
    """
    return _renderer(backend).render(scene, camera, width=width, height=height, options=options, **switches)
