"""``hirad.solve``: the radiosity of every polygon of a scene, in one call."""

import json
import numbers
import os
import warnings

import numpy as np

from . import _hirad, _progress
from ._errors import HiradWarning
from ._scene import Scene


class Solution:
    """The results of a solve, one row per polygon in global-id order (the CLI's results
    table), front side unless said.

    * ``ids`` (uint64): global ids.
    * ``area`` (float32, m^2).
    * ``radiosity``, ``irradiance`` (float32, polygons x bands, W/m^2): front side.
    * ``radiosity_back``, ``irradiance_back``: the same for the back, NaN on one-sided
      polygons; None when no polygon is two-sided.
    * ``band_names``: the scene's band names (``"0"``, ``"1"``, ... when unnamed).
    * ``stats``: the dict ``hirad solve --stats`` writes (settings, counts, time, memory,
      power balance per band in ``stats["power"]``, verdict).
    * ``materials`` (list of names) and ``material_index`` (int32 per row).
    * ``groups``: the group path of every group (the results table's ``group`` column,
      e.g. ``scene/plant_3/leaves``), in order of first appearance; ``group_index``
      (int32 per row) says which; ``group_ids`` (int64 per group): for a ``hirad.Scene``,
      the ids given with the triangles (-1 for triangles given without), else the group's
      index.
    * ``group_area`` (float64, m^2 per group) and ``group_absorbed`` (float64, groups x
      bands, W): absorbed power per group, ``area * (1 - rho - tau) * irradiance`` summed
      over the receiving sides of its polygons (the front, and the back of two-sided ones):
      the power balance's ``absorbed``.
    * ``triangles`` (int64 per row, for a ``hirad.Scene``): the input triangle of the row;
      ``faces`` (int64 per row, for an OBJ scene): its face number (1-based); else None.
    * ``warnings``: the run's warnings (also issued as ``hirad.HiradWarning``).
    * ``failure``: why the numbers are not right (not converged, power balance off), or
      None (``stats["verdict"]`` says the same).
    """

    def __init__(self, raw, from_model):
        n, b = raw["count"], raw["bands"]

        def arr(key, dtype, shape=None):
            data = raw[key]
            if data is None:
                return None
            a = np.frombuffer(data, dtype=dtype).copy()
            return a.reshape(shape) if shape is not None else a

        self.ids = arr("ids", "<u8").astype(np.uint64, copy=False)
        self.area = arr("area", "<f4").astype(np.float32, copy=False)
        self.radiosity = arr("radiosity", "<f4", (n, b)).astype(np.float32, copy=False)
        self.irradiance = arr("irradiance", "<f4", (n, b)).astype(np.float32, copy=False)
        self.radiosity_back = arr("radiosity_back", "<f4", (n, b))
        self.irradiance_back = arr("irradiance_back", "<f4", (n, b))
        if self.radiosity_back is not None:
            self.radiosity_back = self.radiosity_back.astype(np.float32, copy=False)
            self.irradiance_back = self.irradiance_back.astype(np.float32, copy=False)
        self.band_names = list(raw["band_names"])
        self.stats = json.loads(raw["stats_json"])
        self.materials = list(raw["material_names"])
        self.material_index = arr("material_of_row", "<u4").astype(np.int32, copy=False)
        self.groups = list(raw["group_names"])
        self.group_index = arr("group_of_row", "<u4").astype(np.int32, copy=False)
        self.group_area = arr("group_area", "<f8")
        self.group_absorbed = arr("group_absorbed", "<f8", (len(self.groups), b))
        if from_model:
            self.group_ids = np.array(
                [int(g.rsplit("/", 1)[1]) if "/" in g else -1 for g in self.groups],
                dtype=np.int64)
        else:
            self.group_ids = np.arange(len(self.groups), dtype=np.int64)
        t = arr("triangles", "<u8")
        self.triangles = None if t is None else t.astype(np.int64, copy=False)
        f = arr("faces", "<u8")
        self.faces = None if f is None else f.astype(np.int64, copy=False)
        self.warnings = list(raw["warnings"])
        self.failure = raw["failure"]

    def __len__(self):
        return len(self.ids)

    def __repr__(self):
        return (f"hirad.Solution({len(self)} polygons, bands {self.band_names}, "
                f"method {self.stats.get('method')}, {len(self.groups)} groups)")


def _scene_argument(scene):
    if isinstance(scene, Scene):
        return scene._builder, True
    if isinstance(scene, (str, os.PathLike)):
        path = os.fspath(scene)
        if isinstance(path, bytes):
            path = os.fsdecode(path)
        return path, False
    raise TypeError(
        f"scene: expected a path (str or os.PathLike to a .hir, .hirb or .obj file) or a "
        f"hirad.Scene, got {type(scene).__name__}")


def solve(scene, method=None, epsilon=1e-3, threads=None, memory=None, progress=None,
          instancing=None):
    """Solves ``scene`` as ``hirad solve`` does and returns a :class:`Solution`.

    * ``scene``: a path (``.hir``, ``.hirb`` or ``.obj``; str or os.PathLike) or a
      :class:`hirad.Scene`.
    * ``method``: None (the CLI's default: ``hi`` where ``instancing="auto"`` closes an
      instance, i.e. the scene carries tables or its instances are too many to expand,
      else ``hr``), or ``"hi"``, ``"hr"``, ``"exact"`` as ``--method``.
    * ``epsilon``: refinement threshold (dimensionless, ``--epsilon``).
    * ``threads``: worker threads, 1 to 1024 (None: every core). Results are identical
      for any count.
    * ``memory``: workspace size, bytes (int) or a size such as ``"64M"``, ``"2G"``
      (``--memory``; None: the planner's suggestion). Too small: :class:`hirad.UsageError`.
    * ``progress``: a callable ``progress(phase, done, total)`` (``total`` None for an
      open count; return ``False`` or raise to stop the solve), None (a tqdm bar when
      tqdm is installed, else nothing), or False (nothing).
    * ``instancing``: ``--instancing`` (``"auto"``, ``"all"``, ``"every:N"``, ``"none"``).

    The GIL is released while the solver runs; Ctrl-C stops it (KeyboardInterrupt) within a
    fraction of a second of the next progress report. Errors raise :class:`hirad.HiradError`
    (``InputError`` for a bad scene, ``UsageError`` for bad settings) with the CLI's
    message. When the numbers are not right (not converged, power balance off by more than
    5 %) the results are returned with a :class:`hirad.HiradWarning` and
    ``stats["verdict"]["passed"]`` False.
    """
    target, from_model = _scene_argument(scene)
    if method is not None and not isinstance(method, str):
        raise ValueError(f"method: expected 'hi', 'hr', 'exact' or None, got {method!r}")
    if instancing is not None and not isinstance(instancing, str):
        raise ValueError(f"instancing: expected a string such as 'auto', got {instancing!r}")
    if isinstance(epsilon, bool) or not isinstance(epsilon, numbers.Real):
        raise ValueError(f"epsilon: expected a positive number, got {epsilon!r}")
    epsilon = float(epsilon)
    if threads is not None:
        if isinstance(threads, bool) or not isinstance(threads, numbers.Integral) \
                or not 1 <= threads <= 1024:
            raise ValueError(f"threads: expected a whole number from 1 to 1024, got {threads!r}")
        threads = int(threads)
    if memory is not None:
        if isinstance(memory, bool):
            raise ValueError(f"memory: expected bytes or a size such as '64M', got {memory!r}")
        if isinstance(memory, numbers.Integral):
            if memory < 1:
                raise ValueError(f"memory: expected a positive number of bytes, got {memory}")
            memory = str(int(memory))
        elif isinstance(memory, str):
            _hirad.parse_bytes(memory)  # ValueError with --memory's message
        else:
            raise ValueError(f"memory: expected bytes or a size such as '64M', got {memory!r}")
    callback, close = _progress.choose(progress)
    try:
        raw = _hirad.solve(target, method=method, instancing=instancing, epsilon=epsilon,
                           threads=threads, memory=memory, progress=callback)
    finally:
        close()
    result = Solution(raw, from_model)
    for w in result.warnings:
        warnings.warn(w, HiradWarning, stacklevel=2)
    if result.failure:
        warnings.warn(result.failure, HiradWarning, stacklevel=2)
    return result
