#!/usr/bin/env python3
"""Tables and power-law fits of the moduli runs of docs/reports/elasticity.md.

    python3 experiments/elasticity/fit.py [--x p|dphi] [--pmin X] [--pmax X] [--same-seeds] DIR...

Reads `results.csv` of every DIR (one run per pressure, made with
`--set protocol.pressure=<p>`, or with `--x dphi` one `AboveJam` run per
delta_phi, read from the DIR's `experiment.ron`, or from the packing ids'
`_dphi<value>` label when the file scans a list of delta_phi; the same
packing (id and x) met in two DIRs is counted once), groups the packings by
family parameters and x (target pressure or delta_phi), and prints per
group: x, the mean pressure, phi, z_J,
dz = 2 iso_margin / N_nr (= z - z_iso with the finite-N isostatic count),
G, B and G/B (mean +- s.e.m. over the packings), z - z_J against the
packing's own jamming point (`AboveJam` runs, columns jam_z), how many
packings have
G < 0, and the largest number of negative modes and extra zero modes;
then per group the packings with G or B not finite, with G < 0, the
smallest B and the largest floppy share (and, where the run has the
column, the packings with G_min < 0), and (--x dphi) per delta_phi the
packings whose pressure is below half the point's median (a packing that
rearranged on its way up sits closer to its new jamming point than
delta_phi says).
Then weighted least-squares fits (weights 1/(s.e.m./mean)^2, on logs) of
G ~ x^a, G/B ~ dz^c, dz ~ x^e, p ~ x^b, z - z_J ~ x^f and (x = dphi) G and
z - z_J against each point's mean p, over pmin <= x <= pmax, with the slope's
standard error from the weights and chi^2 per degree of freedom. With
--same-seeds, each group keeps only the seeds that have a packing at
every x (samples that failed at one x drop out of all). Only the
standard library.
"""
import argparse
import csv
import math
import os
import re
from collections import defaultdict


def mean_sem(xs):
    n = len(xs)
    m = sum(xs) / n
    if n < 2:
        return m, 0.0
    return m, math.sqrt(sum((x - m) ** 2 for x in xs) / ((n - 1) * n))


def write_csv(path, columns, rows):
    """Write `rows` (dicts) as CSV with `columns`, floats as `%.6e`."""
    with open(path, "w") as out:
        out.write(",".join(columns) + "\n")
        for r in rows:
            out.write(",".join(
                f"{r[c]:.6e}" if isinstance(r[c], float) else str(r[c]) for c in columns
            ) + "\n")


def wls(xs, ys, sigmas):
    """Slope, its standard error and chi^2/dof of a weighted line fit."""
    w = [1.0 / s**2 for s in sigmas]
    sw = sum(w)
    mx = sum(wi * x for wi, x in zip(w, xs)) / sw
    my = sum(wi * y for wi, y in zip(w, ys)) / sw
    sxx = sum(wi * (x - mx) ** 2 for wi, x in zip(w, xs))
    sxy = sum(wi * (x - mx) * (y - my) for wi, x, y in zip(w, xs, ys))
    a = sxy / sxx
    b = my - a * mx
    chi2 = sum(wi * (y - a * x - b) ** 2 for wi, x, y in zip(w, xs, ys))
    return a, math.sqrt(1.0 / sxx), chi2 / max(len(xs) - 2, 1)


PARAMS = ("n", "delta", "aspect", "alpha")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--x", choices=["p", "dphi"], default="p")
    ap.add_argument("--pmin", type=float, default=0.0)
    ap.add_argument("--pmax", type=float, default=math.inf)
    ap.add_argument("--same-seeds", action="store_true")
    ap.add_argument("dirs", nargs="+")
    args = ap.parse_args()
    groups = defaultdict(list)
    seen = set()
    for d in args.dirs:
        packings = os.path.join(d, "packings")
        failed = [f for f in os.listdir(packings) if f.endswith(".failed.json")] if os.path.isdir(packings) else []
        if failed:
            print(f"{d}: {len(failed)} failed samples ({', '.join(sorted(failed))})")
        dphi = None
        if args.x == "dphi":
            with open(os.path.join(d, "experiment.ron")) as f:
                one = re.search(r"delta_phi: *([0-9.eE+-]+)", f.read())
            # a single delta_phi; a list (one file scanning delta_phi) is read
            # from each packing's id, whose label ends in `_dphi<value>`
            dphi = float(one.group(1)) if one else None
        with open(os.path.join(d, "results.csv")) as f:
            for r in csv.DictReader(f):
                key = (r["family"], r["particles"]) + tuple(
                    f"{k}={r[k]}" for k in PARAMS if k in r
                )
                if args.x == "p":
                    target = round(math.log10(float(r["pressure"])), 1)
                elif dphi is not None:
                    target = dphi
                else:
                    target = float(re.search(r"_dphi([0-9.eE+-]+)_s[0-9]+$", r["id"]).group(1))
                if (r["id"], target) in seen:
                    continue  # the same packing in two runs (a run and its rerun with more samples)
                seen.add((r["id"], target))
                groups[key].append((target, r))
    for key, items in sorted(groups.items()):
        if args.same_seeds:
            # only the seeds with a packing at every x of the group (a sample
            # that failed at one x leaves the group at all of them)
            xs = {t for t, _ in items}
            every = set.intersection(*({r["seed"] for t, r in items if t == x} for x in xs))
            items = [(t, r) for t, r in items if r["seed"] in every]
        by_p = defaultdict(list)
        for target, r in items:
            by_p[target].append(r)
        print("## " + " ".join(key))
        if args.same_seeds:
            print(f"(same seeds: the {len(every)} seeds with a packing at every {args.x})")
        print(f"{args.x} | p | phi | z_J | dz | z - z_J | G | B | G/B | G<0 | packings | neg. modes | extra zero")
        points = []
        for target in sorted(by_p):
            rs = by_p[target]
            f = lambda name: [float(r[name]) for r in rs]
            p = mean_sem(f("pressure"))
            x = p[0] if args.x == "p" else target
            g, b = mean_sem(f("G")), mean_sem(f("B"))
            gb = mean_sem([float(r["G"]) / float(r["B"]) for r in rs if float(r["B"]) != 0])
            dz = mean_sem(
                [
                    2 * int(r["iso_margin"]) / (int(r["particles"]) - int(r["n_rattlers"]))
                    for r in rs
                ]
            )
            above = [float(r["z_j"]) - float(r["jam_z"]) for r in rs if r.get("jam_z")]
            zz = mean_sem(above) if above else (math.nan, math.nan)
            print(
                f"{x:.2e} | {p[0]:.2e} | {mean_sem(f('phi_j'))[0]:.4f} | {mean_sem(f('z_j'))[0]:.3f}"
                f" | {dz[0]:.4f} ± {dz[1]:.1e} | {zz[0]:.4f} ± {zz[1]:.1e} | {g[0]:.3e} ± {g[1]:.1e}"
                f" | {b[0]:.4f} ± {b[1]:.1e} | {gb[0]:.3e} ± {gb[1]:.1e}"
                f" | {sum(x < 0 for x in f('G'))} | {len(rs)}"
                f" | {max(int(r['moduli_negative_modes']) for r in rs)}"
                f" | {max(int(r['moduli_zero_extra']) for r in rs)}"
            )
            points.append((x, g, gb, dz, p, zz))
        rs = [r for _, r in items]
        finite = [r for r in rs if math.isfinite(float(r["G"])) and math.isfinite(float(r["B"]))]
        print(
            f"{len(rs)} packings: {len(rs) - len(finite)} with G or B not finite,"
            f" {sum(float(r['G']) < 0 for r in finite)} with G < 0,"
            f" smallest B {min(float(r['B']) for r in finite):.3g},"
            f" largest floppy share {max(float(r['moduli_floppy_share']) for r in rs):.1e}"
        )
        # runs made since G_min was measured: packings unstable to the shear
        # of one plane (also where the mean G is positive)
        mins = [r for r in finite if r.get("G_min")]
        if mins:
            neg = sum(float(r["G_min"]) < 0 for r in mins)
            print(f"G_min < 0 on {neg} of {len(mins)} packings")
        if args.x == "dphi":
            # a packing that rearranged on the way up into a state jamming
            # above its phi_J sits closer to its new jamming point than
            # dphi says: its pressure is low for its dphi
            low = []
            for target in sorted(by_p):
                ps = sorted(float(r["pressure"]) for r in by_p[target])
                median = ps[len(ps) // 2]
                low.append(f"{target:g}: {sum(q < 0.5 * median for q in ps)}/{len(ps)}")
            print("p below half the point's median p (rearranged on the way up): " + ", ".join(low))
        sel = [t for t in points if args.pmin <= t[0] <= args.pmax]
        fits = [
            (f"G ~ {args.x}^a", lambda t: (t[0], t[1][0], t[1][1])),
            ("G/B ~ dz^c", lambda t: (t[3][0], t[2][0], t[2][1])),
            (f"dz ~ {args.x}^e", lambda t: (t[0], t[3][0], t[3][1])),
        ]
        if args.x == "dphi":
            fits.append(("p ~ dphi^b", lambda t: (t[0], t[4][0], t[4][1])))
            # G against the points' mean pressure (the x of the Pressure runs)
            fits.append(("G ~ p^a (mean p of each dphi)", lambda t: (t[4][0], t[1][0], t[1][1])))
            fits.append(("z - z_J ~ dphi^f", lambda t: (t[0], t[5][0], t[5][1])))
            fits.append(("z - z_J ~ p^f (mean p of each dphi)", lambda t: (t[4][0], t[5][0], t[5][1])))
        for name, pick in fits:
            xyz = [pick(t) for t in sel]
            if len(xyz) < 3 or any(not (x > 0 and y > 0 and s > 0) for x, y, s in xyz):
                print(f"{name}: no fit (fewer than 3 points, or a mean <= 0 in range)")
                continue
            a, se, chi2 = wls(
                [math.log(x) for x, _, _ in xyz],
                [math.log(y) for _, y, _ in xyz],
                [s / y for _, y, s in xyz],
            )
            print(
                f"{name}: exponent {a:.3f} ± {se:.3f} (chi2/dof {chi2:.2f}),"
                f" {len(xyz)} points, {args.pmin:g} <= {args.x} <= {args.pmax:g}"
            )
        print()


if __name__ == "__main__":
    main()
