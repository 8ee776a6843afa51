"""The package is built with the crates the CLI is built with (the same numbers)."""

import pytest

from conftest import ROOT


def test_shared_crates_have_the_root_lockfile_versions():
    tomllib = pytest.importorskip("tomllib")
    root = tomllib.loads((ROOT / "Cargo.lock").read_text())["package"]
    ours = tomllib.loads((ROOT / "python" / "Cargo.lock").read_text())["package"]
    versions = {}
    for p in root:
        versions.setdefault(p["name"], set()).add(p["version"])
    drift = [(p["name"], p["version"], sorted(versions[p["name"]])) for p in ours
             if p["name"] in versions and p["version"] not in versions[p["name"]]]
    assert not drift, (
        f"python/Cargo.lock differs from Cargo.lock in {drift}: resync it with "
        "`cp Cargo.lock python/Cargo.lock && (cd python && cargo metadata >/dev/null)`")
