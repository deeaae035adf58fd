#!/usr/bin/env python3
"""Sparse against Dense shear stabilisation: are the two ensembles the same?
(docs/reports/elasticity.md, "Sparse against Dense").

    python3 experiments/elasticity/solvers.py \
        --dense STAB.csv POINTS.csv --sparse STAB.csv POINTS.csv \
        [--boot 4000] [--seed 1] [--range DELTA:LO:HI]... [--csv OUT.csv]

STAB.csv: the per-packing tables of `stabilised.py --csv`; POINTS.csv: the
per-point tables of `crossover.py --csv` (for z_stab - z_J, which needs the
packing's own jamming point, not in the per-packing table). The two runs
are the same experiment file with another `Moduli(solver: ...)`, so the
fixed-box packings are the same (checked here: G, B and z of the fixed box
per packing id, to the tables' 7 digits) and only the stabilisation's path
can differ.

Prints, per point (family, delta_phi):
* the unpaired comparison of the two ensembles: mean +- s.e.m. of the
  stabilised G, B, p, z_stab - z_J and the strain steps, and the difference
  Sparse - Dense in units of its standard error sqrt(se_D^2 + se_S^2);
* the paired one, packing by packing (same id): how many have the same
  fixed box, how many took the same path (stabilised G, B and z_stab equal
  to the tables' precision, relative 1e-5, and the same number of strain
  steps), how many more ended in the same state by another number of steps
  (G to 1e-3 relative, z_stab exactly), the largest |G_S/G_D - 1| of the
  others (another state), and the mean paired difference of G +- its s.e.
  (in units of it);
* slopes d ln G_stab / d ln delta_phi (least squares on the log of the
  means, as crossover.py) over each --range for both solvers, +- the s.d.
  over --boot bootstrap replicas resampling each point's packings, and the
  difference S - D +- the s.d. of a paired bootstrap (the same resampled
  packing ids for both).
--csv writes the per-point comparison. Only the standard library.
"""
import argparse
import csv
import math
import os
import random
import sys
from collections import defaultdict

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fit import mean_sem, write_csv  # noqa: E402
from crossover import slope  # noqa: E402  (crossover.py's fit, so the slopes are its own)

# A packing "took the same path" if these agree to SAME relative (the
# tables are written to 7 significant digits, so 1e-5 is well above their
# rounding and far below any difference of a path) in the same number of
# strain steps; it "ended in the same state" if G agrees to NEAR and the
# cell's contacts exactly (one strain step more or less near convergence
# moves G by 1e-6..1e-5).
SAME = 1e-5
NEAR = 1e-3
# The slope table's ranges, per Δ (docs/reports/elasticity.md, "Near-disks
# across δφ ∼ Δ"): below the bend (δφ = 1e-5 … 1e-3; … 1e-2 for
# Δ = 0.03), above it (1e-2 … 1e-1), and all of Δ = 0.003's.
RANGES = [
    "0.003:1e-5:1e-3", "0.003:1e-2:1e-1", "0.003:1e-5:1e-1",
    "0.01:1e-5:1e-3", "0.01:1e-2:1e-1",
    "0.03:1e-5:1e-2", "0.03:1e-2:1e-1",
]


def delta_of(family):
    for word in family.split():
        if word.startswith("delta="):
            return float(word[len("delta="):])
    return None  # disks


def read_stab(path):
    """Per-packing rows keyed by id; numbers as floats."""
    rows = {}
    for r in csv.DictReader(open(path)):
        out = dict(r)
        for k in ("x", "p", "G_fixed", "G", "B_fixed", "B", "z_fixed", "z_stab", "iterations"):
            out[k] = float(r[k]) if r[k] != "" else None
        out["delta"] = delta_of(r["family"])
        rows[r["id"]] = out
    return rows


def read_points(path):
    """Per-point z_stab - z_J (mean, s.e.m., packings) keyed by (delta, delta_phi)."""
    points = {}
    for r in csv.DictReader(open(path)):
        if r["dz_stab"] == "":
            continue
        key = (delta_of(r["family"]), float(r["delta_phi"]))
        points[key] = (float(r["dz_stab"]), float(r["dz_stab_sem"]), int(r["packings"]))
    return points


def rel(a, b):
    return abs(a - b) / max(abs(a), abs(b), 1e-300)


def sd(xs):
    m = sum(xs) / len(xs)
    return math.sqrt(sum((x - m) ** 2 for x in xs) / (len(xs) - 1))


def slopes(dense, sparse, delta, lo, hi, boot, rng):
    """Slopes of G_stab over lo <= delta_phi <= hi for both solvers with
    their bootstrap s.d., and the paired bootstrap s.d. of S - D."""
    def by_point(rows):
        g = defaultdict(dict)
        for i, r in rows.items():
            if r["delta"] == delta and lo * (1 - 1e-9) <= r["x"] <= hi * (1 + 1e-9):
                g[r["x"]][i] = r["G"]
        return g
    gd, gs = by_point(dense), by_point(sparse)
    xs = sorted(set(gd) & set(gs))
    if len(xs) < 2:
        return None
    mean = lambda v: sum(v) / len(v)
    best_d = slope(xs, [mean(list(gd[x].values())) for x in xs])
    best_s = slope(xs, [mean(list(gs[x].values())) for x in xs])
    common = {x: sorted(set(gd[x]) & set(gs[x])) for x in xs}
    rd, rs, rdiff = [], [], []
    for _ in range(boot):
        md, ms, pd, ps = [], [], [], []
        for x in xs:
            vd, vs = list(gd[x].values()), list(gs[x].values())
            md.append(mean([rng.choice(vd) for _ in vd]))
            ms.append(mean([rng.choice(vs) for _ in vs]))
            ids = [rng.choice(common[x]) for _ in common[x]]
            pd.append(mean([gd[x][i] for i in ids]))
            ps.append(mean([gs[x][i] for i in ids]))
        if min(md + ms + pd + ps) <= 0:
            continue
        rd.append(slope(xs, md))
        rs.append(slope(xs, ms))
        rdiff.append(slope(xs, ps) - slope(xs, pd))
    return xs, best_d, sd(rd), best_s, sd(rs), sd(rdiff)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dense", nargs=2, required=True, metavar=("STAB", "POINTS"))
    ap.add_argument("--sparse", nargs=2, required=True, metavar=("STAB", "POINTS"))
    ap.add_argument("--boot", type=int, default=4000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--range", action="append", default=[], help="DELTA:LO:HI (default, per Delta: 1e-5:1e-3 below the bend, 1e-5:1e-2 for Delta = 0.03, 1e-2:1e-1 above it, and 1e-5:1e-1 for Delta = 0.003)")
    ap.add_argument("--csv", help="write the per-point comparison here")
    args = ap.parse_args()
    rng = random.Random(args.seed)
    dense, sparse = read_stab(args.dense[0]), read_stab(args.sparse[0])
    zd, zs = read_points(args.dense[1]), read_points(args.sparse[1])

    # The fixed-box packings must be the same: the runs differ only in the
    # solver of the stabilisation.
    common = sorted(set(dense) & set(sparse))
    only_s = sorted(set(sparse) - set(dense))
    fixed_diff = [
        i for i in common
        if rel(dense[i]["G_fixed"], sparse[i]["G_fixed"]) > SAME
        or rel(dense[i]["B_fixed"], sparse[i]["B_fixed"]) > SAME
        or dense[i]["z_fixed"] != sparse[i]["z_fixed"]
    ]
    worst_fixed = max((rel(dense[i]["G_fixed"], sparse[i]["G_fixed"]) for i in common), default=0.0)
    print(f"{len(sparse)} Sparse packings, {len(common)} of them in the Dense table; "
          f"only in Sparse: {len(only_s)}")
    print(f"fixed box: {len(common) - len(fixed_diff)} of {len(common)} the same "
          f"(G_fixed, B_fixed to {SAME:g}, z_fixed exactly; largest |dG_fixed|/G_fixed "
          f"{worst_fixed:.1e}, the tables' rounding is 5e-7)")
    for i in fixed_diff:
        print(f"  fixed box differs: {i}: G_fixed {dense[i]['G_fixed']:.6e} / {sparse[i]['G_fixed']:.6e}")

    groups = defaultdict(list)
    for i in common:
        groups[(sparse[i]["family"], sparse[i]["delta"], sparse[i]["x"])].append(i)

    quantities = [("G", "G stab."), ("B", "B stab."), ("p", "p"), ("iterations", "strain steps")]
    print("\n## Unpaired: mean ± s.e.m. per ensemble, (S − D)/s.e.")
    print("| family | δφ | n D/S | " + " | ".join(
        f"{name} Dense | {name} Sparse | (S−D)/se" for _, name in quantities)
        + " | z_stab − z_J Dense | Sparse | (S−D)/se |")
    print("|---|---|---|" + "---|---|---|" * (len(quantities) + 1))
    out = []
    for (fam, delta, x) in sorted(groups, key=lambda k: (k[1] is None, k[1] or 0, k[2])):
        ds = [r for r in dense.values() if r["family"] == fam and r["x"] == x]
        ss = [r for r in sparse.values() if r["family"] == fam and r["x"] == x]
        row = {"family": fam, "delta_phi": x, "n_dense": len(ds), "n_sparse": len(ss)}
        cells = []
        for q, _ in quantities:
            md, ed = mean_sem([r[q] for r in ds])
            ms, es = mean_sem([r[q] for r in ss])
            se = math.hypot(ed, es)
            t = (ms - md) / se if se > 0 else (0.0 if ms == md else math.inf)
            row.update({f"{q}_dense": md, f"{q}_dense_sem": ed, f"{q}_sparse": ms,
                        f"{q}_sparse_sem": es, f"{q}_t": t})
            fmt = ".1f" if q == "iterations" else ".3e"
            cells.append(f"{md:{fmt}} ± {ed:.1g} | {ms:{fmt}} ± {es:.1g} | {t:+.2f}")
        if (delta, x) in zd and (delta, x) in zs:
            (md, ed, _), (ms, es, _) = zd[(delta, x)], zs[(delta, x)]
            se = math.hypot(ed, es)
            t = (ms - md) / se if se > 0 else 0.0
            row.update({"dz_stab_dense": md, "dz_stab_dense_sem": ed, "dz_stab_sparse": ms,
                        "dz_stab_sparse_sem": es, "dz_stab_t": t})
            cells.append(f"{md:.4f} ± {ed:.4f} | {ms:.4f} ± {es:.4f} | {t:+.2f}")
        else:
            row.update({k: "" for k in ("dz_stab_dense", "dz_stab_dense_sem", "dz_stab_sparse",
                                        "dz_stab_sparse_sem", "dz_stab_t")})
            cells.append("– | – | –")
        print(f"| {fam} | {x:g} | {len(ds)}/{len(ss)} | " + " | ".join(cells) + " |")
        out.append(row)

    print("\n## Paired, packing by packing (same id)")
    print("| family | δφ | pairs | same path | same state | other state: max abs(G_S/G_D − 1) "
          "| mean G_S − G_D ± s.e. (in s.e.) | steps S − D (range) | z_stab S − D (range) |")
    print("|---|---|---|---|---|---|---|---|---|")
    total_same, total_near, total = 0, 0, 0
    all_rel = []
    for k, row in zip(sorted(groups, key=lambda k: (k[1] is None, k[1] or 0, k[2])), out):
        fam, delta, x = k
        ids = groups[k]
        same = [
            i for i in ids
            if rel(dense[i]["G"], sparse[i]["G"]) < SAME and rel(dense[i]["B"], sparse[i]["B"]) < SAME
            and dense[i]["z_stab"] == sparse[i]["z_stab"]
            and dense[i]["iterations"] == sparse[i]["iterations"]
        ]
        near = [
            i for i in ids
            if i not in same and rel(dense[i]["G"], sparse[i]["G"]) < NEAR
            and dense[i]["z_stab"] == sparse[i]["z_stab"]
        ]
        others = [abs(sparse[i]["G"] / dense[i]["G"] - 1) for i in ids if i not in same + near]
        all_rel += others
        diffs = [sparse[i]["G"] - dense[i]["G"] for i in ids]
        md, ed = mean_sem(diffs)
        t = md / ed if ed > 0 else 0.0
        steps = [sparse[i]["iterations"] - dense[i]["iterations"] for i in ids]
        dz = [sparse[i]["z_stab"] - dense[i]["z_stab"] for i in ids]
        row.update({"pairs": len(ids), "same_path": len(same), "same_state": len(near),
                    "max_rel_dG_others": max(others) if others else 0.0,
                    "paired_dG": md, "paired_dG_sem": ed, "paired_dG_t": t})
        total_same += len(same)
        total_near += len(near)
        total += len(ids)
        print(f"| {fam} | {x:g} | {len(ids)} | {len(same)} | {len(near)} | "
              + (f"{max(others):.3f}" if others else "–")
              + f" | {md:+.2e} ± {ed:.1e} ({t:+.2f}) | {sum(steps) / len(steps):+.1f} "
              f"({min(steps):+.0f} … {max(steps):+.0f}) | {sum(dz) / len(dz):+.4f} "
              f"({min(dz):+.4f} … {max(dz):+.4f}) |")
    all_rel.sort()
    if all_rel:
        med = all_rel[len(all_rel) // 2]
        print(f"\nsame path: {total_same} of {total}; same state by another number of steps: "
              f"{total_near}; another state: {len(all_rel)}, |G_S/G_D − 1| "
              f"median {med:.3f}, largest {all_rel[-1]:.3f}")
    else:
        print(f"\nsame path: {total_same} of {total}; same state: {total_near}")

    print("\n## Slopes d ln G_stab / d ln δφ (least squares on the log of the means; "
          f"± bootstrap s.d., {args.boot} replicas)")
    print("| Δ | δφ range | points | Dense | Sparse | S − D (paired bootstrap) |")
    print("|---|---|---|---|---|---|")
    for spec in args.range or RANGES:
        delta, lo, hi = (float(v) for v in spec.split(":"))
        r = slopes(dense, sparse, delta, lo, hi, args.boot, rng)
        if r is None:
            print(f"| {delta:g} | {lo:g} … {hi:g} | fewer than two points in both | | | |")
            continue
        xs, bd, sdd, bs, sds, sdiff = r
        print(f"| {delta:g} | {lo:g} … {hi:g} | {len(xs)} | {bd:.3f} ± {sdd:.3f} | "
              f"{bs:.3f} ± {sds:.3f} | {bs - bd:+.3f} ± {sdiff:.3f} |")

    if args.csv:
        columns = ["family", "delta_phi", "n_dense", "n_sparse"]
        for q in [q for q, _ in quantities] + ["dz_stab"]:
            columns += [f"{q}_dense", f"{q}_dense_sem", f"{q}_sparse", f"{q}_sparse_sem", f"{q}_t"]
        columns += ["pairs", "same_path", "same_state", "max_rel_dG_others", "paired_dG", "paired_dG_sem",
                    "paired_dG_t"]
        write_csv(args.csv, columns, out)


if __name__ == "__main__":
    main()
