"""jamkit from Python: run jamming experiments, load packings as numpy
arrays, jam, minimise and measure any packing in memory, and read a run's
tables as pandas DataFrames.

The numbers are jamkit's own (the same Rust library as the ``jamkit``
command line, bit for bit). See docs/how-to/python.md for a worked example
and docs/reference/python.md for the API.
"""

from __future__ import annotations

import json
import math
import os
import sys
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Mapping, Optional, Union

import numpy as np

from . import _native
from ._native import JamkitError

__all__ = [
    "JamkitError",
    "Packing",
    "run",
    "load",
    "contacts",
    "spectrum",
    "measure",
    "jam",
    "minimize",
    "gaps",
    "moduli",
    "results",
    "summary",
    "dos_table",
    "gaps_table",
    "draw",
    "export_xyz",
]

PathLike = Union[str, os.PathLike]


def _invalid(field_name: str, value: Any, allowed: str) -> JamkitError:
    return JamkitError(f"{field_name} = {value}: {allowed}")


def _array(name: str, value: Any, ndim: int) -> np.ndarray:
    try:
        a = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise _invalid(name, repr(value)[:60], "must be an array of numbers") from None
    if a.ndim != ndim:
        raise _invalid(name, f"an array of shape {a.shape}", f"must have {ndim} dimension(s)")
    return a


@dataclass
class Packing:
    """One packing: the values of a ``packings/<id>.json`` file.

    Arrays: ``positions`` (N x d centres), ``radii`` (N sizes R0),
    ``orientations`` (N x k orientation coordinates; k = 0 for spheres),
    ``box`` (d edge lengths), ``rattler`` (N booleans; empty if contacts
    were not measured). ``measures`` is the dict of measured values
    (``phi``, ``z_j``, ``n_contacts``, ``n_rattlers``, ``pressure``, ...),
    ``params`` the family parameters, ``settings`` everything that shaped
    the packing. Every function that takes a packing reads these
    attributes as they are when it is called.
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
        d = record["dim"]
        positions = np.asarray(record["positions"], dtype=float).reshape(-1, d)
        orientations = np.asarray(record["orientations"], dtype=float)
        if orientations.size == 0:
            orientations = np.zeros((len(positions), 0))
        return cls(
            id=record["id"],
            family=record["family"],
            dim=d,
            particles=record["particles"],
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

    @classmethod
    def from_arrays(
        cls,
        family: str,
        params: Mapping[str, Any],
        positions: Any,
        sizes: Any,
        box: Any,
        orientations: Any = None,
    ) -> "Packing":
        """A packing of ``family`` (parameters ``params``) from arrays:
        ``positions`` (N x d centres), ``sizes`` (N sizes R0), ``box``
        (d edges) and, for bodies that rotate, ``orientations`` (N x k;
        ``None``: every body in its reference orientation for k = 0
        families, required otherwise). Nothing is measured; ``phi`` and
        ``energy_per_particle`` are those of the arrays."""
        positions = _array("positions", positions, 2)
        sizes = _array("sizes", sizes, 1)
        box = _array("box", box, 1)
        n, d = positions.shape
        if d != len(box):
            raise _invalid("positions", f"an array of shape {positions.shape}",
                           f"must have one column per box edge ({len(box)})")
        if len(sizes) != n:
            raise _invalid("sizes", f"{len(sizes)} entries",
                           f"must have one entry per centre ({n})")
        if orientations is None:
            rows = []
        else:
            o = _array("orientations", orientations, 2)
            if len(o) != n:
                raise _invalid("orientations", f"an array of shape {o.shape}",
                               f"must have one row per centre ({n})")
            rows = o.tolist() if o.shape[1] > 0 else []
        record = json.loads(
            _native.from_arrays(
                str(family), json.dumps(dict(params)), positions.tolist(),
                sizes.tolist(), box.tolist(), rows,
            )
        )
        return cls._from_record(record)

    def _json(self) -> str:
        """The packing file of the attributes as they are now."""
        record = dict(self._record)
        orientations = np.asarray(self.orientations, dtype=float)
        record.update(
            id=self.id,
            family=self.family,
            dim=int(self.dim),
            seed=int(self.seed),
            params=self.params,
            phi=float(self.phi),
            energy_per_particle=_finite_or_zero(self.energy_per_particle),
            measures=self.measures,
            settings=self.settings,
            box=np.asarray(self.box, dtype=float).tolist(),
            positions=np.asarray(self.positions, dtype=float).tolist(),
            radii=np.asarray(self.radii, dtype=float).tolist(),
            orientations=orientations.tolist() if orientations.size else [],
            rattler=np.asarray(self.rattler, dtype=bool).tolist(),
        )
        record["particles"] = len(record["positions"])
        return json.dumps(record)

    def to_ase(self):
        """The packing as an ``ase.Atoms``: one atom (``B``) per body at
        its centre (``z = 0`` in 2D, where the cell's third edge is 1 and
        ``pbc`` is ``(True, True, False)``, as ``jamkit export`` writes),
        the sizes in ``arrays["radius"]``, jamkit's orientation
        coordinates in ``arrays["jamkit_orientation"]``, the rattler flags
        in ``arrays["rattler"]`` and ``id``, ``family``, ``params``,
        ``phi`` in ``info``. Needs ase."""
        ase = _optional("ase", "Packing.to_ase")
        n, d = np.asarray(self.positions).shape
        pos = np.zeros((n, 3))
        pos[:, :d] = self.positions
        cell = np.ones(3)
        cell[:d] = self.box
        atoms = ase.Atoms("B" * n, positions=pos, cell=np.diag(cell), pbc=[True, True, d == 3])
        atoms.set_array("radius", np.array(self.radii, dtype=float))
        if np.asarray(self.orientations).size:
            atoms.set_array("jamkit_orientation", np.array(self.orientations, dtype=float))
        if len(self.rattler) == n:
            atoms.set_array("rattler", np.array(self.rattler, dtype=bool))
        atoms.info.update(id=self.id, family=self.family, params=dict(self.params), phi=self.phi)
        return atoms

    @classmethod
    def from_ase(
        cls,
        atoms,
        family: str,
        params: Mapping[str, Any],
        sizes: Any = None,
        orientations: Any = None,
    ) -> "Packing":
        """A packing from an ``ase.Atoms`` with an orthorhombic cell: 2D
        when ``pbc[2]`` is false (the third coordinate dropped), else 3D.
        ``sizes`` default to ``atoms.arrays["radius"]``, ``orientations``
        to ``atoms.arrays["jamkit_orientation"]`` (both as ``to_ase``
        writes them). As ``from_arrays`` otherwise."""
        cell = np.asarray(atoms.cell[:], dtype=float)
        if np.any(cell - np.diag(np.diag(cell)) != 0.0):
            raise _invalid("atoms.cell", cell.tolist(), "must be orthorhombic (off-diagonal zero)")
        d = 3 if bool(atoms.pbc[2]) else 2
        if sizes is None:
            if "radius" not in atoms.arrays:
                raise _invalid("sizes", None, 'must be given when atoms.arrays has no "radius"')
            sizes = atoms.arrays["radius"]
        if orientations is None:
            orientations = atoms.arrays.get("jamkit_orientation")
        return cls.from_arrays(
            family, params, atoms.positions[:, :d], sizes, np.diag(cell)[:d], orientations
        )


def _finite_or_zero(x: Any) -> float:
    return float(x) if x is not None and math.isfinite(float(x)) else 0.0


def _optional(name: str, who: str):
    try:
        return __import__(name)
    except ImportError:
        raise ImportError(
            f"{who} needs the Python package `{name}`, which is not installed: pip install {name}"
        ) from None


def _stderr_progress(event: dict) -> None:
    what = (
        f"FAILED: {event['error']}" if event["error"] is not None
        else f"phi = {event['phi']:.6f}"
    )
    print(f"[{event['done']}/{event['total']}] {event['id']}: {what}", file=sys.stderr, flush=True)


def run(
    experiment: Union[PathLike, Mapping[str, Any]],
    out: Optional[PathLike] = None,
    jobs: int = 1,
    set: Optional[Iterable[str]] = None,
    progress: Optional[Callable[[dict], Any]] = None,
    quiet: bool = False,
) -> list:
    """Run an experiment and return its packings (a list of ``Packing``).

    ``experiment`` is the path of a RON experiment file, RON text, or a
    dict with the file's fields (enums as ``"Name"`` or ``{"Name": {...}}``,
    e.g. ``"protocol": {"Jam": {}}``). ``out`` is the run directory
    (default ``out/<name>``); a rerun resumes from it as ``jamkit run``
    does. ``set`` takes ``--set`` overrides (``["samples=4"]``).

    As each sample ends, ``progress`` is called with a dict ``{"done",
    "total", "id", "phi", "error"}``; without it a line per sample goes to
    stderr unless ``quiet``. The run does not hold the GIL. Ctrl-C (or an
    exception raised by ``progress``) stops it once the samples under way
    are saved and is raised then; the finished packings stay in ``out``
    and a rerun makes the rest.

    Raises ``JamkitError`` naming the field, value and what is allowed;
    when samples fail, a ``JamkitError`` whose ``packings`` are the ones
    made and ``failures`` the ``(id, message)`` of the failed samples.
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
    callback = progress if progress is not None else (None if quiet else _stderr_progress)
    done = json.loads(_native.run(text, is_json, origin, target, int(jobs), sets, callback))
    folder = os.path.join(done["out"], "packings")
    packings = [load(os.path.join(folder, f"{i}.json")) for i in done["ids"]]
    if done["failures"]:
        failures = [(f["id"], f["message"]) for f in done["failures"]]
        error = JamkitError(
            f"{len(failures)} of the samples failed: "
            + "; ".join(message for _, message in failures)
            + f" ({len(packings)} made are in {folder}; a rerun retries only the failed ones)"
        )
        error.packings = packings
        error.failures = failures
        raise error
    return packings


def load(path: PathLike) -> Packing:
    """Read a packing file (``packings/<id>.json``), checked as jamkit
    checks it."""
    return Packing._from_record(json.loads(_native.load(os.fspath(path))))


def _packing(p: Any) -> Packing:
    if not isinstance(p, Packing):
        raise _invalid("packing", type(p).__name__, "must be a jamkit.Packing")
    return p


def contacts(packing: Packing) -> tuple:
    """The contacts of ``packing`` (gap h < 0): ``(pairs, gaps)``, an
    ``(M, 2)`` int array of body indices and the M gaps. Bodies made of
    spheres may touch at several points: one row each."""
    found = json.loads(_native.contacts(_packing(packing)._json()))
    pairs = np.asarray(found["pairs"], dtype=np.int64).reshape(-1, 2)
    return pairs, np.asarray(found["gaps"], dtype=float)


def spectrum(
    packing: Packing, stiffness_only: bool = True, remove_rattlers: bool = False
) -> dict:
    """The Hessian's eigenvalues (ascending) of ``packing``, with
    ``omega = sqrt(max(lambda, 0))`` and the zero modes by origin:
    ``{"eigenvalues", "omega", "zero_modes"}``. The defaults are the
    ``Spectrum`` observable's: the stiffness part K, rattlers kept."""
    s = json.loads(
        _native.spectrum(_packing(packing)._json(), bool(stiffness_only), bool(remove_rattlers))
    )
    lam = np.asarray(s["eigenvalues"], dtype=float)
    return {
        "eigenvalues": lam,
        "omega": np.sqrt(np.clip(lam, 0.0, None)),
        "zero_modes": s["zero_modes"],
    }


def _observables(observables: Optional[Iterable[Any]]) -> str:
    return json.dumps(["Contacts", "Pressure"] if observables is None else list(observables))


def measure(packing: Packing, observables: Optional[Iterable[Any]] = None) -> Packing:
    """``packing`` with ``observables`` (an experiment file's list, as in a
    dict experiment: ``["Contacts", {"Gaps": {}}]``; default
    ``["Contacts", "Pressure"]``) measured on it as a run measures them,
    with the packing's potential and rattler rule: a new ``Packing``
    whose ``measures`` and ``rattler`` hold them."""
    p = _packing(packing)
    return Packing._from_record(json.loads(_native.measure_packing(p._json(), _observables(observables))))


def jam(
    packing: Packing,
    observables: Optional[Iterable[Any]] = None,
    minimizer: Optional[Mapping[str, Any]] = None,
    **protocol: Any,
) -> Packing:
    """The ``Jam`` protocol (the jamming search of ``jamkit run``) from the
    configuration of ``packing`` instead of a random start, then
    ``observables`` (default ``["Contacts", "Pressure"]``): the jammed
    ``Packing``. Keyword arguments are the ``Jam`` protocol's fields
    (``eps``, ``energy_low``, ``energy_high``, ``max_density_steps``,
    ``search``, ``escape_saddles``); ``minimizer`` the experiment file's
    ``minimizer`` fields. Defaults are the experiment file's."""
    return _protocol(packing, {"Jam": protocol}, minimizer, observables)


def minimize(
    packing: Packing,
    observables: Optional[Iterable[Any]] = None,
    minimizer: Optional[Mapping[str, Any]] = None,
) -> Packing:
    """The energy minimum reached from ``packing`` at its packing fraction
    (the ``Phi`` protocol at the packing's own φ: one minimisation), then
    ``observables`` (default ``["Contacts", "Pressure"]``): a new
    ``Packing``. ``minimizer`` takes the experiment file's ``minimizer``
    fields; defaults are the experiment file's."""
    p = _packing(packing)
    phi = json.loads(_native.normalize(p._json()))["phi"]
    return _protocol(p, {"Phi": {"phi": phi}}, minimizer, observables)


def _protocol(packing, protocol, minimizer, observables) -> Packing:
    p = _packing(packing)
    text = _native.run_protocol(
        p._json(), json.dumps(protocol), "" if minimizer is None else json.dumps(dict(minimizer)),
        _observables(observables),
    )
    return Packing._from_record(json.loads(text))


def gaps(packing: Packing, **params: Any) -> dict:
    """The gaps between the non-rattlers of ``packing`` as the ``Gaps``
    observable counts them (keyword arguments: its ``h_cut``, ``h_min``,
    ``points_per_decade``; defaults the observable's), with the rattlers
    of the ``Contacts`` observable: ``{"h", "below"}``, the log-spaced
    sample points h (the last is ``h_cut``) and the number of gaps
    ``0 < gap < h`` at each (the ``measures["gaps"]`` of the measured
    packing, as arrays)."""
    g = measure(packing, ["Contacts", {"Gaps": params}]).measures["gaps"]
    return {"h": np.asarray(g["h"], dtype=float), "below": np.asarray(g["below"], dtype=np.int64)}


def moduli(packing: Packing, **params: Any) -> dict:
    """The shear and bulk moduli of ``packing`` by linear response, as the
    ``Moduli`` observable measures them (keyword arguments: its
    ``omega_zero``, ``solver``; defaults the observable's), rattlers of the
    ``Contacts`` observable removed: the ``measures["moduli"]`` dict of the
    measured packing."""
    return measure(packing, ["Contacts", {"Moduli": params}]).measures["moduli"]


def draw(packing: Packing, path: PathLike, size: int = 800) -> None:
    """Draw ``packing`` to ``path`` (``.svg`` or ``.png``) as ``jamkit
    draw`` does: 2D outlines with periodic images and rattlers, or a 3D
    ray-cast seen along z. ``size``: the longer side in pixels."""
    _native.draw(_packing(packing)._json(), os.fspath(path), int(size))


def export_xyz(packing: Packing, path: PathLike) -> None:
    """Write ``packing`` to ``path`` as one frame of extended XYZ, as
    ``jamkit export`` does (for OVITO and ASE)."""
    _native.export_xyz(_packing(packing)._json(), os.fspath(path))


def export_gsd(packings: Union[Packing, Iterable[Packing]], path: PathLike) -> None:
    """Write ``packings`` (one, or several: one frame each, in order) to
    ``path`` as HOOMD-blue's GSD, as ``jamkit export … -o FILE.gsd`` does
    (for HOOMD-blue, OVITO and the ``gsd`` package; float32 positions)."""
    if isinstance(packings, Packing):
        packings = [packings]
    _native.export_gsd([_packing(p)._json() for p in packings], os.fspath(path))


def _table(directory: PathLike, name: str, written_with: str):
    pd = _optional("pandas", f"jamkit.{name.split('.')[0]}")
    path = os.path.join(os.fspath(directory), name)
    if not os.path.exists(path):
        raise _invalid("path", path, f"no such file: {name} is written by a run {written_with}")
    return pd.read_csv(path)


def results(directory: PathLike):
    """``results.csv`` of a run directory as a pandas DataFrame: one row
    per packing. Needs pandas."""
    return _table(directory, "results.csv", "(as its packings finish)")


def summary(directory: PathLike):
    """``summary.csv`` of a run directory as a pandas DataFrame: one row
    per grid point. Needs pandas."""
    return _table(directory, "summary.csv", "(at its end)")


def dos_table(directory: PathLike):
    """``dos.csv`` of a run directory, D(omega) per grid point, as a pandas
    DataFrame (columns ``point``, ``omega``, ``omega_lo``, ``omega_hi``,
    ``count``, ``dos``). Needs pandas."""
    return _table(directory, "dos.csv", "with the Spectrum observable")


def gaps_table(directory: PathLike):
    """``gaps.csv`` of a run directory, Z(h) and g(h) per grid point, as a
    pandas DataFrame (columns ``point``, ``h``, ``count_below``, ``z``,
    ``g``). Needs pandas."""
    return _table(directory, "gaps.csv", "with the Gaps observable")
