"""Every kind of scene path: .hir, .hirb, .obj, as str or os.PathLike."""

import pathlib

import numpy as np
import pytest

import hirad
from conftest import FIXTURES, run_cli


def test_text_and_binary_give_the_same_results(hirad_bin, tmp_path):
    hirb = tmp_path / "plant.hirb"
    run_cli(hirad_bin, "convert", FIXTURES / "small_plant.hir", "-o", hirb)
    text = hirad.solve(FIXTURES / "small_plant.hir", progress=False)  # a pathlib.Path
    binary = hirad.solve(str(hirb), progress=False)
    assert len(binary) == len(text) == 105
    np.testing.assert_array_equal(binary.ids, text.ids)
    np.testing.assert_array_equal(binary.radiosity, text.radiosity)
    np.testing.assert_array_equal(binary.irradiance, text.irradiance)
    assert binary.groups == text.groups
    assert binary.faces is None and binary.triangles is None


def test_obj_has_face_numbers(hirad_bin, tmp_path, in_root):
    path = pathlib.Path("fixtures/obj/cornell_triangles.obj")
    csv_path = tmp_path / "c.csv"
    run_cli(hirad_bin, "solve", path, "--results", csv_path)
    s = hirad.solve(path, progress=False)
    assert len(s) == 32
    assert s.band_names == ["0", "1", "2"] or len(s.band_names) == 3
    assert s.faces is not None and sorted(s.faces) == list(range(1, 33))
    assert s.radiosity_back is None and s.irradiance_back is None  # one-sided walls
    lines = csv_path.read_text().splitlines()[1:]
    assert len(lines) == 32
    assert (s.radiosity.max(axis=1) > 0).any()


def test_bytes_of_a_path_are_refused_with_a_type_error():
    with pytest.raises(TypeError):
        hirad.solve(42)


def test_loader_warnings_are_python_warnings(in_root):
    with pytest.warns(hirad.HiradWarning, match=r"max_groups.mtl:9:5: Tf 1 1 1"):
        s = hirad.solve("fixtures/obj/max_groups.obj", progress=False)
    assert any("Tf 1 1 1" in w for w in s.warnings)


@pytest.mark.parametrize("suffix", [".hir", ".hirb"])
def test_a_saved_scene_solves_to_the_same_numbers(tmp_path, suffix):
    from conftest import canopy

    scene, *_ = canopy(leaves=100, seed=9)
    path = tmp_path / f"canopy{suffix}"
    assert scene.save(path) > 0
    a = hirad.solve(scene, progress=False)
    b = hirad.solve(path, progress=False)
    for k in ["ids", "area", "radiosity", "irradiance", "radiosity_back", "irradiance_back"]:
        np.testing.assert_array_equal(getattr(a, k), getattr(b, k))
    assert a.groups == b.groups
    np.testing.assert_array_equal(a.group_absorbed, b.group_absorbed)


def test_saving_as_another_format_is_refused(tmp_path):
    s = hirad.Scene(bands=2)
    with pytest.raises(ValueError, match="hir or .hirb"):
        s.save(tmp_path / "x.obj")
