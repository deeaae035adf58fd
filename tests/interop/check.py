"""ASE and gsd against jamkit, both ways (called by tests/interop.rs via run.sh).

1. Every packing of WORK/runs/*/packings exported by `jamkit export` is read
   by ase.io.read: N, box and positions must equal the packing file's to
   1e-12 (per sphere for bodies made of spheres, whose centres the packing
   file lists under "spheres"), radii exactly.
2. Every packing exported as GSD is read by gsd.hoomd: N, dimensions,
   box, positions (HOOMD's box [-L/2, L/2), the packing's modulo L) and
   orientations (unit quaternions (w, x, y, z), up to sign) equal the
   packing file's to float32 rounding, and each type shape parses as JSON
   of the type its family's look asks for (Sphere, Ellipsoid,
   SphereUnion, Polygon, Mesh).
3. ASE writes a sphere packing (a jammed one of ours, as plain ASE Atoms
   with a radius array) as extended XYZ; `jamkit analyze` on it must give
   back the contacts and rattlers that jamkit's own run recorded.
"""
import glob
import json
import os
import subprocess
import sys

import ase.io
import gsd.hoomd
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

# 2. GSD, read by the gsd package.
# The type shape each family's look gives.
SHAPE = {"sphere": "Sphere", "ellipse": "Ellipsoid", "ellipsoid": "Ellipsoid",
         "nmer": "SphereUnion", "fourier": "Polygon", "fourier_sum": "Polygon",
         "lobed": "Polygon", "harmonic": "Mesh"}
F32 = float(np.finfo(np.float32).eps)
gsd_read, kinds = [], set()
for path in sorted(glob.glob(os.path.join(work, "runs", "*", "packings", "*.json"))):
    p = json.load(open(path))
    out = path[:-5] + ".gsd"
    subprocess.run([jamkit, "export", path, "-o", out], check=True, capture_output=True)
    with gsd.hoomd.open(out, mode="r") as traj:
        assert len(traj) == 1, (path, len(traj))
        frame = traj[0]
    dim, n, box = p["dim"], p["particles"], np.array(p["box"])
    assert frame.particles.N == n and frame.configuration.dimensions == dim, path
    want_box = np.zeros(6, dtype=np.float32)
    want_box[:dim] = box
    assert np.array_equal(frame.configuration.box, want_box), (path, frame.configuration.box)
    pos = frame.particles.position.astype(float)
    assert pos.shape == (n, 3), path
    half = frame.configuration.box[:dim].astype(float) / 2
    assert np.all(pos[:, :dim] >= -half) and np.all(pos[:, :dim] < half), path
    assert np.all(pos[:, dim:] == 0), path
    d = pos[:, :dim] + box / 2 - np.array(p["positions"])
    d -= box * np.round(d / box)
    assert np.max(np.abs(d)) <= F32 * np.max(box), (path, np.max(np.abs(d)))
    q = frame.particles.orientation.astype(float)
    for i, o in enumerate(p["orientations"] or [[]] * n):
        if len(o) == 0:
            want = np.array([1.0, 0, 0, 0])
        elif len(o) == 1:
            want = np.array([np.cos(o[0] / 2), 0, 0, np.sin(o[0] / 2)])
        else:
            want = np.array(o)
        s = np.sign(np.dot(q[i], want)) or 1.0
        assert np.max(np.abs(q[i] - s * want)) <= 2 * F32, (path, i, q[i], want)
    assert np.array_equal(frame.particles.diameter, np.float32(2 * np.array(p["radii"]))), path
    shapes = frame.particles.type_shapes
    assert len(shapes) == len(frame.particles.types) == len(set(p["radii"])), path
    for t, s in zip(frame.particles.types, shapes):
        assert s["type"] == SHAPE[p["family"]], (path, t, s["type"])
        kinds.add(s["type"])
    for i in range(n):
        name = frame.particles.types[frame.particles.typeid[i]]
        assert float(name[1:]) == p["radii"][i], (path, i, name)
    gsd_read.append(p["family"])
assert len(gsd_read) == len(checked), (gsd_read, checked)
assert {"Sphere", "Ellipsoid", "SphereUnion", "Polygon"} <= kinds, kinds
print("gsd read", len(gsd_read), "packings with type shapes", sorted(kinds))

# 3. Files written by other code, analysed by jamkit.
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
