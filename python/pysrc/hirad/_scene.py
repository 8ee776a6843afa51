"""``hirad.Scene``: a scene built from NumPy arrays, the way plant modellers hold canopies.

Units: metres for positions, W/m^2 for exitance and irradiance; reflectance and
transmittance are fractions (0 to 1). The scene's up is +z (the sky's zenith).
"""

import numbers

import numpy as np

from . import _hirad


def _per_band(scene, what, value):
    """``value`` as one float per band: a scalar is used for every band."""
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{what}: expected a number or one number per band ({e})") from None
    if a.ndim == 0:
        a = np.full(scene.bands, float(a))
    if a.shape != (scene.bands,):
        raise ValueError(
            f"{what}: expected a number or {scene.bands} numbers (one per band: "
            f"{', '.join(scene.band_names) or scene.bands}), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{what}: values must be finite, got {a.tolist()}")
    return [float(x) for x in a]


def _direction(what, value):
    try:
        d = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{what}: expected 3 numbers (x, y, z)") from None
    if d.shape != (3,):
        raise ValueError(f"{what}: expected 3 numbers (x, y, z), got shape {d.shape}")
    if not np.all(np.isfinite(d)):
        raise ValueError(f"{what}: values must be finite, got {d.tolist()}")
    return [float(x) for x in d]


class Scene:
    """A scene built in memory: materials, triangles (optionally in groups), suns and sky.

    ``bands`` is a count (1 to 8, unnamed bands) or a list of band names, e.g.
    ``Scene(bands=["par", "nir"])``. Every per-band value (reflectance, irradiance, ...) is
    then a number for all bands or one number per band.

    Triangles keep the order they were added in: ``Solution.triangles`` gives, for every
    result row, the index of the triangle it belongs to (rows are in the solver's order:
    ungrouped triangles first, then each group in order of its first appearance).
    """

    def __init__(self, bands=1):
        if isinstance(bands, numbers.Integral) and not isinstance(bands, bool):
            names = []
            count = int(bands)
        elif isinstance(bands, str):
            names = [bands]
            count = 1
        else:
            try:
                names = [str(b) for b in bands]
            except TypeError:
                raise ValueError(
                    f"bands: expected a count or a list of names, got {bands!r}") from None
            count = len(names)
        if len(set(names)) != len(names):
            raise ValueError(f"bands: names must differ, got {names}")
        self._builder = _hirad.SceneBuilder(count, names)
        self._names = names

    @property
    def bands(self):
        """Number of spectral bands."""
        return self._builder.bands

    @property
    def band_names(self):
        """Band names (empty for unnamed bands)."""
        return list(self._names)

    @property
    def materials(self):
        """Material names, in the order they were added."""
        return self._builder.materials

    @property
    def triangles(self):
        """Triangles added so far."""
        return self._builder.triangles

    def add_material(self, name, reflectance, transmittance=None, emission=None,
                     back_reflectance=None, back_emission=None):
        """Adds a material called ``name``; each value is a number for all bands or one per
        band.

        * ``reflectance``: front diffuse reflectance (0 to 1).
        * ``transmittance``: diffuse transmittance through the surface, the same from
          either side (0 to 1).
        * ``emission``: front emitted exitance (W/m^2), default 0.
        * ``back_reflectance``: back reflectance (0 to 1), default: equal to
          ``reflectance``.
        * ``back_emission``: back emitted exitance (W/m^2), default 0.

        As in the ``.hir`` format, a material is one-sided (its back absorbs everything)
        unless it has a transmittance, a back reflectance or a back emission: then it is
        two-sided (a leaf). Energy must be conserved: reflectance + transmittance <= 1 on
        each side, in every band. Raises ValueError otherwise.
        """
        if not isinstance(name, str) or not name:
            raise ValueError(f"material name: expected a non-empty string, got {name!r}")
        opt = lambda what, v: None if v is None else _per_band(self, what, v)  # noqa: E731
        self._builder.add_material(
            name,
            _per_band(self, f"material '{name}': reflectance", reflectance),
            opt(f"material '{name}': transmittance", transmittance),
            opt(f"material '{name}': emission", emission),
            opt(f"material '{name}': back_reflectance", back_reflectance),
            opt(f"material '{name}': back_emission", back_emission),
        )

    def add_triangles(self, vertices, indices, material, groups=None):
        """Adds triangles and returns the indices they were given (a range).

        * ``vertices``: n x 3 positions (m).
        * ``indices``: m x 3 integer indices into ``vertices``, corners counter-clockwise
          seen from the front side (the side ``reflectance`` and ``emission`` describe).
        * ``material``: one material name for every triangle, or a sequence of m names.
        * ``groups``: None, or m integer group ids (0 or more): the triangles of a group
          are kept together (a cluster named by the id, ``scene/<id>`` in the results'
          group paths), and ``Solution.group_absorbed`` sums absorbed power per group.
          Triangles of the same id added by several calls join one group.

        Every triangle is checked as the solver checks polygons (finite, not degenerate, not
        too small for 32-bit floats); nothing is added when one fails (ValueError naming the
        triangle, counted from 0 within this call).
        """
        v = np.asarray(vertices)
        if v.dtype == object or not (np.issubdtype(v.dtype, np.number)):
            raise ValueError(f"vertices: expected numbers, got dtype {v.dtype}")
        v = v.astype(np.float64)
        if v.ndim != 2 or v.shape[1] != 3:
            raise ValueError(f"vertices: expected shape (n, 3), got {v.shape}")
        bad = ~np.all(np.isfinite(v), axis=1)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ValueError(f"vertices: vertex {i} is not finite: {v[i].tolist()}")
        t = np.asarray(indices)
        if t.size == 0 and t.ndim <= 2:
            t = t.reshape(0, 3)
        if not np.issubdtype(t.dtype, np.integer):
            raise ValueError(f"indices: expected integers, got dtype {t.dtype}")
        if t.ndim != 2 or t.shape[1] != 3:
            raise ValueError(f"indices: expected shape (m, 3), got {t.shape}")
        m = t.shape[0]
        n = v.shape[0]
        out = (t < 0) | (t >= n)
        if out.any():
            i = int(np.flatnonzero(out.any(axis=1))[0])
            raise ValueError(
                f"indices: triangle {i} has a vertex index out of range: {t[i].tolist()} "
                f"({n} vertices)")
        mats = self._materials_of(material, m)
        g = None
        if groups is not None:
            g = np.asarray(groups)
            if not np.issubdtype(g.dtype, np.integer):
                raise ValueError(f"groups: expected integers, got dtype {g.dtype}")
            if g.shape != (m,):
                raise ValueError(f"groups: expected one id per triangle, shape ({m},), got "
                                 f"{g.shape}")
            if (g < 0).any():
                i = int(np.flatnonzero(g < 0)[0])
                raise ValueError(f"groups: triangle {i} has a negative group id {int(g[i])}")
            g = g.astype("<i8").tobytes()
        first = self.triangles
        self._builder.add_triangles(
            v.astype("<f8").tobytes(), t.astype("<i8").tobytes(), mats.astype("<i8").tobytes(), g)
        return range(first, first + m)

    def _materials_of(self, material, m):
        """One material index per triangle."""
        if isinstance(material, str):
            return np.full(m, self._builder.material_index(material), dtype=np.int64)
        names = np.asarray(material, dtype=object)
        if names.shape != (m,):
            raise ValueError(
                f"material: expected one name, or one per triangle (shape ({m},)), got shape "
                f"{names.shape}")
        index = {}
        out = np.empty(m, dtype=np.int64)
        for i, name in enumerate(names):
            if not isinstance(name, str):
                raise ValueError(f"material: triangle {i}: expected a name, got {name!r}")
            if name not in index:
                index[name] = self._builder.material_index(name)
            out[i] = index[name]
        return out

    def add_sun(self, direction, irradiance):
        """Adds a sun: ``direction`` points from the scene towards the sun (the ``.hir``
        format's ``sun from``; e.g. ``(0, 0, 1)`` for a sun at the zenith), normalised if
        it is not unit; ``irradiance`` (W/m^2, per band) is measured on a plane facing the
        sun (direct normal irradiance)."""
        self._builder.add_sun(_direction("sun direction", direction),
                              _per_band(self, "sun irradiance", irradiance))

    def add_sky(self, direction=None, irradiance=None, *, horizontal=None, model="uniform",
                rings=6):
        """Adds sky light, in one of two ways.

        * ``add_sky(direction, irradiance)``: weighted sky directions as the ``.hir``
          format's ``sky from`` lines: ``direction`` (3 numbers, or k x 3) points towards
          that patch of sky, ``irradiance`` (per band, or k x bands) is its irradiance on a
          plane facing it (W/m^2).
        * ``add_sky(horizontal=..., model="uniform" | "standard_overcast", rings=6)``: a
          whole sky over the upper hemisphere (z up), as ``hirad gen`` makes: ``rings``
          rings of equal solid angle (about 2 rings^2 directions), radiance uniform or the
          CIE standard overcast (brighter towards the zenith), its directions' irradiance on
          a horizontal plane summing to ``horizontal`` per band (W/m^2).
        """
        if horizontal is not None:
            if direction is not None or irradiance is not None:
                raise ValueError("add_sky: give direction and irradiance, or horizontal")
            if model not in ("uniform", "standard_overcast"):
                raise ValueError(
                    f"add_sky: model must be 'uniform' or 'standard_overcast', got {model!r}")
            if not isinstance(rings, numbers.Integral) or not 1 <= rings <= 64:
                raise ValueError(f"add_sky: rings must be a whole number from 1 to 64, "
                                 f"got {rings!r}")
            h = _per_band(self, "sky horizontal irradiance", horizontal)
            if min(h) < 0:
                raise ValueError(f"sky horizontal irradiance: must be 0 or more, got {h}")
            dirs, irr = _hirad.SceneBuilder.sky_directions(int(rings),
                                                           model == "standard_overcast", h)
            d = np.asarray(dirs, dtype=np.float64).reshape(-1, 3)
            e = np.asarray(irr, dtype=np.float64).reshape(-1, self.bands)
            for k in range(d.shape[0]):
                self._builder.add_sky(d[k].tolist(), e[k].tolist())
            return
        if direction is None or irradiance is None:
            raise ValueError("add_sky: give direction and irradiance, or horizontal")
        d = np.asarray(direction, dtype=np.float64)
        if d.ndim == 1:
            self._builder.add_sky(_direction("sky direction", d),
                                  _per_band(self, "sky irradiance", irradiance))
            return
        if d.ndim != 2 or d.shape[1] != 3:
            raise ValueError(f"sky direction: expected 3 numbers or shape (k, 3), got {d.shape}")
        e = np.asarray(irradiance, dtype=np.float64)
        if e.ndim == 1 and e.shape[0] == self.bands:
            e = np.broadcast_to(e, (d.shape[0], self.bands))
        if e.shape != (d.shape[0], self.bands):
            raise ValueError(f"sky irradiance: expected shape ({d.shape[0]}, {self.bands}), "
                             f"got {e.shape}")
        for k in range(d.shape[0]):
            self._builder.add_sky(_direction(f"sky direction {k}", d[k]),
                                  _per_band(self, f"sky irradiance {k}", e[k]))

    def save(self, path):
        """Writes the scene to ``path``, a ``.hir`` (text, docs/format.md) or ``.hirb``
        (binary image) file by its extension, for the ``hirad`` command line (``hirad solve
        SCENE --image OUT.png``, ``hirad info``): the file solves to the same numbers.
        Returns the bytes written. Raises ``hirad.InputError`` for a scene the solver would
        refuse (a fault the format cannot hold) and ``ValueError`` for another extension.
        """
        import os

        p = os.fspath(path)
        if isinstance(p, bytes):
            p = os.fsdecode(p)
        if not p.lower().endswith((".hir", ".hirb")):
            raise ValueError(f"save: {p}: expected a path ending in .hir or .hirb")
        return self._builder.save(p)

    def __repr__(self):
        suns, sky = self._builder.lights
        return (f"hirad.Scene(bands={self._names or self.bands}, materials={self.materials}, "
                f"triangles={self.triangles}, suns={suns}, sky directions={sky})")
