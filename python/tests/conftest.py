"""Shared fixtures: the repository's root and scenes, and the `hirad` command line to compare
with (HIRAD_BIN, else target/release/hirad, built with cargo when missing)."""

import os
import pathlib
import subprocess

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
FIXTURES = ROOT / "fixtures"


@pytest.fixture(scope="session")
def hirad_bin():
    given = os.environ.get("HIRAD_BIN")
    if given:
        return given
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    exe = target / "release" / "hirad"
    if not exe.exists():
        subprocess.run(["cargo", "build", "--release", "-p", "hirad", "--bin", "hirad"],
                       cwd=ROOT, check=True)
    return str(exe)


def run_cli(hirad_bin, *args, check=True):
    """Runs `hirad ARGS` from the repository's root; returns the completed process."""
    return subprocess.run([hirad_bin, *map(str, args)], cwd=ROOT, capture_output=True,
                          text=True, check=check, env={**os.environ, "HIRAD_PROGRESS": "off"})


@pytest.fixture
def in_root(monkeypatch):
    """Runs the test from the repository's root (paths as the CLI is given them)."""
    monkeypatch.chdir(ROOT)
    return ROOT


def canopy(leaves=998, bands=("par", "nir"), seed=7, plants=10, soil=True, sky=True):
    """A canopy of `leaves` random two-sided leaves (triangles about 8 cm across, tilted at
    random) over a one-sided soil quad (two triangles), grouped by plant, with a sun and a
    uniform sky: the acceptance scene. Returns (scene, leaf reflectance, leaf transmittance,
    soil reflectance) per band."""
    import hirad

    rng = np.random.default_rng(seed)
    s = hirad.Scene(bands=list(bands))
    leaf_rho, leaf_tau, soil_rho = [0.1, 0.45], [0.05, 0.45], [0.12, 0.3]
    s.add_material("leaf", reflectance=leaf_rho, transmittance=leaf_tau)
    s.add_material("soil", reflectance=soil_rho)
    if soil:
        s.add_triangles([[-3, -3, 0], [3, -3, 0], [3, 3, 0], [-3, 3, 0]],
                        [[0, 1, 2], [0, 2, 3]], material="soil")
    centres = rng.uniform([-1.5, -1.5, 0.2], [1.5, 1.5, 1.4], size=(leaves, 3))
    # Each leaf: a triangle in a random plane, about 8 cm across.
    a = rng.normal(size=(leaves, 3))
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(a, rng.normal(size=(leaves, 3)))
    b /= np.linalg.norm(b, axis=1, keepdims=True)
    r = 0.05
    verts = np.stack([centres + r * a,
                      centres + r * (-0.5 * a + 0.866 * b),
                      centres + r * (-0.5 * a - 0.866 * b)], axis=1).reshape(-1, 3)
    idx = np.arange(3 * leaves).reshape(leaves, 3)
    plant = np.floor((centres[:, 0] + 1.5) / 3.0 * plants).clip(0, plants - 1).astype(int)
    s.add_triangles(verts, idx, material="leaf", groups=plant)
    s.add_sun([0.3, 0.2, 0.9], [400.0, 350.0])
    if sky:
        s.add_sky(horizontal=[80.0, 60.0], rings=4)
    return s, leaf_rho, leaf_tau, soil_rho
