"""Errors are Python exceptions with the command line's message; no panic reaches Python."""

import math

import numpy as np
import pytest

import hirad
from conftest import FIXTURES, run_cli


def cli_error(hirad_bin, *args):
    r = run_cli(hirad_bin, "solve", *args, check=False)
    assert r.returncode != 0
    line = [l for l in r.stderr.splitlines() if l.startswith("error: ")][-1]
    return line[len("error: "):]


def test_missing_file(hirad_bin, tmp_path):
    path = tmp_path / "nowhere.hir"
    with pytest.raises(hirad.InputError) as e:
        hirad.solve(path, progress=False)
    assert str(path) in str(e.value)
    assert str(e.value) == cli_error(hirad_bin, path)


def test_malformed_hir_names_its_line_and_column(hirad_bin, tmp_path):
    path = tmp_path / "bad.hir"
    path.write_text("hirad 1\nbands 2\nmaterial m rho 0.5\nscene { }\n")
    with pytest.raises(hirad.InputError) as e:
        hirad.solve(path, progress=False)
    assert f"{path}:3:" in str(e.value)
    assert str(e.value) == cli_error(hirad_bin, path)


def test_bad_settings_are_value_errors():
    for kw in [dict(threads=0), dict(threads=2000), dict(memory="lots"), dict(memory=-5),
               dict(epsilon="small"), dict(progress=3)]:
        with pytest.raises(ValueError):
            hirad.solve(FIXTURES / "small_plant.hir", **kw)
    with pytest.raises(hirad.UsageError) as e:
        hirad.solve(FIXTURES / "small_plant.hir", method="fastest", progress=False)
    assert "fastest" in str(e.value)
    with pytest.raises(hirad.UsageError):
        hirad.solve(FIXTURES / "small_plant.hir", epsilon=-1.0, progress=False)


def test_memory_too_small(hirad_bin):
    with pytest.raises(hirad.UsageError) as e:
        hirad.solve(FIXTURES / "small_plant.hir", memory="4K", progress=False)
    assert str(e.value) == cli_error(hirad_bin, FIXTURES / "small_plant.hir", "--memory", "4K")
    assert isinstance(e.value, ValueError)


def small_scene():
    s = hirad.Scene(bands=["par", "nir"])
    s.add_material("leaf", reflectance=[0.1, 0.4], transmittance=[0.05, 0.4])
    return s


TRI = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=float)


@pytest.mark.parametrize("vertices,indices,material,groups,words", [
    (TRI[:, :2], [[0, 1, 2]], "leaf", None, "shape (n, 3)"),
    (TRI, [[0, 1]], "leaf", None, "shape (m, 3)"),
    (TRI, [[0, 1, 3]], "leaf", None, "out of range"),
    (TRI, [[0, -1, 2]], "leaf", None, "out of range"),
    (TRI, [[0.0, 1.0, 2.0]], "leaf", None, "integers"),
    (TRI, [[0, 1, 2]], "bark", None, "unknown material 'bark'"),
    (TRI, [[0, 1, 2]], ["leaf", "leaf"], None, "one per triangle"),
    (np.where(TRI == 1, math.nan, TRI), [[0, 1, 2]], "leaf", None, "not finite"),
    (TRI, [[0, 1, 2]], "leaf", [1, 2], "one id per triangle"),
    (TRI, [[0, 1, 2]], "leaf", [-3], "negative"),
    (TRI, [[0, 1, 1]], "leaf", None, "triangle 0"),
    (np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], float), [[0, 1, 2]], "leaf", None,
     "triangle 0"),
])
def test_bad_arrays(vertices, indices, material, groups, words):
    s = small_scene()
    with pytest.raises(ValueError) as e:
        s.add_triangles(vertices, indices, material=material, groups=groups)
    assert words in str(e.value)
    assert s.triangles == 0


def test_bad_materials_and_lights():
    s = small_scene()
    with pytest.raises(ValueError, match="defined twice"):
        s.add_material("leaf", reflectance=0.2)
    with pytest.raises(ValueError, match="one per band"):
        s.add_material("x", reflectance=[0.1, 0.2, 0.3])
    with pytest.raises(ValueError):
        s.add_material("y", reflectance=0.7, transmittance=0.5)  # creates energy
    with pytest.raises(ValueError, match="finite"):
        s.add_material("z", reflectance=[math.nan, 0.1])
    with pytest.raises(ValueError, match="zero"):
        s.add_sun([0, 0, 0], 100)
    with pytest.raises(ValueError, match="finite"):
        s.add_sun([0, 0, math.inf], 100)
    with pytest.raises(ValueError):
        s.add_sky(horizontal=[1, 2], model="clear")
    with pytest.raises(ValueError):
        hirad.Scene(bands=9)


def test_a_scene_without_light_or_polygons_is_an_input_error():
    s = small_scene()
    with pytest.raises(hirad.InputError, match="hirad.Scene"):
        hirad.solve(s, progress=False)
    s.add_triangles(TRI, [[0, 1, 2]], material="leaf")
    with pytest.raises(hirad.InputError):
        hirad.solve(s, progress=False)
