"""hirad.solve gives the command line's numbers, value by value."""

import csv
import json

import numpy as np
import pytest

import hirad
from conftest import FIXTURES, run_cli

# Stats that depend on the run's time or on the files it wrote.
TIMED = {"seconds", "phases", "outputs"}


def read_results(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def assert_equals_csv(s, csv_path):
    """Every value of the solution `s` is the one of the CLI's results table, bit for bit."""
    rows = read_results(csv_path)
    assert len(rows) == len(s)
    for k, row in enumerate(rows):
        assert int(row["id"]) == s.ids[k]
        # The CSV holds shortest round-trip floats: parsed, they are the f32 bits again.
        assert np.float32(float(row["area_m2"])) == s.area[k]
        for b, band in enumerate(s.band_names):
            assert np.float32(float(row[f"rad_{band}_W_m2"])) == s.radiosity[k, b]
            assert np.float32(float(row[f"irr_{band}_W_m2"])) == s.irradiance[k, b]
            if s.radiosity_back is None:
                assert f"rad_back_{band}_W_m2" not in row
                continue
            back = row[f"rad_back_{band}_W_m2"]
            if back == "":
                assert np.isnan(s.radiosity_back[k, b])
                assert np.isnan(s.irradiance_back[k, b])
            else:
                assert np.float32(float(back)) == s.radiosity_back[k, b]
                assert np.float32(float(row[f"irr_back_{band}_W_m2"])) == s.irradiance_back[k, b]
        assert row["material"] == s.materials[s.material_index[k]]
        assert row["group"] == s.groups[s.group_index[k]]
        if "face" in row:
            assert int(row["face"]) == s.faces[k]
        else:
            assert s.faces is None


@pytest.mark.parametrize("words,kwargs", [
    ([], {}),
    (["--method", "hi"], dict(method="hi")),
    (["--method", "hr", "--epsilon", "0.01", "--threads", "1", "--memory", "64M"],
     dict(method="hr", epsilon=0.01, threads=1, memory="64M")),
], ids=["default", "hi", "hr-settings"])
def test_small_plant_equals_the_cli(hirad_bin, in_root, tmp_path, words, kwargs):
    csv_path, stats_path = tmp_path / "plant.csv", tmp_path / "plant.json"
    run_cli(hirad_bin, "solve", "fixtures/small_plant.hir", *words, "--results", csv_path,
            "--stats", stats_path)
    s = hirad.solve("fixtures/small_plant.hir", progress=False, **kwargs)
    assert len(s) == 105
    assert_equals_csv(s, csv_path)
    cli = json.loads(stats_path.read_text())
    assert set(cli) == set(s.stats)
    for key in set(cli) - TIMED:
        if key == "settings":
            assert {k: v for k, v in cli[key].items()} == s.stats[key]
        else:
            assert cli[key] == s.stats[key], key
    if not kwargs:
        assert s.stats["method"] == "hr"  # no tables: the CLI's default falls back to hr


def test_group_sums_equal_the_sums_of_rows(in_root):
    s = hirad.solve("fixtures/small_plant.hir", progress=False)
    leaf = {"leaf": ([0.1, 0.45], [0.05, 0.45]), "stem": ([0.08, 0.3], [0, 0]),
            "soil": ([0.1, 0.2], [0, 0])}
    absorbed = np.zeros((len(s), 2))
    for k in range(len(s)):
        rho, tau = (np.array(v) for v in leaf[s.materials[s.material_index[k]]])
        a = (1 - rho - tau) * s.irradiance[k]
        if not np.isnan(s.irradiance_back[k, 0]):
            a = a + (1 - rho - tau) * s.irradiance_back[k]
        absorbed[k] = s.area[k] * a
    for g in range(len(s.groups)):
        rows = s.group_index == g
        np.testing.assert_allclose(s.group_area[g], s.area[rows].astype(np.float64).sum(),
                                   rtol=1e-12)
        np.testing.assert_allclose(s.group_absorbed[g], absorbed[rows].sum(axis=0),
                                   rtol=1e-6)  # the material values as f32
    # The groups' absorbed power is the balance's.
    stats_absorbed = [p["absorbed"] for p in s.stats["power"]]
    np.testing.assert_allclose(s.group_absorbed.sum(axis=0), stats_absorbed, rtol=1e-6)
    assert "scene/soil" in s.groups
    assert list(s.group_ids) == list(range(len(s.groups)))


def test_obj_equals_the_cli(hirad_bin, in_root, tmp_path):
    csv_path = tmp_path / "cornell.csv"
    run_cli(hirad_bin, "solve", "fixtures/obj/cornell_triangles.obj", "--results", csv_path)
    s = hirad.solve("fixtures/obj/cornell_triangles.obj", progress=False)
    assert s.faces is not None
    assert_equals_csv(s, csv_path)


def test_tables_image_solved_by_hi_equals_the_cli(hirad_bin, tmp_path):
    """A .hirb that carries its originals' tables, solved by hi level by level straight from
    the file (the model then keeps no vertices: groups and materials still come out)."""
    hirb = tmp_path / "plant_tables.hirb"
    # Coarse tables, quickly made: they miss their error targets (exit 1) but are written.
    r = run_cli(hirad_bin, "tables", FIXTURES / "small_plant.hir", "-o", hirb,
                "--instancing", "all", "--no-cache", "-q", "--max-side", "4",
                "--max-tau-side", "4", "--max-out-side", "4", "--max-single-side", "0",
                check=False)
    assert hirb.exists(), r.stderr
    csv_path = tmp_path / "plant.csv"
    run_cli(hirad_bin, "solve", hirb, "--instancing", "all", "--results", csv_path)
    s = hirad.solve(hirb, instancing="all", progress=False)
    assert s.stats["method"] == "hi"
    assert_equals_csv(s, csv_path)
    np.testing.assert_allclose(s.group_absorbed.sum(axis=0),
                               [p["absorbed"] for p in s.stats["power"]], rtol=1e-6)


def test_a_scene_from_arrays_equals_the_same_scene_as_hir(hirad_bin, tmp_path):
    """hirad.Scene builds what the .hir format says: the same arrays written as a .hir
    file and solved by the CLI give the same numbers, bit for bit (materials' defaults,
    light directions, groups as clusters, global-id order)."""
    rng = np.random.default_rng(4)
    f32 = lambda a: np.asarray(a, dtype=np.float32).astype(np.float64)  # noqa: E731
    leaves = 60
    centres = rng.uniform([-1, -1, 0.2], [1, 1, 1.2], size=(leaves, 3))
    offsets = rng.normal(scale=0.06, size=(leaves, 3, 3))
    leaf_v = f32((centres[:, None, :] + offsets).reshape(-1, 3))
    leaf_t = np.arange(3 * leaves).reshape(leaves, 3)
    plant = rng.integers(0, 4, size=leaves)
    soil_v = f32([[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]])
    soil_t = np.array([[0, 1, 2], [0, 2, 3]])
    sun, sun_e = f32([0.3, 0.2, 0.9]), f32([400.5, 350.25])
    sky = f32([[0, 0, 1], [0.5, 0.5, 0.7071], [-0.6, 0.1, 0.79]])
    sky_e = f32([[40, 30], [20, 15.5], [10, 8]])

    s = hirad.Scene(bands=["par", "nir"])
    s.add_material("leaf", reflectance=f32([0.1, 0.45]), transmittance=f32([0.05, 0.45]))
    s.add_material("soil", reflectance=f32([0.12, 0.3]))
    s.add_triangles(soil_v, soil_t, material="soil")
    s.add_triangles(leaf_v, leaf_t, material="leaf", groups=plant)
    s.add_sun(sun, sun_e)
    s.add_sky(sky, sky_e)

    num = lambda xs: " ".join(repr(float(x)) for x in np.ravel(xs))  # noqa: E731
    lines = ["hirad 1", "bands par nir",
             f"material leaf rho {num(f32([0.1, 0.45]))} tau {num(f32([0.05, 0.45]))}",
             f"material soil rho {num(f32([0.12, 0.3]))}",
             f"sun from {num(sun)} irradiance {num(sun_e)}"]
    lines += [f"sky from {num(d)} irradiance {num(e)}" for d, e in zip(sky, sky_e)]
    lines.append("scene {")
    lines += [f"  v {num(p)}" for p in soil_v]
    lines += [f"  tri soil {' '.join(map(str, t))}" for t in soil_t]
    for g in dict.fromkeys(plant.tolist()):  # groups in order of first appearance
        lines.append(f'  cluster "{g}" {{')
        for k in np.flatnonzero(plant == g):
            lines += [f"    v {num(leaf_v[i])}" for i in leaf_t[k]]
        for n, _ in enumerate(np.flatnonzero(plant == g)):
            lines.append(f"    tri leaf {3 * n} {3 * n + 1} {3 * n + 2}")
        lines.append("  }")
    lines.append("}")
    hir = tmp_path / "arrays.hir"
    hir.write_text("\n".join(lines) + "\n")
    csv_path = tmp_path / "arrays.csv"
    run_cli(hirad_bin, "solve", hir, "--results", csv_path)

    r = hirad.solve(s, progress=False)
    assert len(r) == leaves + 2
    assert_equals_csv(r, csv_path)
    # Rows map back to the triangles added: the soil, then each plant's leaves in order.
    expect = [0, 1] + [2 + int(k) for g in dict.fromkeys(plant.tolist())
                       for k in np.flatnonzero(plant == g)]
    assert list(r.triangles) == expect
