#!/usr/bin/env bash
# CI of the Python package, run from anywhere on a fresh machine with Rust and python3: a
# virtual environment (target/python-venv), `pip install ./python` (maturin from the
# package's build-system, the extension built in release), numpy, pytest and tqdm; cargo
# fmt and clippy on the package's crate (outside the workspace, so the workspace's own
# checks do not see it), the `hirad` command line in release (the tests compare with it value
# by value), then pytest on python/tests, whose summary is the last line but one. Exits
# non-zero when anything fails.
set -euo pipefail
cd "$(dirname "$0")/.."
start=$(date +%s)
target=${CARGO_TARGET_DIR:-$PWD/target}
venv=${HIRAD_PY_VENV:-$target/python-venv}
python=${PYTHON:-python3}

echo "== python: virtual environment ($venv)"
if ! "$python" -m venv --clear "$venv"; then
  # Debian's python3 keeps venv (ensurepip) apart.
  echo "note: $python -m venv failed; installing python3-venv"
  apt-get update >/dev/null 2>&1 || true
  apt-get install -y python3-venv >/dev/null
  "$python" -m venv --clear "$venv"
fi
"$venv/bin/python" --version

echo "== python: pip install ./python numpy pytest tqdm"
"$venv/bin/pip" install --quiet --disable-pip-version-check ./python numpy pytest tqdm

echo "== python: cargo fmt and clippy on the package's crate"
(cd python && cargo fmt -- --check)
(cd python && PYO3_PYTHON="$venv/bin/python" CARGO_TARGET_DIR=$target/python-clippy \
  cargo clippy --all-targets -- -D warnings)

echo "== python: the hirad command line (release) to compare with"
CARGO_TARGET_DIR=$target cargo build --release -p hirad --bin hirad
export HIRAD_BIN=$target/release/hirad

echo "== python: pytest python/tests"
"$venv/bin/python" -m pytest python/tests -q -p no:cacheprovider
echo "python CI took $(( $(date +%s) - start )) s"
