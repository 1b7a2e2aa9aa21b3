"""Growing Cells Radiosity from Python: the ``gcr`` program's solve as a library.

Load a scene (a file or a built-in, lit by its own emitters and any sun, sky, environment map,
point or spot lights), solve it with the program's settings and defaults, then ask for radiosity
B or irradiance at points (NumPy arrays in, NumPy arrays out), images as arrays, or the
program's files (glTF bake, EXR/PNG image, PLY, probe values, metrics)::

    import gcr
    scene = gcr.Scene.load("cornell-box")
    solution = gcr.solve(scene, quality="good", seed=1)
    values, std_errors = solution.radiosity(points, normals)
    solution.write(image="cornell.png", mesh="cornell.glb", metrics="cornell.json")

Errors are :class:`GcrError` with the program's messages, warnings :class:`GcrWarning`; long
calls release the GIL and report progress to an optional ``progress`` callback. The isgcs
regressor is :class:`gcr.isgcs.IsgcsRegressor`, a scikit-learn estimator.
"""

import importlib
from typing import TYPE_CHECKING

from gcr._gcr import (
    GcrError,
    GcrWarning,
    Scene,
    Solution,
    __version__,
    builtin_scenes,
    solve,
)

if TYPE_CHECKING:
    from gcr import isgcs

__all__ = [
    "GcrError",
    "GcrWarning",
    "Scene",
    "Solution",
    "__version__",
    "builtin_scenes",
    "isgcs",
    "solve",
]


def __getattr__(name: str):
    """``gcr.isgcs`` is imported on first use: it imports scikit-learn (a second or more), which
    a solve does not need."""
    if name == "isgcs":
        return importlib.import_module("gcr.isgcs")
    raise AttributeError(f"module 'gcr' has no attribute {name!r}")
