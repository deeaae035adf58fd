#!/usr/bin/env python3
"""v_corr = N_nr · PR of the softest modes against δz_J, near-disks (docs/reports/vcorr.md).

Reads run directories of experiments/rough/vcorr.ron (results.csv with the
softest_* columns, and eigenvalues/<id>.csv) and writes, under the prefix
given with -o: PREFIX.csv (one row per N, n, Δ), PREFIX_fits.csv (the fitted
exponent of v_corr ∝ δz_J^x per N, n and mode) and PREFIX.png.

Two modes per packing, both of the stiffness matrix K at φ_J without the
rattlers' rows, above the zero-mode threshold ω > 1e-5:
  soft   the softest non-zero mode (results.csv: softest_*);
  trans  the softest mode with rotational share < 1/2 (from the eigenvalue
         table): the lowest mode of the translational band.
δz_J = z_J − (4 − 4/N_nr), the paper's Eq. (2) with the non-rattlers (as
`jamkit report`'s Fig. 10). Each point's v_corr is the geometric mean over
its packings (the mean of ln v_corr), with the s.e.m. of ln v_corr. The fits
of ln v_corr against ln δz_J weigh each point by samples / s², s² the
variance of ln v_corr pooled over the points of the same N and n, and
leave out points with flagged packings (non-convex outlines) and points
with v_corr above --fit-max-fraction of N_nr.

Usage: python3 vcorr.py RUN_DIR [RUN_DIR …] -o PREFIX [--fit-max-fraction F]
"""

import argparse
import csv
import math
import os
from collections import defaultdict

OMEGA_ZERO = 1e-5


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def translational_softest(table):
    for m in table:
        if float(m["omega"]) > OMEGA_ZERO and float(m["rotational_share"]) < 0.5:
            return float(m["omega"]), float(m["participation"])
    return None


def mean_sem(xs):
    n = len(xs)
    m = sum(xs) / n
    if n < 2:
        return m, float("nan")
    var = sum((x - m) ** 2 for x in xs) / (n - 1)
    return m, math.sqrt(var / n)


def fit(points):
    """Weighted least squares of y = a + x·s on (x, y, σ_y): slope, its error
    (scaled by √(χ²/dof) when that exceeds 1), and the point count."""
    if len(points) < 2:
        return None
    w = [1 / s**2 for _, _, s in points]
    sw = sum(w)
    mx = sum(wi * x for wi, (x, _, _) in zip(w, points)) / sw
    my = sum(wi * y for wi, (_, y, _) in zip(w, points)) / sw
    sxx = sum(wi * (x - mx) ** 2 for wi, (x, _, _) in zip(w, points))
    slope = sum(wi * (x - mx) * (y - my) for wi, (x, y, _) in zip(w, points)) / sxx
    a = my - slope * mx
    err = math.sqrt(1 / sxx)
    if len(points) > 2:
        chi2 = sum(wi * (y - a - slope * x) ** 2 for wi, (x, y, _) in zip(w, points))
        err *= max(1.0, math.sqrt(chi2 / (len(points) - 2)))
    return slope, err, len(points), a


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("-o", "--out", required=True, help="output prefix")
    ap.add_argument(
        "--fit-max-fraction",
        type=float,
        default=1.0,
        help="fit only points with v_corr below this fraction of N_nr (finite-size saturation)",
    )
    args = ap.parse_args()

    groups = defaultdict(lambda: defaultdict(list))
    for run in args.runs:
        for r in rows(os.path.join(run, "results.csv")):
            if not r.get("softest_participation"):
                raise SystemExit(f"{run}: {r['id']} has no softest_participation (Spectrum(modes: true))")
            n_nr = int(r["particles"]) - int(r["n_rattlers"])
            key = (int(r["particles"]), int(r["n"]), float(r["delta"]))
            g = groups[key]
            g["dz"].append(float(r["z_j"]) - (4 - 4 / n_nr))
            g["soft_omega"].append(float(r["softest_omega"]))
            g["soft_v"].append(n_nr * float(r["softest_participation"]))
            g["soft_rot"].append(float(r["softest_rotational_share"]))
            g["n_nr"].append(n_nr)
            g["flagged"].append(bool(r.get("flag")))
            table = rows(os.path.join(run, "eigenvalues", r["id"] + ".csv"))
            t = translational_softest(table)
            if t is not None:
                g["trans_omega"].append(t[0])
                g["trans_v"].append(n_nr * t[1])

    out_rows = []
    for (big_n, n, delta), g in sorted(groups.items()):
        row = {"particles": big_n, "n": n, "delta": delta, "samples": len(g["dz"])}
        row["dz_mean"], row["dz_sem"] = mean_sem(g["dz"])
        row["n_nr_mean"] = mean_sem(g["n_nr"])[0]
        for mode in ("soft", "trans"):
            logs = [math.log(v) for v in g[mode + "_v"]]
            m, s = mean_sem(logs)
            row[f"{mode}_vcorr_gmean"] = math.exp(m)
            row[f"{mode}_vcorr_log_sem"] = s
            row[f"{mode}_vcorr_mean"] = mean_sem(g[mode + "_v"])[0]
            row[f"{mode}_omega_gmean"] = math.exp(mean_sem([math.log(w) for w in g[mode + "_omega"]])[0])
        row["soft_rot_mean"] = mean_sem(g["soft_rot"])[0]
        row["flagged"] = sum(g["flagged"])
        out_rows.append(row)

    with open(args.out + ".csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(out_rows[0].keys()))
        w.writeheader()
        for r in out_rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})

    fits = []
    for big_n in sorted({r["particles"] for r in out_rows}):
        for n in sorted({r["n"] for r in out_rows}):
            pts = [r for r in out_rows if r["particles"] == big_n and r["n"] == n]
            if not pts:
                continue
            for mode in ("soft", "trans"):
                # One scatter of ln v_corr for all points of (N, n), pooled
                # over them: a 2-sample s.e.m. can be near 0 by chance.
                dof = sum(r["samples"] - 1 for r in pts)
                pooled = math.sqrt(
                    sum((r["samples"] - 1) * r["samples"] * r[f"{mode}_vcorr_log_sem"] ** 2 for r in pts) / dof
                )
                use = [
                    (math.log(r["dz_mean"]), math.log(r[f"{mode}_vcorr_gmean"]), pooled / math.sqrt(r["samples"]))
                    for r in pts
                    if r[f"{mode}_vcorr_gmean"] < args.fit_max_fraction * r["n_nr_mean"]
                    and r["flagged"] == 0
                    and r["dz_mean"] > 0
                ]
                f_ = fit(use)
                if f_ is None:
                    fits.append({"particles": big_n, "n": n, "mode": mode, "points": len(use)})
                    continue
                slope, err, k, a = f_
                fits.append(
                    {"particles": big_n, "n": n, "mode": mode, "points": k, "exponent": slope, "exponent_err": err, "log_prefactor": a}
                )
    with open(args.out + "_fits.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["particles", "n", "mode", "points", "exponent", "exponent_err", "log_prefactor"])
        w.writeheader()
        for r in fits:
            w.writerow({k: (f"{v:.4g}" if isinstance(v, float) else v) for k, v in r.items()})
    for r in fits:
        if "exponent" in r:
            print(f"N={r['particles']} n={r['n']} {r['mode']}: x = {r['exponent']:.3f} ± {r['exponent_err']:.3f} ({r['points']} points)")
        else:
            print(f"N={r['particles']} n={r['n']} {r['mode']}: no fit ({r['points']} points)")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sizes = sorted({r["particles"] for r in out_rows})
    colours = {2: "C0", 3: "C1", 4: "C2", 5: "C3"}
    marks = ["o", "s", "^", "D"]
    titles = {"soft": "softest non-zero mode", "trans": "softest translational mode (rot. share < 1/2)"}
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2), sharey=True)
    for ax, mode in zip(axes, ("soft", "trans")):
        for i, big_n in enumerate(sizes):
            for n in sorted(colours):
                pts = [r for r in out_rows if r["particles"] == big_n and r["n"] == n]
                if not pts:
                    continue
                x = [r["dz_mean"] for r in pts]
                y = [r[f"{mode}_vcorr_gmean"] for r in pts]
                lo = [yy * (1 - math.exp(-r[f"{mode}_vcorr_log_sem"])) for yy, r in zip(y, pts)]
                hi = [yy * (math.exp(r[f"{mode}_vcorr_log_sem"]) - 1) for yy, r in zip(y, pts)]
                ax.errorbar(
                    x, y, yerr=[lo, hi], marker=marks[i % len(marks)], color=colours[n],
                    mfc=colours[n] if i == 0 else "none", ls="-" if i == 0 else ":",
                    label=f"n = {n}, N = {big_n}", capsize=2, ms=5,
                )
            ax.axhline(sum(r["n_nr_mean"] for r in out_rows if r["particles"] == big_n) / len([r for r in out_rows if r["particles"] == big_n]),
                       color="grey", lw=0.8, ls=(0, (1, 3 + 2 * i)))
        xs = [r["dz_mean"] for r in out_rows]
        x0, x1 = min(xs), max(xs)
        ax.plot([x0, x1], [3 / x0, 3 / x1], "k--", lw=1, label="∝ δz⁻¹")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("δz_J = z_J − z_iso(disks)")
        ax.set_title(titles[mode], fontsize=10)
    axes[0].set_ylabel("v_corr = N_nr · PR  (geometric mean)")
    axes[1].legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(args.out + ".png", dpi=90)


if __name__ == "__main__":
    main()
