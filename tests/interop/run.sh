#!/usr/bin/env bash
# The physicist's tools read what jamkit writes, and jamkit reads theirs:
# a venv with ASE and gsd (from PyPI) under target/, then
# tests/interop/check.py.
# Usage: run.sh JAMKIT_BINARY WORK_DIR
set -euo pipefail
jamkit=$1
work=$2
root=$(cd "$(dirname "$0")/../.." && pwd)
venv=$root/target/interop-venv
if ! "$venv/bin/python" -c "import ase, gsd.hoomd" 2>/dev/null; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check "ase>=3.22" "gsd>=3" numpy
fi
"$venv/bin/python" "$root/tests/interop/check.py" "$jamkit" "$work"
