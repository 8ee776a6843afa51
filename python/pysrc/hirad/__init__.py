"""hirad: radiosity (diffuse global illumination) for huge repetitive scenes, in-process.

``hirad.solve(scene)`` solves a scene file (``.hir``, ``.hirb``, ``.obj``) or a
:class:`hirad.Scene` built from NumPy arrays, exactly as the ``hirad solve`` command line
does, and returns every polygon's radiosity and irradiance (W/m^2) as NumPy arrays, with
the run's stats and absorbed power per group (W).
"""

from ._errors import Cancelled, HiradError, HiradWarning, InputError, UsageError
from ._hirad import __version__
from ._scene import Scene
from ._solve import Solution, solve

__all__ = [
    "Cancelled",
    "HiradError",
    "HiradWarning",
    "InputError",
    "Scene",
    "Solution",
    "UsageError",
    "__version__",
    "solve",
]
