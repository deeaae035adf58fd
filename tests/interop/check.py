"""ASE against jamkit, both ways (called by tests/interop.rs via run.sh).

1. Every packing of WORK/runs/*/packings exported by `jamkit export` is read
   by ase.io.read: N, box and positions must equal the packing file's to
   1e-12 (per sphere for bodies made of spheres, whose centres the packing
   file lists under "spheres"), radii exactly.
2. ASE writes a sphere packing (a jammed one of ours, as plain ASE Atoms
   with a radius array) as extended XYZ; `jamkit analyze` on it must give
   back the contacts and rattlers that jamkit's own run recorded.
"""
import glob
import json
import os
import subprocess
import sys

import ase.io
import numpy as np

jamkit, work = sys.argv[1], sys.argv[2]
checked = []
for path in sorted(glob.glob(os.path.join(work, "runs", "*", "packings", "*.json"))):
    p = json.load(open(path))
    xyz = path[:-5] + ".xyz"
    subprocess.run([jamkit, "export", path, "-o", xyz], check=True, capture_output=True)
    atoms = ase.io.read(xyz, format="extxyz")
    dim = p["dim"]
    if p.get("spheres"):
        want = np.array([s[:dim] for s in p["spheres"]])
        radii = np.array([s[dim] for s in p["spheres"]])
        # the export lists each body's spheres after no body line: compare
        # the sphere rows ("S") only
        mask = np.array(atoms.get_chemical_symbols()) == "S"
    else:
        want = np.array(p["positions"])
        radii = np.array(p["radii"])
        mask = np.ones(len(atoms), dtype=bool)
    got = atoms.get_positions()[mask][:, :dim]
    assert got.shape == want.shape, (path, got.shape, want.shape)
    assert np.max(np.abs(got - want)) <= 1e-12 * max(1.0, np.max(np.abs(want))), path
    assert np.array_equal(atoms.arrays["radius"][mask], radii), path
    cell = np.diag(atoms.get_cell())[:dim]
    assert np.max(np.abs(cell - np.array(p["box"]))) <= 1e-12, path
    checked.append(p["family"])
assert len(checked) >= 4, checked
print("ase read", len(checked), "packings of", sorted(set(checked)))

# 2. Files written by other code, analysed by jamkit.
spheres = sorted(glob.glob(os.path.join(work, "runs", "sphere*", "packings", "*.json")))
assert spheres, "no sphere packing to write"
for path in spheres:
    p = json.load(open(path))
    dim = p["dim"]
    want = p["measures"]

    # (a) A small script's plain text, full precision (repr): analyze must
    # find the run's own contact network.
    txt = path[:-5] + ".txt"
    with open(txt, "w") as f:
        f.write("# box " + " ".join(repr(x) for x in p["box"]) + "\n")
        for x, r in zip(p["positions"], p["radii"]):
            f.write(" ".join(repr(v) for v in list(x) + [r]) + "\n")
    out = txt + ".json"
    run = subprocess.run([jamkit, "analyze", txt, "-o", out, "--observables", "[Contacts]"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    got = json.load(open(out))["measures"]
    assert (got["n_contacts"], got["n_rattlers"]) == (want["n_contacts"], want["n_rattlers"]), (got, want)

    # (b) ase.io.write: extended XYZ with ASE's own number format (8
    # decimals): analyze must read ASE's bodies and box exactly as ASE
    # wrote them.
    pos = np.array(p["positions"])
    if dim == 2:
        pos = np.hstack([pos, np.zeros((len(pos), 1))])
    box = list(p["box"]) + ([1.0] if dim == 2 else [])
    atoms = ase.Atoms("Ar%d" % len(pos), positions=pos, cell=np.diag(box),
                      pbc=[True, True, dim == 3])
    atoms.new_array("radius", np.array(p["radii"]))
    ase_file = path[:-5] + "_ase.xyz"
    ase.io.write(ase_file, atoms, format="extxyz")
    back = ase.io.read(ase_file, format="extxyz")
    out = ase_file + ".json"
    run = subprocess.run([jamkit, "analyze", ase_file, "-o", out, "--observables", "[Contacts]"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    q = json.load(open(out))
    assert q["dim"] == dim and q["particles"] == len(atoms)
    assert np.max(np.abs(np.array(q["positions"]) - back.get_positions()[:, :dim])) <= 1e-12
    assert np.array_equal(np.array(q["radii"]), back.arrays["radius"])
    assert np.max(np.abs(np.array(q["box"]) - np.diag(back.get_cell())[:dim])) <= 1e-12
    print("analyze of %s: %d contacts as the run (plain text); ASE's file read as ASE reads it"
          % (os.path.basename(path), got["n_contacts"]))
print("analyze of files from other code: ok")
