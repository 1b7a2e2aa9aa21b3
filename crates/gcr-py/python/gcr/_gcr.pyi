"""Type stubs of the extension module ``gcr._gcr`` (re-exported by ``gcr``).

The docstrings of the compiled objects (``help(gcr.solve)``) say what every argument means;
these stubs give the types.
"""

import os
from collections.abc import Callable, Sequence
from typing import Any, Literal, TypedDict

import numpy as np
import numpy.typing as npt

__version__: str

class GcrError(Exception):
    """An error gcr reports, with the program's message."""

class GcrWarning(UserWarning):
    """A warning gcr reports (the program's ``warning: …`` lines)."""

class Progress(TypedDict):
    """What a ``progress`` callback gets (keys that do not apply are None)."""

    stage: Literal["solve", "gather"]
    phase: str
    elapsed: float
    points: int | None
    rays: int | None
    error: float | None
    target: float | None
    done: float | None
    eta: float | None
    kernel_cells: int | None
    kernel_budget: int | None
    shading_cells: int | None
    samples: int | None
    fem_steps: int | None

ProgressCallback = Callable[[Progress], object]
ArrayLike = npt.ArrayLike
Numbers = str | Sequence[float] | Sequence[Sequence[float]]
View = (
    tuple[str | os.PathLike[str], Sequence[float], Sequence[float]]
    | tuple[str | os.PathLike[str], Sequence[float], Sequence[float], Sequence[float]]
    | tuple[str | os.PathLike[str], Sequence[float], Sequence[float], Sequence[float], float]
)
Values = tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]

def builtin_scenes() -> list[str]: ...

class Scene:
    @staticmethod
    def load(
        scene: str | os.PathLike[str],
        *,
        allow_outside_files: bool = False,
        max_file_mib: int | None = None,
        max_texture_mib: int | None = None,
        single_sided: bool = False,
        sun: Numbers | None = None,
        sky: str | None = None,
        env: str | os.PathLike[str] | None = None,
        ground_reflectance: float | None = None,
        up: Literal["y", "z"] | None = None,
        portals: Sequence[Numbers] = (),
        auto_portals: bool = False,
        point_lights: Sequence[Numbers] = (),
        spot_lights: Sequence[Numbers] = (),
        lights: str | os.PathLike[str] | None = None,
    ) -> Scene: ...
    @property
    def name(self) -> str: ...
    @property
    def dim(self) -> int: ...
    @property
    def bands(self) -> int: ...
    @property
    def faces(self) -> int: ...
    @property
    def found_portals(self) -> list[list[list[float]]]: ...

def solve(
    scene: Scene,
    *,
    quality: Literal["draft", "good", "final"] | None = None,
    target_error: float | None = None,
    seed: int | None = None,
    cells: int | None = None,
    shading_cells: int | None = None,
    time_budget: float | None = None,
    gather: Literal["paths", "rays", "kernel", "base"] | None = None,
    output_fit: Literal["projection", "delta-rule"] | None = None,
    network_target: Literal["clamped-kernel", "kernel-value", "sample-weight"] | None = None,
    gather_rays: int | None = None,
    corrections: int | None = None,
    share_paths: int | None = None,
    guiding: str | None = None,
    block_points: int | None = None,
    keep_base: bool = False,
    keep_networks: bool = False,
    kernel_facing: bool = False,
    cluster_min_elements: int | None = None,
    cluster_theta: float | None = None,
    progress: ProgressCallback | None = None,
) -> Solution: ...

class Solution:
    def radiosity(
        self,
        points: ArrayLike,
        normals: ArrayLike,
        *,
        tolerance: float | None = None,
        progress: ProgressCallback | None = None,
    ) -> Values: ...
    def irradiance(
        self, points: ArrayLike, normals: ArrayLike, *, progress: ProgressCallback | None = None
    ) -> Values: ...
    def shard_values(
        self,
        points: ArrayLike,
        normals: ArrayLike,
        *,
        shard: tuple[int, int],
        quantity: Literal["radiosity", "irradiance", "daylight-factor"] = "radiosity",
        tolerance: float | None = None,
        progress: ProgressCallback | None = None,
    ) -> tuple[npt.NDArray[np.uintp], npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...
    def daylight_factor(
        self, points: ArrayLike, normals: ArrayLike, *, progress: ProgressCallback | None = None
    ) -> Values: ...
    def image(
        self,
        *,
        camera_eye: Sequence[float] | None = None,
        camera_target: Sequence[float] | None = None,
        camera_up: Sequence[float] = (0.0, 1.0, 0.0),
        fov: float | None = None,
        auto_camera: bool = False,
        resolution: tuple[int, int] | None = None,
        image_mode: Literal["mesh", "pixel"] | None = None,
        pixel_samples: int = 1,
        exposure: float | None = None,
        progress: ProgressCallback | None = None,
    ) -> npt.NDArray[np.float32]: ...
    def write(
        self,
        *,
        image: str | os.PathLike[str] | None = None,
        mesh: str | os.PathLike[str] | None = None,
        ply: str | os.PathLike[str] | None = None,
        metrics: str | os.PathLike[str] | None = None,
        probes: str | os.PathLike[str] | None = None,
        probe_out: str | os.PathLike[str] | None = None,
        probe_quantity: Literal["radiosity", "irradiance", "daylight-factor"] | None = None,
        probe_tolerance: float | None = None,
        kernel_image: str | os.PathLike[str] | None = None,
        views: Sequence[View] = (),
        lightmap: str | os.PathLike[str] | None = None,
        lightmap_density: float | None = None,
        lightmap_size: int | None = None,
        lightmap_padding: int | None = None,
        lightmap_quantity: Literal["irradiance", "radiosity"] | None = None,
        lightmap_denoise: bool = False,
        shard: tuple[int, int] | None = None,
        from_shards: Sequence[str | os.PathLike[str]] = (),
        camera_eye: Sequence[float] | None = None,
        camera_target: Sequence[float] | None = None,
        camera_up: Sequence[float] = (0.0, 1.0, 0.0),
        fov: float | None = None,
        auto_camera: bool = False,
        resolution: tuple[int, int] | None = None,
        image_mode: Literal["mesh", "pixel"] | None = None,
        pixel_samples: int = 1,
        exposure: float | None = None,
        progress: ProgressCallback | None = None,
    ) -> dict[str, Any]: ...
    @property
    def metrics(self) -> dict[str, Any]: ...
    @property
    def scene(self) -> Scene: ...
    @property
    def networks_trained(self) -> bool: ...

class IsgcsModel:
    @staticmethod
    def fit(x: ArrayLike, y: ArrayLike, params: str) -> IsgcsModel: ...
    def predict(self, x: ArrayLike) -> npt.NDArray[np.float64]: ...
    @property
    def input_dim(self) -> int: ...
    @property
    def output_dim(self) -> int: ...
    @property
    def cells(self) -> int: ...
    @property
    def report(self) -> str: ...
    def state(self) -> str: ...
    @staticmethod
    def from_state(state: str) -> IsgcsModel: ...
