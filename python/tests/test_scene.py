"""Scenes built from NumPy arrays: the acceptance canopy, groups, sides, threads, progress."""

import time

import numpy as np
import pytest

import hirad
from conftest import canopy

TRI = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=float)


@pytest.fixture(scope="module")
def canopy_solution():
    scene, leaf_rho, leaf_tau, soil_rho = canopy()
    assert scene.triangles == 1000
    start = time.monotonic()
    s = hirad.solve(scene, progress=False)
    print(f"1000-triangle canopy solved in {time.monotonic() - start:.2f} s")
    return s, leaf_rho, leaf_tau, soil_rho


def test_canopy_balances_its_power(canopy_solution):
    """Acceptance: absorbed (by the receiving sides, plus what the soil's back takes) and
    escaped power equal emitted and direct power within 0.5 % per band."""
    s, *_ = canopy_solution
    assert len(s) == 1000
    assert s.band_names == ["par", "nir"]
    for p in s.stats["power"]:
        into = p["emitted"] + p["direct"]
        out = p["absorbed"] + p["absorbed_backs"] + p["escaped"]
        assert into > 0
        assert abs(out - into) <= 0.005 * into, p
    assert s.stats["verdict"]["passed"], s.stats["verdict"]


def test_canopy_absorbed_from_the_arrays(canopy_solution):
    """Absorbed power recomputed from the per-polygon arrays is the balance's."""
    s, leaf_rho, leaf_tau, soil_rho = canopy_solution
    leaf = np.array([s.materials[m] == "leaf" for m in s.material_index])
    rho = np.where(leaf[:, None], leaf_rho, soil_rho)
    tau = np.where(leaf[:, None], leaf_tau, 0.0)
    front = (1 - rho - tau) * s.irradiance
    back = np.where(leaf[:, None], (1 - rho - tau) * np.nan_to_num(s.irradiance_back), 0.0)
    absorbed = (s.area[:, None].astype(np.float64) * (front + back)).sum(axis=0)
    stats = np.array([p["absorbed"] for p in s.stats["power"]])
    np.testing.assert_allclose(absorbed, stats, rtol=1e-4)
    np.testing.assert_allclose(s.group_absorbed.sum(axis=0), stats, rtol=1e-6)
    into = np.array([p["emitted"] + p["direct"] for p in s.stats["power"]])
    escaped = np.array([p["escaped"] + p["absorbed_backs"] for p in s.stats["power"]])
    np.testing.assert_allclose(absorbed + escaped, into, rtol=5e-3)


def test_canopy_groups_and_rows(canopy_solution):
    s, *_ = canopy_solution
    # Ungrouped soil first (id -1), then the plants in order of first appearance.
    assert s.group_ids[0] == -1 and s.groups[0] == "scene"
    assert sorted(s.group_ids[1:]) == list(range(10))
    assert [f"scene/{g}" for g in s.group_ids[1:]] == s.groups[1:]
    for g in range(len(s.groups)):
        rows = s.group_index == g
        np.testing.assert_allclose(s.group_area[g], s.area[rows].astype(np.float64).sum())
    # Every input triangle is one row.
    assert sorted(s.triangles) == list(range(1000))
    assert list(s.triangles[:2]) == [0, 1]  # the soil
    assert s.radiosity.dtype == np.float32 and s.radiosity.shape == (1000, 2)
    assert s.ids.dtype == np.uint64 and s.area.dtype == np.float32
    assert s.radiosity_back is not None  # leaves are two-sided
    assert np.isnan(s.radiosity_back[0]).all()  # the soil is not
    assert np.isfinite(s.radiosity_back[2:]).all()


def test_threads_give_identical_results():
    scene, *_ = canopy(leaves=200, seed=3)
    one = hirad.solve(scene, threads=1, progress=False)
    two = hirad.solve(scene, threads=2, progress=False)
    for k in ["radiosity", "irradiance", "radiosity_back", "irradiance_back", "area"]:
        np.testing.assert_array_equal(getattr(one, k), getattr(two, k))
    assert one.stats["threads"] == 1 and two.stats["threads"] == 2


def test_one_sided_scene_has_no_backs():
    s = hirad.Scene(bands=1)
    s.add_material("floor", reflectance=0.5)
    s.add_material("lamp", reflectance=0.0, emission=100.0)
    s.add_triangles([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]],
                    material="floor")
    s.add_triangles([[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], [[0, 2, 1], [0, 3, 2]],
                    material="lamp")
    r = hirad.solve(s, progress=False)
    assert r.radiosity_back is None and r.irradiance_back is None
    assert r.band_names == ["0"]
    assert (r.irradiance[:2, 0] > 10).all()  # the floor is lit by the lamp above
    np.testing.assert_allclose(r.radiosity[2:, 0], 100.0, rtol=0.05)  # the lamp


def test_materials_per_triangle_and_sky_directions():
    s = hirad.Scene(bands=["par", "nir"])
    s.add_material("a", reflectance=0.2)
    s.add_material("b", reflectance=[0.1, 0.5], back_reflectance=0.3)
    s.add_triangles(np.vstack([TRI, TRI + [0, 0, 0.5]]), [[0, 1, 2], [3, 4, 5]],
                    material=["a", "b"], groups=np.array([5, 5]))
    s.add_sky([[0, 0, 1], [0.5, 0, 0.5]], [[100, 80], [10, 8]])
    s.add_sky([0, 0.1, 1.0], 5.0)
    r = hirad.solve(s, progress=False)
    assert [r.materials[m] for m in r.material_index] == ["a", "b"]
    assert r.groups == ["scene/5"] and list(r.group_ids) == [5]
    assert r.radiosity_back is not None and np.isnan(r.radiosity_back[0]).all()


def test_progress_callback_and_cancel():
    scene, *_ = canopy(leaves=200, seed=5)
    seen = []

    def record(phase, done, total):
        seen.append((phase, done, total))

    hirad.solve(scene, progress=record)
    assert seen and all(isinstance(p, str) for p, _, _ in seen)
    assert any(t is not None and d == t for _, d, t in seen)

    with pytest.raises(hirad.Cancelled):
        hirad.solve(scene, progress=lambda *a: False)

    class Stop(Exception):
        pass

    def fail(*a):
        raise Stop("enough")

    with pytest.raises(Stop):
        hirad.solve(scene, progress=fail)
    # The module still works after a cancelled solve.
    assert len(hirad.solve(scene, progress=False)) == 202


def test_tqdm_bar_is_optional():
    pytest.importorskip("tqdm")
    scene, *_ = canopy(leaves=50, seed=2)
    assert len(hirad.solve(scene)) == 52  # a tqdm bar (after a second), no error


def test_ctrl_c_stops_a_long_solve(tmp_path):
    """SIGINT during a solve raises KeyboardInterrupt within a second, not at its end."""
    import os
    import signal
    import subprocess
    import sys

    script = tmp_path / "long.py"
    script.write_text(f"""
import signal, sys, time
signal.signal(signal.SIGINT, signal.default_int_handler)
sys.path.insert(0, {os.path.dirname(__file__)!r})
from conftest import canopy
import hirad
scene, *_ = canopy(leaves=20000, seed=1)
print("solving", flush=True)
try:
    hirad.solve(scene, epsilon=1e-5, progress=False)
    print("finished", flush=True)
except KeyboardInterrupt:
    print("interrupted", flush=True)
""")
    p = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "solving"
    time.sleep(2.0)
    p.send_signal(signal.SIGINT)
    sent = time.monotonic()
    out, _ = p.communicate(timeout=60)
    assert out.strip() == "interrupted"
    assert time.monotonic() - sent < 5.0


def test_the_gil_is_released_while_solving():
    """Another Python thread runs while the solver works."""
    import threading

    scene, *_ = canopy(leaves=998, seed=11)
    ticks = []
    done = threading.Event()

    def tick():
        while not done.is_set():
            ticks.append(time.monotonic())
            time.sleep(0.002)

    t = threading.Thread(target=tick)
    t.start()
    try:
        start = time.monotonic()
        hirad.solve(scene, progress=False)
        end = time.monotonic()
    finally:
        done.set()
        t.join()
    during = [x for x in ticks if start < x < end]
    # At one tick per 2 ms (or slower on a busy machine), far more than the ten or so a
    # solve that held the GIL would allow between its progress reports.
    assert len(during) >= min(50, (end - start) / 0.02), (len(during), end - start)
