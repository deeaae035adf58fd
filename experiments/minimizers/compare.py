#!/usr/bin/env python3
"""Compare two ensembles of jammed packings point by point (standard library only).

    python3 experiments/minimizers/compare.py NEW_DIR OLD_DIR [--csv OUT.csv]

NEW_DIR and OLD_DIR are `jamkit run` output directories (their results.csv)
of the same experiment file run with two minimisers. For every grid point
(the id without its `_s<seed>` suffix) and every quantity (phi_j, z_j,
z_corr for bodies made of spheres, the rattler fraction n_rattlers/N, and,
for the cost, fire_steps and wall_s) it prints the two means with their
standard errors, the difference in units of its standard error, and the two-sample Kolmogorov-Smirnov statistic with its
asymptotic p-value. The packings need not be paired one by one. Packings
with a flag (results.csv column `flag`) are left out of the table and
counted below it, point by point, with their flags.
"""

import csv
import math
import sys
from collections import defaultdict


def load(directory):
    points = defaultdict(list)
    flagged = defaultdict(list)
    with open(f"{directory}/results.csv", newline="") as f:
        for row in csv.DictReader(f):
            point = row["id"].rsplit("_s", 1)[0]
            if row.get("flag"):
                flagged[point].append((row["id"], row["flag"].split(";")[0]))
                continue
            n = float(row["particles"])
            values = {
                "phi_j": float(row["phi_j"]),
                "z_j": float(row["z_j"]),
                "rattler_fraction": float(row["n_rattlers"]) / n,
                "fire_steps": float(row["fire_steps"]),
                "wall_s": float(row["wall_s"]),
            }
            # Bodies made of spheres: also the contact number corrected for
            # rotational rattlers (the same as z_j for other families).
            if row.get("family") == "nmer" and row.get("z_corr"):
                values["z_corr"] = float(row["z_corr"])
            points[point].append(values)
    return points, flagged


def mean_sem(xs):
    m = sum(xs) / len(xs)
    if len(xs) < 2:
        return m, float("nan")
    var = sum((x - m) ** 2 for x in xs) / (len(xs) - 1)
    return m, math.sqrt(var / len(xs))


def ks(a, b):
    """Two-sample KS statistic D and its asymptotic p-value
    (Kolmogorov distribution with the Stephens small-sample correction)."""
    a, b = sorted(a), sorted(b)
    i = j = 0
    d = 0.0
    while i < len(a) and j < len(b):
        x = min(a[i], b[j])
        while i < len(a) and a[i] <= x:
            i += 1
        while j < len(b) and b[j] <= x:
            j += 1
        d = max(d, abs(i / len(a) - j / len(b)))
    ne = len(a) * len(b) / (len(a) + len(b))
    lam = (math.sqrt(ne) + 0.12 + 0.11 / math.sqrt(ne)) * d
    if lam < 1e-3:
        return d, 1.0
    p = 2 * sum((-1) ** (k - 1) * math.exp(-2 * k * k * lam * lam) for k in range(1, 101))
    return d, min(1.0, max(0.0, p))


def main():
    args = sys.argv[1:]
    out = None
    if "--csv" in args:
        k = args.index("--csv")
        out = args[k + 1]
        args = args[:k] + args[k + 2 :]
    if len(args) != 2:
        sys.exit(__doc__)
    (new, new_flagged), (old, old_flagged) = load(args[0]), load(args[1])
    rows = []
    for point in sorted(set(new) & set(old)):
        quantities = ["phi_j", "z_j", "z_corr", "rattler_fraction", "fire_steps", "wall_s"]
        for q in quantities:
            if not all(q in p for p in new[point] + old[point]):
                continue
            a = [p[q] for p in new[point]]
            b = [p[q] for p in old[point]]
            (ma, sa), (mb, sb) = mean_sem(a), mean_sem(b)
            se = math.sqrt(sa * sa + sb * sb)
            z = (ma - mb) / se if se > 0 else float("nan")
            d, p = ks(a, b)
            rows.append([point, q, len(a), len(b), ma, sa, mb, sb, z, d, p])
    header = ["point", "quantity", "n_new", "n_old", "mean_new", "sem_new",
              "mean_old", "sem_old", "diff_over_se", "ks_d", "ks_p"]
    print("| point | quantity | new (mean ± s.e.) | old (mean ± s.e.) | Δ/s.e. | KS D | KS p |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        fmt = "{:.0f}" if r[1] == "fire_steps" else ("{:.2f}" if r[1] == "wall_s" else "{:.5f}")
        print(f"| {r[0]} | {r[1]} | {fmt.format(r[4])} ± {fmt.format(r[5])} (n = {r[2]}) | "
              f"{fmt.format(r[6])} ± {fmt.format(r[7])} (n = {r[3]}) | {r[8]:+.2f} | {r[9]:.3f} | {r[10]:.3f} |")
    for point in sorted(set(new_flagged) | set(old_flagged)):
        for side, flagged in (("new", new_flagged), ("old", old_flagged)):
            if flagged.get(point):
                ids = ", ".join(i for i, _ in flagged[point])
                print(f"\nLeft out, flagged: {point}, {side}: {len(flagged[point])} ({ids}): "
                      f"{flagged[point][0][1]}")
    if out:
        with open(out, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(header)
            w.writerows(rows)


if __name__ == "__main__":
    main()
