#!/usr/bin/env bash
# The Python module: a venv under target/ with numpy, pytest and maturin
# (from PyPI), `pip install ./python` (the README's one command; the
# extension is built by cargo into target/python-build, apart from the
# workspace's target so that it never waits on the running `cargo test`),
# then pytest of python/tests against the command line JAMKIT_BINARY.
# Usage: run.sh JAMKIT_BINARY
set -euo pipefail
jamkit=$1
root=$(cd "$(dirname "$0")/../.." && pwd)
venv=$root/target/python-venv
if ! "$venv/bin/python" -c "import numpy, pytest, maturin" 2>/dev/null; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check numpy pytest "maturin>=1.5,<2"
fi
export PATH="$venv/bin:$PATH"
export CARGO_TARGET_DIR="$root/target/python-build"
"$venv/bin/pip" install --quiet --disable-pip-version-check --no-build-isolation "$root/python"
cd "$root/target"
JAMKIT_BIN="$jamkit" "$venv/bin/python" -m pytest -q -p no:cacheprovider "$root/python/tests"
