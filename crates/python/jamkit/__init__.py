"""jamkit from Python: run jamming experiments, load packings as numpy
arrays, and measure contacts and vibrational spectra of a packing in memory.

The numbers are jamkit's own (the same Rust library as the ``jamkit``
command line, bit for bit). See docs/how-to/python.md for a worked example
and docs/reference/python.md for the API.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping, Optional, Union

import numpy as np

from . import _native
from ._native import JamkitError

__all__ = ["JamkitError", "Packing", "run", "load", "contacts", "spectrum"]


@dataclass
class Packing:
    """One packing, as its ``packings/<id>.json`` file holds it.

    Arrays: ``positions`` (N x d centres in the primary cell), ``radii``
    (N sizes R0), ``orientations`` (N x k orientation coordinates; k = 0
    for spheres), ``box`` (d edge lengths), ``rattler`` (N booleans; empty
    if contacts were not measured). ``measures`` is the dict of measured
    values (``phi``, ``z_j``, ``n_contacts``, ``n_rattlers``, ``pressure``,
    ...), ``params`` the family parameters, ``settings`` everything that
    shaped the packing.
    """

    id: str
    family: str
    dim: int
    particles: int
    seed: int
    params: dict
    phi: float
    energy_per_particle: float
    measures: dict
    box: np.ndarray
    positions: np.ndarray
    radii: np.ndarray
    orientations: np.ndarray
    rattler: np.ndarray
    settings: dict
    _record: dict = field(repr=False)

    @classmethod
    def _from_record(cls, record: dict) -> "Packing":
        n, d = record["particles"], record["dim"]
        positions = np.asarray(record["positions"], dtype=float).reshape(-1, d)
        orientations = np.asarray(record["orientations"], dtype=float)
        if orientations.size == 0:
            orientations = np.zeros((len(positions), 0))
        return cls(
            id=record["id"],
            family=record["family"],
            dim=d,
            particles=n,
            seed=record["seed"],
            params=record["params"],
            phi=record["phi"],
            energy_per_particle=record["energy_per_particle"],
            measures=record["measures"],
            box=np.asarray(record["box"], dtype=float),
            positions=positions,
            radii=np.asarray(record["radii"], dtype=float),
            orientations=orientations,
            rattler=np.asarray(record["rattler"], dtype=bool),
            settings=record["settings"],
            _record=record,
        )

    def _json(self) -> str:
        return json.dumps(self._record)


def run(
    experiment: Union[str, os.PathLike, Mapping[str, Any]],
    out: Optional[Union[str, os.PathLike]] = None,
    jobs: int = 1,
    set: Optional[Iterable[str]] = None,
) -> list:
    """Run an experiment and return its packings (a list of ``Packing``).

    ``experiment`` is the path of a RON experiment file, RON text, or a
    dict with the file's fields (enums as ``"Name"`` or ``{"Name": {...}}``,
    e.g. ``"protocol": {"Jam": {}}``). ``out`` is the run directory
    (default ``out/<name>``); a rerun resumes from it as ``jamkit run``
    does. ``set`` takes ``--set`` overrides (``["samples=4"]``). Raises
    ``JamkitError`` naming the field, value and what is allowed.
    """
    sets = [str(s) for s in (set or [])]
    if isinstance(experiment, Mapping):
        text, is_json, origin = json.dumps(experiment), True, "<dict>"
    elif os.path.exists(os.fspath(experiment)):
        path = os.fspath(experiment)
        with open(path, encoding="utf-8") as f:
            text, is_json, origin = f.read(), False, path
    else:
        text, is_json, origin = str(experiment), False, "<text>"
    target = None if out is None else os.fspath(out)
    done = json.loads(_native.run(text, is_json, origin, target, int(jobs), sets))
    folder = os.path.join(done["out"], "packings")
    return [load(os.path.join(folder, f"{i}.json")) for i in done["ids"]]


def load(path: Union[str, os.PathLike]) -> Packing:
    """Read a packing file (``packings/<id>.json``), checked as jamkit
    checks it."""
    return Packing._from_record(json.loads(_native.load(os.fspath(path))))


def contacts(packing: Packing) -> tuple:
    """The contacts of ``packing`` (gap h < 0): ``(pairs, gaps)``, an
    ``(M, 2)`` int array of body indices and the M gaps. Bodies made of
    spheres may touch at several points: one row each."""
    found = json.loads(_native.contacts(packing._json()))
    pairs = np.asarray(found["pairs"], dtype=np.int64).reshape(-1, 2)
    return pairs, np.asarray(found["gaps"], dtype=float)


def spectrum(
    packing: Packing, stiffness_only: bool = False, remove_rattlers: bool = False
) -> dict:
    """The Hessian's eigenvalues (ascending) of ``packing``, as
    ``jamkit spectrum`` gives them, with ``omega = sqrt(max(lambda, 0))``
    and the zero modes by origin: ``{"eigenvalues", "omega",
    "zero_modes"}``."""
    s = json.loads(
        _native.spectrum(packing._json(), bool(stiffness_only), bool(remove_rattlers))
    )
    lam = np.asarray(s["eigenvalues"], dtype=float)
    return {
        "eigenvalues": lam,
        "omega": np.sqrt(np.clip(lam, 0.0, None)),
        "zero_modes": s["zero_modes"],
    }
