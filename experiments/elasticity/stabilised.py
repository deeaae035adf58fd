#!/usr/bin/env python3
"""Per-packing table and per-point summary of shear-stabilised runs
(`protocol.shear_stabilised: true`; docs/reports/elasticity.md,
"Shear-stabilised packings at N = 128").

    python3 experiments/elasticity/stabilised.py [--csv OUT.csv] DIR...

Reads the packing files of every DIR (`packings/*.json`; the failed
samples, `*.failed.json`, are listed with their V/N and the start of their
flag: those that unjammed on their way up, and those whose stabilisation
failed, kept as the fixed-box packing it started from) and writes one row per packing (--csv): the fixed-box moduli kept in
`moduli.stabilisation.fixed_box` beside the stabilised ones, det F, the
largest entry of |F - I|, strain steps, residuals, V/N before and after,
z of the fixed box and (where the file records it) the stabilised cell's
z, rattlers and isostaticity margin, and the dense fallbacks of a
`Moduli(solver: Sparse)` run (strain steps whose stiffness fell back, and
whether the fixed box's and the stabilised cell's moduli did) and the
packing's wall time. A packing found in several DIRs counts once, from
the first.
Then prints per family parameters and delta_phi (or target pressure): the
number of packings, mean p, mean +- s.e.m. of G fixed and stabilised with
the counts of G < 0 and G_min < 0, mean B fixed and stabilised, the largest
|F - I| and |det F - 1|, the range of strain steps, the largest residual
and the largest number of negative modes, the dense fallbacks against
the stiffness evaluations (strain steps + 1) and the summed wall time
(of it the stabilisations'). Only the standard library.
"""
import argparse
import glob
import json
import math
import os
import re
import sys
from collections import defaultdict

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fit import write_csv  # noqa: E402


def mean_sem(xs):
    n = len(xs)
    m = sum(xs) / n
    if n < 2:
        return m, float("nan")
    var = sum((x - m) ** 2 for x in xs) / (n - 1)
    return m, math.sqrt(var / n)


def det(f):
    if len(f) == 2:
        return f[0][0] * f[1][1] - f[0][1] * f[1][0]
    return (
        f[0][0] * (f[1][1] * f[2][2] - f[1][2] * f[2][1])
        - f[0][1] * (f[1][0] * f[2][2] - f[1][2] * f[2][0])
        + f[0][2] * (f[1][0] * f[2][1] - f[1][1] * f[2][0])
    )


def point_of(d):
    protocol = d["settings"]["protocol"]
    if "AboveJam" in protocol:
        return "dphi", protocol["AboveJam"]["delta_phi"]
    if "Pressure" in protocol:
        return "p_target", protocol["Pressure"]["pressure"]
    raise SystemExit(f"{d['id']}: not an AboveJam or Pressure packing")


def family_of(d):
    params = {k: v for k, v in sorted(d["params"].items()) if v is not None}
    return d["family"] + " " + " ".join(f"{k}={v}" for k, v in params.items())


def rows_of(directory):
    rows = []
    for path in sorted(glob.glob(os.path.join(directory, "packings", "*.json"))):
        if path.endswith(".failed.json"):
            continue
        d = json.load(open(path))
        m = d["measures"]["moduli"]
        s = m.get("stabilisation")
        if s is None:
            raise SystemExit(f"{path}: not shear-stabilised")
        fixed, stab = s["fixed_box"], m["moduli"]
        cell = s.get("contacts")
        f = s["deformation"]
        dim = len(f)
        strain = max(abs(f[a][b] - (1.0 if a == b else 0.0)) for a in range(dim) for b in range(dim))
        label, x = point_of(d)
        rows.append(
            {
                "id": d["id"],
                "family": family_of(d),
                label: x,
                "x": x,
                "label": label,
                "seed": d["seed"],
                "p": stab["pressure"],
                "G_fixed": fixed["shear"],
                "Gmin_fixed": min(fixed["shear_planes"]),
                "G": stab["shear"],
                "Gmin": min(stab["shear_planes"]),
                "B_fixed": fixed["bulk"],
                "B": stab["bulk"],
                "detF": det(f),
                "strain": strain,
                "iterations": s["iterations"],
                "residual_before": s["residual_before"],
                "residual": s["residual"],
                "neg_modes": stab["negative_modes"],
                "e_before": s["energy_before"],
                "e_after": s["energy_after"],
                "stab_s": s["wall_s"],
                # Contacts: the fixed box's (`Contacts`) and the stabilised
                # cell's (empty in files written before it was recorded).
                "z_fixed": d["measures"]["z_j"],
                "z_stab": cell["z"] if cell else "",
                "rattlers_stab": cell["n_rattlers"] if cell else "",
                "margin_stab": cell["iso_margin"] if cell else "",
                # With `Moduli(solver: Sparse)`: the strain
                # steps whose stiffness fell back to the dense solver (of
                # `iterations + 1` evaluations), and whether the fixed box's
                # and the stabilised cell's measured moduli did
                # (`dense_fallback`, the zero-mode rule); the packing's wall
                # time (jamming, compression, moduli and stabilisation).
                "fallbacks": s.get("dense_fallbacks", 0),
                "fallback_fixed": int("dense_fallback" in fixed),
                "fallback_stab": int("dense_fallback" in stab),
                "wall_s": d["measures"]["wall_s"],
            }
        )
    failed = sorted(glob.glob(os.path.join(directory, "packings", "*.failed.json")))
    return rows, failed


COLUMNS = [
    "id", "family", "x", "label", "seed", "p", "G_fixed", "Gmin_fixed", "G", "Gmin",
    "B_fixed", "B", "detF", "strain", "iterations", "residual_before", "residual",
    "neg_modes", "e_before", "e_after", "stab_s", "z_fixed", "z_stab", "rattlers_stab",
    "margin_stab", "fallbacks", "fallback_fixed", "fallback_stab", "wall_s",
]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--csv", help="write the per-packing table here")
    ap.add_argument("dirs", nargs="+")
    args = ap.parse_args()
    rows, failed = [], []
    seen = set()
    for d in args.dirs:
        r, f = rows_of(d)
        # A packing in several directories (a re-measured copy first)
        # counts once, from the first. By id and target: a run of one
        # target names its packings without it, so runs at two targets
        # share ids (as fit.py).
        rows += [x for x in r if (x["id"], x["x"]) not in seen]
        seen.update((x["id"], x["x"]) for x in r)
        failed += f
    if args.csv:
        write_csv(args.csv, COLUMNS, rows)
    groups = defaultdict(list)
    for r in rows:
        groups[(r["family"], r["label"], r["x"])].append(r)
    print("| family | x | packings | p | G fixed (G<0; G_min<0) | G stabilised (G<0; G_min<0) "
          "| B fixed | B stab. | max abs(F-I) | max abs(detF-1) | steps | max residual | neg. modes "
          "| dense fallbacks / evaluations (moduli: fixed, stab.) | wall s (stab. s) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for (fam, label, x), g in sorted(groups.items(), key=lambda kv: (kv[0][0], -kv[0][2])):
        def ms(key):
            m, e = mean_sem([r[key] for r in g])
            return f"{m:.4g} ± {e:.2g}"
        neg = lambda key: sum(1 for r in g if r[key] < 0)
        print(
            f"| {fam} | {label} = {x:g} | {len(g)} | {sum(r['p'] for r in g) / len(g):.3e} "
            f"| {ms('G_fixed')} ({neg('G_fixed')}; {neg('Gmin_fixed')}) "
            f"| {ms('G')} ({neg('G')}; {neg('Gmin')}) "
            f"| {sum(r['B_fixed'] for r in g) / len(g):.3f} | {sum(r['B'] for r in g) / len(g):.3f} "
            f"| {max(r['strain'] for r in g):.3f} | {max(abs(r['detF'] - 1) for r in g):.3f} "
            f"| {min(r['iterations'] for r in g)}–{max(r['iterations'] for r in g)} "
            f"| {max(r['residual'] for r in g):.1e} | {max(r['neg_modes'] for r in g)} "
            f"| {sum(r['fallbacks'] for r in g)}/{sum(r['iterations'] + 1 for r in g)} "
            f"({sum(r['fallback_fixed'] for r in g)}, {sum(r['fallback_stab'] for r in g)}) "
            f"| {sum(r['wall_s'] for r in g):.0f} ({sum(r['stab_s'] for r in g):.0f}) |"
        )
    print(f"\n{len(rows)} packings; G < 0: fixed box {sum(1 for r in rows if r['G_fixed'] < 0)}, "
          f"stabilised {sum(1 for r in rows if r['G'] < 0)}; G_min < 0: fixed box "
          f"{sum(1 for r in rows if r['Gmin_fixed'] < 0)}, stabilised {sum(1 for r in rows if r['Gmin'] < 0)}")
    print(f"dense fallbacks: {sum(r['fallbacks'] for r in rows)} of "
          f"{sum(r['iterations'] + 1 for r in rows)} stiffness evaluations; measured moduli: fixed box "
          f"{sum(r['fallback_fixed'] for r in rows)}, stabilised {sum(r['fallback_stab'] for r in rows)}; "
          f"wall time {sum(r['wall_s'] for r in rows):.0f} s (stabilisations {sum(r['stab_s'] for r in rows):.0f} s)")
    print(f"{len(failed)} failed samples (failed.json):")
    for f in failed:
        d = json.load(open(f))
        why = d["measures"]["flag"].split(";")[0][:160]
        print(f"  {d['id']}: V/N = {d['energy_per_particle']:.3e}: {why}")


if __name__ == "__main__":
    main()
