#!/usr/bin/env bash
# The Python module as a user gets it: `maturin build --release` makes the
# abi3 wheel (the extension built by cargo into target/python-build, apart
# from the workspace's target so that it never waits on the running
# `cargo test`), then a test venv without cargo on PATH and without
# maturin installs that wheel (pip from the wheel file only) and runs, in
# order: the ```python blocks of docs/how-to/python.md as one script (in a
# scratch directory where the repository's experiments/ is visible), and
# pytest of crates/python/tests (against the command line JAMKIT_BINARY,
# with the notebooks of docs/notebooks executed by nbclient).
# Usage: run.sh JAMKIT_BINARY
set -euo pipefail
jamkit=$1
root=$(cd "$(dirname "$0")/../.." && pwd)
quiet=(--quiet --disable-pip-version-check)
build=$root/target/python-build-venv
if ! "$build/bin/python" -c "import maturin" 2>/dev/null; then
    python3 -m venv "$build"
    "$build/bin/pip" install "${quiet[@]}" "maturin>=1.9,<2"
fi
venv=$root/target/python-venv
if ! "$venv/bin/python" -c "import numpy, pandas, pytest, ase, gsd, matplotlib, nbclient, ipykernel" 2>/dev/null; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install "${quiet[@]}" numpy pandas pytest "ase>=3.22" "gsd>=3" matplotlib nbclient ipykernel
fi
wheels=$root/target/python-wheels
rm -rf "$wheels"
CARGO_TARGET_DIR="$root/target/python-build" "$build/bin/maturin" build --release --quiet \
    --manifest-path "$root/crates/python/Cargo.toml" --out "$wheels"
wheel=$(ls "$wheels"/jamkit-*-abi3-*.whl)
# PATH without any directory holding cargo: the wheel installs and runs
# without a Rust toolchain.
nocargo=$(tr ':' '\n' <<<"$PATH" | while read -r d; do [ -x "$d/cargo" ] || echo "$d"; done | paste -sd:)
export PATH="$venv/bin:$nocargo"
"$venv/bin/pip" install "${quiet[@]}" --no-index --no-deps --force-reinstall "$wheel"
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
ln -s "$root/experiments" "$scratch/experiments"
awk '/^```python$/ {on = 1; next} /^```/ {on = 0} on' "$root/docs/how-to/python.md" > "$scratch/manual.py"
[ -s "$scratch/manual.py" ] || { echo "no python blocks in docs/how-to/python.md" >&2; exit 1; }
(cd "$scratch" && MPLBACKEND=Agg "$venv/bin/python" manual.py >&2) || { echo "the Python of docs/how-to/python.md failed" >&2; exit 1; }
cd "$root/target"
JAMKIT_BIN="$jamkit" JAMKIT_NOTEBOOKS="$root/docs/notebooks" \
    "$venv/bin/python" -m pytest -q -p no:cacheprovider "$root/crates/python/tests"
