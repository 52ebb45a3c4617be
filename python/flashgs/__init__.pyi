# Type stubs of the flashgs package (the compiled flashgs._flashgs and render()).
from typing import Any, Dict, List, Literal, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float32]
ArrayLike = Any  # a numpy array, a torch tensor (CPU, or CUDA with __cuda_array_interface__), a list
Backend = Literal["auto", "cpu", "cuda"]
Output = Literal["numpy", "torch"]

__version__: str
has_cuda: bool  # whether this build has the CUDA backend

class Error(RuntimeError): ...

class SplatKernel:
    @staticmethod
    def classic() -> SplatKernel: ...
    @staticmethod
    def antialiased(epsilon: float = 0.3) -> SplatKernel: ...
    @staticmethod
    def parse(text: str) -> SplatKernel: ...
    @property
    def mode(self) -> Literal["classic", "antialiased"]: ...
    @property
    def epsilon(self) -> float: ...
    @property
    def spec(self) -> str: ...

class Scene:
    @staticmethod
    def from_arrays(means: ArrayLike, quats: ArrayLike, scales: ArrayLike, opacities: ArrayLike, sh: ArrayLike,
                    kernel: Union[None, str, SplatKernel] = None) -> Scene: ...
    def __len__(self) -> int: ...
    @property
    def sh_degree(self) -> int: ...
    @property
    def means(self) -> FloatArray: ...
    @property
    def quats(self) -> FloatArray: ...
    @property
    def scales(self) -> FloatArray: ...
    @property
    def opacities(self) -> FloatArray: ...
    @property
    def sh_dc(self) -> FloatArray: ...
    @property
    def sh_rest(self) -> FloatArray: ...
    @property
    def sh(self) -> FloatArray: ...
    @property
    def kernel(self) -> SplatKernel: ...
    @property
    def kernel_source(self) -> str: ...
    @property
    def load_report(self) -> Optional[Dict[str, Any]]: ...
    def save(self, path: str) -> None: ...

class Camera:
    @staticmethod
    def from_viewmat(viewmat: ArrayLike, K: ArrayLike, width: int, height: int, name: str = "") -> Camera: ...
    @staticmethod
    def look_at(eye: ArrayLike, target: ArrayLike, up: ArrayLike = ..., width: int = 1920, height: int = 1080,
                fov: float = 60.0) -> Camera: ...
    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    name: str
    @property
    def position(self) -> FloatArray: ...
    @property
    def rotation(self) -> FloatArray: ...
    @property
    def viewmat(self) -> FloatArray: ...
    @property
    def K(self) -> FloatArray: ...
    def resized(self, width: int, height: int) -> Camera: ...

class RenderOptions:
    def __init__(self, **options: Any) -> None: ...
    @staticmethod
    def names() -> List[str]: ...
    @staticmethod
    def switches() -> List[Dict[str, Any]]: ...
    @property
    def label(self) -> str: ...
    def replace(self, **options: Any) -> RenderOptions: ...
    algorithm: Literal["flash", "baseline"]
    kernel: Union[str, SplatKernel]
    tau: float
    background: Tuple[float, float, float]
    sh_degree: int
    # The switches of options.h's kRenderSwitches, by label; all on by default.
    opacity_radius: bool
    tight_bbox: bool
    exact_tile_test: bool
    warp_emit: bool
    fused_emit: bool
    sort_bits: bool
    macro_bins: bool
    dense_tiles_first: bool
    pipelined_blend: bool
    exp2_alpha: bool
    fp16_sh: bool
    fp16_shape: bool
    fp16_blend: bool
    collect_tile_counts: bool

class StageTimes:
    project_ms: float
    emit_ms: float
    sort_ms: float
    ranges_ms: float
    blend_ms: float
    total_ms: float
    sort_in_blend: bool
    def as_dict(self) -> Dict[str, float]: ...

class FrameStats:
    kv_pairs: int
    sorted_pairs: int
    tiles_x: int
    tiles_y: int
    @property
    def tile_pair_counts(self) -> Optional[npt.NDArray[np.uint32]]: ...
    max_tile_pairs: int
    gaussians: int
    visible: int
    culled_near: int
    culled_offscreen: int
    culled_low_opacity: int
    culled_degenerate: int
    culled_by_chunk: int
    times: StageTimes
    device_memory_bytes: int
    device_peak_bytes: int
    scene_device_bytes: int

Frame = Tuple[FloatArray, FrameStats]

class Renderer:
    def __init__(self, backend: Backend = "auto", threads: int = 0) -> None: ...
    @property
    def name(self) -> str: ...
    @overload
    def render(self, scene: Scene, camera: Camera, width: Optional[int] = None, height: Optional[int] = None,
               options: Optional[RenderOptions] = None, **switches: Any) -> Frame: ...
    @overload
    def render(self, scene: Scene, camera: Sequence[Camera], width: Optional[int] = None,
               height: Optional[int] = None, options: Optional[RenderOptions] = None,
               **switches: Any) -> List[Frame]: ...
    def render_into(self, scene: Scene, camera: Camera, out: Any, width: Optional[int] = None,
                    height: Optional[int] = None, options: Optional[RenderOptions] = None,
                    **switches: Any) -> FrameStats: ...
    @staticmethod
    def frame_size(camera: Camera, width: Optional[int] = None, height: Optional[int] = None) -> Tuple[int, int]: ...

def load_scene(path: str, lod: Optional[int] = None) -> Scene: ...
def load_cameras(path: str) -> List[Camera]: ...
@overload
def render(scene: Scene, camera: Camera, width: Optional[int] = None, height: Optional[int] = None,
           backend: Backend = "auto", options: Optional[RenderOptions] = None, output: Output = "numpy",
           **switches: Any) -> Tuple[Any, FrameStats]: ...
@overload
def render(scene: Scene, camera: Sequence[Camera], width: Optional[int] = None, height: Optional[int] = None,
           backend: Backend = "auto", options: Optional[RenderOptions] = None, output: Output = "numpy",
           **switches: Any) -> List[Tuple[Any, FrameStats]]: ...
