#!/usr/bin/env bash
# The Python module: a venv under target/ with numpy, pytest and maturin
# (from PyPI), `pip install ./crates/python` (the README's one command; the
# extension is built by cargo into target/python-build, apart from the
# workspace's target so that it never waits on the running `cargo test`),
# then the ```python blocks of docs/how-to/python.md in order as one script
# (in a scratch directory where the repository's experiments/ is visible,
# with pandas), then pytest of crates/python/tests against the command line
# JAMKIT_BINARY.
# Usage: run.sh JAMKIT_BINARY
set -euo pipefail
jamkit=$1
root=$(cd "$(dirname "$0")/../.." && pwd)
venv=$root/target/python-venv
if ! "$venv/bin/python" -c "import numpy, pandas, pytest, maturin" 2>/dev/null; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check numpy pandas pytest "maturin>=1.5,<2"
fi
export PATH="$venv/bin:$PATH"
export CARGO_TARGET_DIR="$root/target/python-build"
"$venv/bin/pip" install --quiet --disable-pip-version-check --no-build-isolation "$root/crates/python"
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
ln -s "$root/experiments" "$scratch/experiments"
awk '/^```python$/ {on = 1; next} /^```/ {on = 0} on' "$root/docs/how-to/python.md" > "$scratch/manual.py"
[ -s "$scratch/manual.py" ] || { echo "no python blocks in docs/how-to/python.md" >&2; exit 1; }
(cd "$scratch" && "$venv/bin/python" manual.py >&2) || { echo "the Python of docs/how-to/python.md failed" >&2; exit 1; }
cd "$root/target"
JAMKIT_BIN="$jamkit" "$venv/bin/python" -m pytest -q -p no:cacheprovider "$root/crates/python/tests"
