"""The notebook docs/notebooks/first-study.ipynb, executed top to bottom by
nbclient in a scratch directory (``JAMKIT_NOTEBOOKS`` names the folder;
``tests/python/run.sh`` sets it): a cell that fails fails the test, and
the three figures the notebook writes must exist afterwards."""

import os
import pathlib

import nbformat
from nbclient import NotebookClient

FOLDER = pathlib.Path(os.environ.get("JAMKIT_NOTEBOOKS", "docs/notebooks"))


def test_the_first_study_notebook_runs(tmp_path, monkeypatch):
    monkeypatch.setenv("MPLBACKEND", "Agg")
    nb = nbformat.read(FOLDER / "first-study.ipynb", as_version=4)
    client = NotebookClient(
        nb, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    )
    client.execute()
    for name in ["phi_j.png", "dos.png", "packing.png"]:
        png = (tmp_path / name).read_bytes()
        assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 1000, name
    # The last cell shows the packing's picture inline.
    assert "image/png" in nb.cells[-1].outputs[-1]["data"]
