"""pytest of the Python module against the jamkit command line.

``JAMKIT_BIN`` names the ``jamkit`` binary of the same checkout
(``tests/python/run.sh`` sets it). Every comparison with the command line
is exact: the module calls the same library, so the same experiment and
seed give the same bits.
"""

import importlib.metadata
import json
import os
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import jamkit

BIN = os.environ.get("JAMKIT_BIN", "jamkit")

NEAR_DISKS = {
    "name": "py-near-disks",
    "family": "fourier",
    "dim": 2,
    "params": {"n": 2, "delta": 0.1},
    "particles": 32,
    "samples": 2,
    "seed": 3,
    "observables": ["Contacts", "Pressure"],
}

NEAR_DISKS_RON = """(
    name: "py-near-disks",
    family: "fourier",
    dim: 2,
    params: {"n": 2, "delta": 0.1},
    particles: 32,
    samples: 2,
    seed: 3,
    observables: [Contacts, Pressure],
)"""

# The same packings with every observable of the tables.
MEASURED = dict(
    NEAR_DISKS,
    observables=["Contacts", "Pressure", {"Spectrum": {}}, {"Gaps": {}}, {"Moduli": {}}],
)


def cli(*args):
    out = subprocess.run([BIN, *args], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    return out.stdout


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The same experiment three ways: a dict, RON text through the module,
    and the RON file through the command line."""
    base = tmp_path_factory.mktemp("runs")
    from_dict = jamkit.run(NEAR_DISKS, out=base / "dict", quiet=True)
    path = base / "near_disks.ron"
    path.write_text(NEAR_DISKS_RON)
    from_file = jamkit.run(path, out=base / "file", quiet=True)
    cli("run", str(path), "--out", str(base / "cli"), "--quiet")
    from_cli = [jamkit.load(base / "cli" / "packings" / f"{p.id}.json") for p in from_file]
    return from_dict, from_file, from_cli, base


@pytest.fixture(scope="module")
def measured(tmp_path_factory):
    """The packings of ``runs`` made again with spectrum, gaps and moduli."""
    out = tmp_path_factory.mktemp("measured") / "run"
    return jamkit.run(MEASURED, out=out, quiet=True), out


def test_the_module_is_an_abi3_wheel_installed_without_cargo():
    # tests/python/run.sh builds the wheel, then installs and tests it with
    # cargo off PATH: nothing here can have been built from source.
    assert shutil.which("cargo") is None
    dist = importlib.metadata.distribution("jamkit")
    wheel = dist.read_text("WHEEL")
    assert "Root-Is-Purelib: false" in wheel and "abi3" in wheel, wheel
    meta = dist.metadata
    assert meta["License-Expression"] == "MIT OR Apache-2.0"
    assert any("Physics" in c for c in meta.get_all("Classifier"))
    assert "jamkit" in meta["Description"]
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    assert not os.path.abspath(jamkit.__file__).startswith(here)


def test_a_jammed_packing_is_the_command_lines_bit_for_bit(runs):
    from_dict, from_file, from_cli, _ = runs
    assert [p.id for p in from_dict] == [p.id for p in from_cli]
    for a, b, c in zip(from_dict, from_file, from_cli):
        for p in (a, b):
            assert p.phi == c.phi
            assert np.array_equal(p.positions, c.positions)
            assert np.array_equal(p.orientations, c.orientations)
            assert p.measures["n_contacts"] == c.measures["n_contacts"]
        # 32 near-disks (n = 2, Delta = 0.1) jam near phi_J = 0.87 at large
        # N; a box of 32 moves it by a few 0.01 (N = 256 gives
        # 0.872 +- 0.002 over 30 seeds, docs/reports/minimizers.md), so the window
        # is wide: it catches a packing that did not jam, not noise.
        assert 0.80 < a.phi < 0.93
        assert 1e-16 < a.energy_per_particle < 2e-16
        assert a.positions.shape == (32, 2) and a.orientations.shape == (32, 1)


def test_contacts_count_as_the_packing_file_counts_them(runs):
    for p in runs[0]:
        pairs, gaps = jamkit.contacts(p)
        assert pairs.shape == (len(gaps), 2) and (gaps < 0).all()
        # N_c counts the contacts among non-rattlers.
        kept = ~p.rattler[pairs[:, 0]] & ~p.rattler[pairs[:, 1]]
        assert int(kept.sum()) == p.measures["n_contacts"]
        z = np.bincount(pairs[kept].ravel(), minlength=p.particles)
        assert (z[p.rattler] == 0).all() and (z[~p.rattler] >= 3).all()


def test_contacts_and_spectrum_follow_edited_arrays(runs):
    p = jamkit.load(runs[3] / "dict" / "packings" / f"{runs[0][0].id}.json")
    pairs, gaps = jamkit.contacts(p)
    lam = jamkit.spectrum(p)["eigenvalues"]
    # Body 1 put next to body 0 at three quarters of their contact distance
    # for disks: an overlap far deeper than any contact of a jammed packing.
    direction = np.array([1.0, 0.0])
    p.positions[1] = p.positions[0] + 0.75 * (p.radii[0] + p.radii[1]) * direction
    moved, moved_gaps = jamkit.contacts(p)
    before = {tuple(sorted(r)) for r in pairs.tolist()}
    after = {tuple(sorted(r)) for r in moved.tolist()}
    assert (0, 1) in after and (0, 1) not in before
    assert moved_gaps.min() < -0.1 < gaps.min()
    assert not np.array_equal(jamkit.spectrum(p)["eigenvalues"], lam)
    # Halved sizes: no contact is left (phi is that of the arrays).
    p.radii = p.radii / 2
    assert len(jamkit.contacts(p)[0]) == 0


def test_the_spectrum_is_jamkit_spectrums(runs):
    p = runs[2][0]
    path = runs[3] / "cli" / "packings" / f"{p.id}.json"
    full = np.array([float(x) for x in cli("spectrum", str(path), "-o", "-").split()])
    stiffness = np.array(
        [float(x) for x in cli("spectrum", str(path), "--stiffness-only", "-o", "-").split()]
    )
    # The default is the Spectrum observable's: the stiffness part K.
    assert np.array_equal(jamkit.spectrum(p)["eigenvalues"], stiffness)
    s = jamkit.spectrum(p, stiffness_only=False)
    assert np.array_equal(s["eigenvalues"], full)
    assert not np.array_equal(full, stiffness)
    assert len(full) == 3 * p.particles
    # Two global translations; near-disks at Delta = 0.1 have no other
    # zero mode in a rattler-free packing.
    assert s["zero_modes"]["translations"] == 2


def test_a_packing_from_its_arrays_is_the_loaded_one(runs):
    p = runs[0][0]
    q = jamkit.Packing.from_arrays(p.family, p.params, p.positions, p.radii, p.box, p.orientations)
    assert q.phi == p.phi and q.particles == p.particles and q.dim == 2
    # V/N of the arrays against the run's V/N of the configuration in
    # memory: the file stores the angle, not its cosine and sine, which
    # moves a gap of ~1e-8 (V/N ~ 1e-16) by ~1e-16, V/N by ~1e-8 relative.
    assert abs(q.energy_per_particle - p.energy_per_particle) < 1e-6 * p.energy_per_particle
    for a, b in zip(jamkit.contacts(q), jamkit.contacts(p)):
        assert np.array_equal(a, b)
    assert np.array_equal(jamkit.spectrum(q)["eigenvalues"], jamkit.spectrum(p)["eigenvalues"])
    m = jamkit.measure(q)
    assert m.measures["n_contacts"] == p.measures["n_contacts"]
    assert np.array_equal(m.rattler, p.rattler)


def test_bad_arrays_are_jamkit_errors_naming_the_field(runs):
    p = runs[0][0]
    with pytest.raises(jamkit.JamkitError, match="positions"):
        jamkit.Packing.from_arrays(p.family, p.params, p.positions[:, :1], p.radii, p.box)
    with pytest.raises(jamkit.JamkitError, match="sizes"):
        jamkit.Packing.from_arrays(p.family, p.params, p.positions, p.radii[:5], p.box)
    bad = p.radii.copy()
    bad[3] = -1.0
    with pytest.raises(jamkit.JamkitError, match=r"radii\[3\] = -1: must be positive"):
        jamkit.Packing.from_arrays(p.family, p.params, p.positions, bad, p.box, p.orientations)
    with pytest.raises(jamkit.JamkitError, match="no_such_family"):
        jamkit.Packing.from_arrays("no_such_family", {}, p.positions, p.radii, p.box)
    with pytest.raises(jamkit.JamkitError, match="eps"):
        jamkit.jam(p, eps=-1.0)


def test_jam_from_a_looser_configuration_reaches_the_jamming_window(runs):
    p = runs[0][0]
    # The jammed packing's configuration in a box 2% wider: unjammed.
    loose = jamkit.Packing.from_arrays(
        p.family, p.params, p.positions * 1.02, p.radii, p.box * 1.02, p.orientations
    )
    assert loose.energy_per_particle == 0.0
    j = jamkit.jam(loose)
    # The Jam protocol's default window (energy_low, energy_high).
    assert 1e-16 < j.energy_per_particle < 2e-16
    assert j.measures["n_contacts"] is not None and j.measures["fire_steps"] > 0
    # From the neighbourhood of a jammed state it jams near the same phi
    # (a few 0.01 is what separate seeds differ by at N = 32).
    assert abs(j.phi - p.phi) < 0.02
    again = jamkit.jam(loose)
    assert again.phi == j.phi and np.array_equal(again.positions, j.positions)


def test_minimize_lowers_the_energy_at_fixed_phi(runs):
    p = runs[0][0]
    rng = np.random.default_rng(5)
    # 2% denser and shaken: overlapping, out of equilibrium.
    q = jamkit.Packing.from_arrays(
        p.family, p.params, p.positions / 1.02 + rng.normal(0, 0.01, p.positions.shape),
        p.radii, p.box / 1.02, p.orientations,
    )
    m = jamkit.minimize(q)
    assert abs(m.phi - q.phi) < 1e-12 * q.phi
    assert 0 < m.energy_per_particle < q.energy_per_particle
    assert m.measures["pressure"] > 0


def test_gaps_and_moduli_are_the_observables(runs, measured):
    made, _ = measured
    for p, want in zip(runs[0], made):
        assert np.array_equal(p.positions, want.positions)
        g = jamkit.gaps(p)
        assert np.array_equal(g["h"], want.measures["gaps"]["h"])
        assert np.array_equal(g["below"], want.measures["gaps"]["below"]) and g["below"][-1] > 0
        got = jamkit.moduli(p)
        expected = dict(want.measures["moduli"])
        got.pop("wall_s"), expected.pop("wall_s")
        assert got == expected
        assert got["moduli"]["shear"] > 0


def test_tables_are_the_csv_files(measured):
    _, out = measured
    for read, name in [
        (jamkit.results, "results.csv"),
        (jamkit.summary, "summary.csv"),
        (jamkit.dos_table, "dos.csv"),
        (jamkit.gaps_table, "gaps.csv"),
    ]:
        df = read(out)
        with open(out / name) as f:
            lines = f.read().splitlines()
        assert list(df.columns) == lines[0].split(",")
        assert len(df) == len(lines) - 1 > 0
    assert list(jamkit.results(out)["id"]) == [p.id for p in measured[0]]
    with pytest.raises(jamkit.JamkitError, match="dos.csv"):
        jamkit.dos_table(out / "packings")


def test_tables_without_pandas_say_what_to_install(measured, monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(ImportError, match="pip install pandas"):
        jamkit.results(measured[1])


def test_ase_round_trip(runs):
    p = runs[0][0]
    atoms = p.to_ase()
    assert atoms.get_pbc().tolist() == [True, True, False]
    assert np.allclose(atoms.positions[:, 2], 0.0)
    q = jamkit.Packing.from_ase(atoms, p.family, p.params)
    for a, b in [(q.positions, p.positions), (q.radii, p.radii), (q.box, p.box),
                 (q.orientations, p.orientations)]:
        assert a.shape == b.shape and np.max(np.abs(a - b), initial=0.0) <= 1e-12
    assert abs(q.phi - p.phi) <= 1e-12


def test_draw_and_export_xyz_are_the_command_lines(runs, tmp_path):
    p = runs[2][0]
    path = runs[3] / "cli" / "packings" / f"{p.id}.json"
    jamkit.draw(p, tmp_path / "p.png")
    cli("draw", str(path), "-o", str(tmp_path / "cli.png"))
    png = (tmp_path / "p.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and png == (tmp_path / "cli.png").read_bytes()
    jamkit.export_xyz(p, tmp_path / "p.xyz")
    cli("export", str(path), "-o", str(tmp_path / "cli.xyz"))
    assert (tmp_path / "p.xyz").read_text() == (tmp_path / "cli.xyz").read_text()


def test_export_gsd_is_the_command_lines_and_gsd_reads_it(runs, tmp_path):
    p = runs[2][0]
    path = runs[3] / "cli" / "packings" / f"{p.id}.json"
    jamkit.export_gsd(p, tmp_path / "p.gsd")
    cli("export", str(path), "-o", str(tmp_path / "cli.gsd"))
    assert (tmp_path / "p.gsd").read_bytes() == (tmp_path / "cli.gsd").read_bytes()
    import gsd.hoomd

    jamkit.export_gsd([p, p], tmp_path / "two.gsd")
    with gsd.hoomd.open(str(tmp_path / "two.gsd"), "r") as frames:
        assert len(frames) == 2
        frame = frames[1]
        assert frame.particles.N == len(p.positions)
        # HOOMD's box is centred on the origin; GSD stores float32.
        centred = p.positions[:, :2] - 0.5 * p.box[:2]
        got = frame.particles.position[:, :2].astype(np.float64)
        d = got - centred
        d -= p.box[:2] * np.round(d / p.box[:2])
        assert np.max(np.abs(d)) <= 1e-6 * np.max(p.box)


def test_progress_reports_every_sample(tmp_path):
    events = []
    made = jamkit.run(dict(NEAR_DISKS, samples=3), out=tmp_path / "run", progress=events.append)
    assert [e["done"] for e in events] == [1, 2, 3]
    assert {e["total"] for e in events} == {3}
    assert [e["id"] for e in events] == [p.id for p in made]
    assert [e["phi"] for e in events] == [p.phi for p in made]


def test_an_interrupt_keeps_the_finished_packings(tmp_path):
    experiment = dict(NEAR_DISKS, samples=4, seed=20)
    out = tmp_path / "run"

    def interrupt(event):
        raise KeyboardInterrupt

    # Raised from the progress of the first sample: with one thread, the
    # run stops before the second starts.
    with pytest.raises(KeyboardInterrupt):
        jamkit.run(experiment, out=out, progress=interrupt)
    kept = sorted(f.name for f in (out / "packings").glob("*.json"))
    assert len(kept) == 1 and not (out / "summary.csv").exists()
    events = []
    made = jamkit.run(experiment, out=out, progress=events.append)
    assert len(made) == 4 and (out / "summary.csv").exists()
    assert f"{made[0].id}.json" == kept[0]


def test_ctrl_c_raises_keyboard_interrupt_and_keeps_the_packings(tmp_path):
    out = tmp_path / "run"
    # Python turns SIGINT into KeyboardInterrupt only where it was not
    # ignored at start (a shell ignores it in background jobs): the child
    # asks for Python's own handler, as an interactive interpreter has it.
    script = (
        "import signal\n"
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "import jamkit, sys\n"
        f"jamkit.run({dict(NEAR_DISKS, samples=200)!r}, out={str(out)!r}, quiet=True)\n"
    )
    child = subprocess.Popen([sys.executable, "-c", script], stderr=subprocess.PIPE, text=True)
    packings = out / "packings"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not any(packings.glob("*_s*.json")):
        time.sleep(0.01)
    child.send_signal(signal.SIGINT)
    _, err = child.communicate(timeout=60)
    assert child.returncode != 0 and "KeyboardInterrupt" in err, err
    kept = list(packings.glob("*.json"))
    assert 1 <= len(kept) < 200
    for f in kept:
        assert jamkit.load(f).particles == 32


def test_failed_samples_come_with_the_packings_made(tmp_path):
    # Five minimiser steps converge on no sample.
    bad = dict(NEAR_DISKS, minimizer={"max_steps": 5, "newton": None})
    with pytest.raises(jamkit.JamkitError) as e:
        jamkit.run(bad, out=tmp_path / "bad", quiet=True)
    assert "2 of the samples failed" in str(e.value)
    assert e.value.packings == [] and len(e.value.failures) == 2
    assert all(id_.startswith("fourier") for id_, _ in e.value.failures)


def test_a_rerun_resumes_from_the_run_directory(runs):
    base = runs[3]
    again = jamkit.run(NEAR_DISKS, out=base / "dict", quiet=True)
    assert [p.phi for p in again] == [p.phi for p in runs[0]]


def test_bad_input_is_a_jamkit_error_naming_the_field(tmp_path):
    bad = dict(NEAR_DISKS, particles=1)
    with pytest.raises(jamkit.JamkitError) as e:
        jamkit.run(bad, out=tmp_path / "bad")
    assert "particles" in str(e.value) and "between 2" in str(e.value)
    bad = dict(NEAR_DISKS, params={"n": 2, "delta": -0.1})
    with pytest.raises(jamkit.JamkitError) as e:
        jamkit.run(bad, out=tmp_path / "bad")
    assert "delta" in str(e.value)
    with pytest.raises(jamkit.JamkitError) as e:
        jamkit.load(tmp_path / "missing.json")
    assert "missing.json" in str(e.value)
    (tmp_path / "zero.json").write_text(json.dumps({"id": "x"}))
    with pytest.raises(jamkit.JamkitError) as e:
        jamkit.load(tmp_path / "zero.json")
    assert "not a jamkit packing file" in str(e.value)
