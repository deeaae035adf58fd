#!/usr/bin/env python3
"""Power-law fits of G and z - z_J against delta_phi per regime, with
bootstrap errors over packings (docs/reports/elasticity.md, "Near-disks
across δφ ∼ Δ (stabilised, N = 512 and 1024)").

    python3 experiments/elasticity/crossover.py [--boot 4000] [--range LO:HI]... [--vs-p] [--csv OUT.csv] DIR...

Reads the packing files of `AboveJam` runs (`packings/*.json`; a
`*.failed.json` is counted with the first line of its flag), groups them
by family parameters and delta_phi, and prints per point: the packings,
mean p, the fixed-box G (with `shear_stabilised`, the one kept in
`moduli.stabilisation.fixed_box`; otherwise the run's own), the stabilised
G (where the run stabilised), z - z_J (the fixed box's contacts against the
packing's own jamming point), each mean +- s.e.m. with the number of
negative G; then the local slope d ln y / d ln delta_phi between
neighbouring points, and least-squares slopes of ln(mean y) against
ln(delta_phi) over each --range and over the two regimes of a near-disk
family on either side of delta_phi = Delta^2 (a crossover in delta_phi/Delta^2) and of
delta_phi = Delta (the paper's outlook: G ~ Delta^1/2 G~(delta_phi/Delta),
G~(x) ~ x for x << 1 and x^1/2 for x >> 1), where they hold two points or
more; for near-disks also the scaling variables x = delta_phi/Delta and
G_stab/Delta^1/2 per point, and across the near-disk
families the collapse on G~ = G_stab/Delta^1/2 against x at equal x, and
z_stab - z_J, the stabilised cell's contacts (`moduli.stabilisation.
contacts`, where recorded) against the packing's own jamming point.
Errors: the standard deviation of the slope over --boot
bootstrap replicas, each resampling every point's packings with
replacement (a replica with a mean <= 0 in the range is dropped and
counted), and the 16th-84th percentile range. With few packings per point
the bootstrap underestimates the spread (by about sqrt((n-1)/n) for n
packings, 13 % at n = 4). --csv writes the per-point table, --svg a figure of the collapse,
--against compares the points with another run's --csv table
(another N: matched by family parameters without N and delta_phi), --vs-p
adds, in every range, the slopes against the mean pressure of
the same packings (G ~ p^a: the disks' law is a = 1/2 whether or not p is
linear in delta_phi), --svg-p draws the stabilised G against
p of every family, with those of --points tables (other runs). Only the
standard library (`mean_sem` from fit.py).

--ellipse-delta treats the `ellipse` family as a near-disk
with Delta_eff = aspect - 1: an ellipse of aspect 1 + eps has, to first
order in eps, the polar radius R0 [1 + (eps/2) cos 2 theta], the n = 2
near-disk R0 [1 + Delta sin(2 theta)/2] with Delta = eps turned by 45
degrees (docs/reports/elasticity.md, "Ellipses near α = 1 (stabilised,
N = 256)"). Its points then
get x = delta_phi/Delta_eff and the fits and collapse of a near-disk, the
collapse's column named "Delta = ... (ellipse)". Without it an ellipse
has no Delta: no x, no near-disk fits, not in the collapse.
"""
import argparse
import csv
import glob
import json
import math
import os
import random
import sys
from collections import defaultdict

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fit import mean_sem, write_csv  # noqa: E402

QUANTITIES = [
    ("p", "p"),
    ("G_fixed", "G fixed box"),
    ("G_stab", "G stabilised"),
    ("dz", "z - z_J"),
    ("dz_stab", "z_stab - z_J"),
]


def family_of(d):
    params = {k: v for k, v in sorted(d["params"].items()) if v is not None}
    return d["family"] + " N=" + str(d["particles"]) + "".join(f" {k}={v}" for k, v in params.items())


class EllipseDelta(float):
    """Delta_eff = aspect - 1 of an ellipse (--ellipse-delta): a float that
    is its own key beside a near-disk's equal Delta and names itself."""

    def __eq__(self, other):
        return isinstance(other, EllipseDelta) and float(self) == float(other)

    def __hash__(self):
        return hash(("ellipse", float(self)))

    def __format__(self, spec):
        return format(float(self), spec) + " (ellipse)"


def read(dirs, ellipse_delta=False):
    groups = defaultdict(lambda: defaultdict(list))
    failed = []
    deltas = {}
    seen = set()
    for directory in dirs:
        for path in sorted(glob.glob(os.path.join(directory, "packings", "*.json"))):
            d = json.load(open(path))
            if path.endswith(".failed.json"):
                failed.append((d["id"], d["measures"]["flag"].split(";")[0][:160]))
                continue
            protocol = d["settings"]["protocol"]
            if "AboveJam" not in protocol:
                raise SystemExit(f"{path}: not an AboveJam packing")
            x = protocol["AboveJam"]["delta_phi"]
            # By id and delta_phi: a run of one delta_phi names its
            # packings without it, so runs at two share ids.
            if (d["id"], x) in seen:
                continue
            seen.add((d["id"], x))
            m = d["measures"]
            moduli = m["moduli"]
            stab = moduli.get("stabilisation")
            fixed = stab["fixed_box"] if stab else moduli["moduli"]
            key = family_of(d)
            deltas[key] = d["params"].get("delta")
            if ellipse_delta and d["family"] == "ellipse" and d["params"]["aspect"] > 1:
                deltas[key] = EllipseDelta(round(d["params"]["aspect"] - 1, 12))
            groups[key][x].append(
                {
                    "p": m["pressure"],
                    "G_fixed": fixed["shear"],
                    "G_stab": moduli["moduli"]["shear"] if stab else None,
                    "dz": m["z_j"] - m["jam_point"]["z"],
                    # The stabilised cell's contacts (None in files
                    # written before they were recorded).
                    "dz_stab": (stab["contacts"]["z"] - m["jam_point"]["z"])
                    if stab and stab.get("contacts") else None,
                    "stab_rattlers": stab["contacts"]["n_rattlers"]
                    if stab and stab.get("contacts") else None,
                    "stab_margin": stab["contacts"]["iso_margin"]
                    if stab and stab.get("contacts") else None,
                }
            )
    return groups, failed, deltas


def slope(xs, ys):
    """Least-squares slope of ln y against ln x."""
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    sxx = sum((a - mx) ** 2 for a in lx)
    return sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sxx


def fit(points, q, lo, hi, boot, rng, abscissa=None):
    """Slope over lo <= x <= hi of quantity q; bootstrap s.d., 16-84 %
    range and the number of dropped replicas. None if fewer than two
    points or a mean <= 0. With abscissa = "p" (--vs-p) the slope is of
    ln(mean q) against ln(mean p) of the same packings, the points still
    chosen by delta_phi; a replica resamples each point's packings once
    for both means."""
    sel = sorted(x for x in points if lo <= x <= hi)
    if len(sel) < 2:
        return None
    # The packings that have the quantity (the stabilised contacts are
    # missing from files written before they were recorded).
    rows = {x: [r for r in points[x] if r[q] is not None] for x in sel}
    values = {x: [r[q] for r in rows[x]] for x in sel}
    if any(not values[x] for x in sel):
        return None
    means = [sum(values[x]) / len(values[x]) for x in sel]
    if any(m <= 0 for m in means):
        return ("mean <= 0", sel)
    if abscissa is None:
        best = slope(sel, means)
    else:
        best = slope([sum(r[abscissa] for r in rows[x]) / len(rows[x]) for x in sel], means)
    reps, dropped = [], 0
    for _ in range(boot):
        ms, xs = [], []
        for x in sel:
            if abscissa is None:
                v = values[x]
                ms.append(sum(rng.choice(v) for _ in v) / len(v))
                continue
            draw = [rng.choice(rows[x]) for _ in rows[x]]
            ms.append(sum(r[q] for r in draw) / len(draw))
            xs.append(sum(r[abscissa] for r in draw) / len(draw))
        if any(m <= 0 for m in ms + xs):
            dropped += 1
            continue
        reps.append(slope(sel if abscissa is None else xs, ms))
    reps.sort()
    if len(reps) < 2:
        return (best, math.nan, math.nan, math.nan, dropped, sel)
    mean = sum(reps) / len(reps)
    sd = math.sqrt(sum((r - mean) ** 2 for r in reps) / (len(reps) - 1))
    lo16, hi84 = reps[int(0.16 * len(reps))], reps[int(0.84 * len(reps))]
    return (best, sd, lo16, hi84, dropped, sel)


def show(name, result, boot):
    if result is None:
        return
    if result[0] == "mean <= 0":
        print(f"  {name}: no fit (a mean <= 0 at delta_phi in {result[1]})")
        return
    best, sd, lo16, hi84, dropped, sel = result
    span = f"{min(sel):g} ... {max(sel):g} ({len(sel)} points)"
    extra = f", {dropped} of {boot} replicas dropped (mean <= 0)" if dropped else ""
    print(f"  {name}: {best:.3f} ± {sd:.3f} [16-84 %: {lo16:.3f} … {hi84:.3f}] over {span}{extra}")


def loglog_svg(series, guides, guide_label, xlabel, ylabel, path):
    """A log-log figure: `series` is a list of (legend, [(x, y, relative
    error)]) drawn as points with error bars joined by a line, `guides` a
    list of ((x0, y0), slope), dashed lines through (x0, y0), clipped to
    the frame, named once in the legend by `guide_label`. SVG only (the
    standard library has no PNG writer)."""
    colours = ["#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e", "#e6ab02", "#a6761d", "#666666"]
    pts = [(x, g, r) for _, c in series for x, g, r in c]
    lx0 = math.floor(math.log10(min(x for x, _, _ in pts)))
    lx1 = math.ceil(math.log10(max(x for x, _, _ in pts)))
    ly0 = math.floor(math.log10(min(g * (1 - r) for _, g, r in pts if r < 1)))
    ly1 = math.ceil(math.log10(max(g * (1 + r) for _, g, r in pts)))
    w, h, left, right, top, bottom = 640, 460, 80, 170, 30, 60
    X = lambda x: left + (math.log10(x) - lx0) / (lx1 - lx0) * (w - left - right)
    Y = lambda y: h - bottom - (math.log10(y) - ly0) / (ly1 - ly0) * (h - top - bottom)
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12">',
           f'<rect width="{w}" height="{h}" fill="white"/>',
           f'<rect x="{left}" y="{top}" width="{w - left - right}" height="{h - top - bottom}" fill="none" stroke="black"/>']
    for k in range(lx0, lx1 + 1):
        out.append(f'<line x1="{X(10 ** k):.1f}" y1="{h - bottom}" x2="{X(10 ** k):.1f}" y2="{h - bottom + 5}" stroke="black"/>')
        out.append(f'<text x="{X(10 ** k):.1f}" y="{h - bottom + 18}" text-anchor="middle">1e{k}</text>')
    for k in range(ly0, ly1 + 1):
        out.append(f'<line x1="{left - 5}" y1="{Y(10 ** k):.1f}" x2="{left}" y2="{Y(10 ** k):.1f}" stroke="black"/>')
        out.append(f'<text x="{left - 8}" y="{Y(10 ** k) + 4:.1f}" text-anchor="end">1e{k}</text>')
    out.append(f'<text x="{(left + w - right) / 2}" y="{h - 15}" text-anchor="middle">{xlabel}</text>')
    out.append(f'<text x="18" y="{(top + h - bottom) / 2}" text-anchor="middle" transform="rotate(-90 18 {(top + h - bottom) / 2})">{ylabel}</text>')
    # The guides, clipped to the frame.
    out.append(f'<clipPath id="frame"><rect x="{left}" y="{top}" width="{w - left - right}" height="{h - top - bottom}"/></clipPath>')
    out.append('<g clip-path="url(#frame)">')
    for (x0, g0), slope in guides:
        xs = (10 ** lx0, 10 ** lx1)
        ys = [g0 * (x / x0) ** slope for x in xs]
        out.append(f'<line x1="{X(xs[0]):.1f}" y1="{Y(ys[0]):.1f}" x2="{X(xs[1]):.1f}" y2="{Y(ys[1]):.1f}" stroke="gray" stroke-dasharray="4 4"/>')
    out.append('</g>')
    for k, (name, curve) in enumerate(series):
        col = colours[k % len(colours)]
        path_d = " ".join(("M" if i == 0 else "L") + f"{X(x):.1f},{Y(g):.1f}" for i, (x, g, _) in enumerate(curve))
        out.append(f'<path d="{path_d}" fill="none" stroke="{col}"/>')
        for x, g, r in curve:
            lo = g * (1 - r) if r < 1 else 10 ** ly0
            out.append(f'<line x1="{X(x):.1f}" y1="{Y(lo):.1f}" x2="{X(x):.1f}" y2="{Y(g * (1 + r)):.1f}" stroke="{col}"/>')
            out.append(f'<circle cx="{X(x):.1f}" cy="{Y(g):.1f}" r="4" fill="{col}"/>')
        ly = top + 20 + 20 * k
        out.append(f'<circle cx="{w - right + 20}" cy="{ly}" r="4" fill="{col}"/>')
        out.append(f'<text x="{w - right + 30}" y="{ly + 4}">{name}</text>')
    ly = top + 20 + 20 * len(series)
    out.append(f'<line x1="{w - right + 12}" y1="{ly}" x2="{w - right + 28}" y2="{ly}" stroke="gray" stroke-dasharray="4 4"/>')
    out.append(f'<text x="{w - right + 30}" y="{ly + 4}">{guide_label}</text>')
    out.append('</svg>')
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


def collapse_svg(curves, path):
    """G~ = G_stab/Delta^1/2 against x = delta_phi/Delta, one series per
    Delta (mean +- s.e.m.), with the paper's two limits G~ ~ x and
    G~ ~ x^1/2 as guides through the first and last points of the
    smallest Delta."""
    first = curves[min(curves)]
    (xa, ga, _), (xb, gb, _) = first[0], first[-1]
    loglog_svg([(f"Δ = {d:g}", curves[d]) for d in sorted(curves)],
               [((xa, ga), 1.0), ((xb, gb), 0.5)], "x and x^(1/2)",
               "x = δφ/Δ", "G/Δ^(1/2) (stabilised)", path)


def short_name(family):
    """`fourier N=1024 delta=0.003 n=2` -> `Δ = 0.003, N = 1024`; a sphere
    family -> `disks, N = …`; others as they are."""
    words = dict(w.split("=", 1) for w in family.split()[1:] if "=" in w)
    kind = family.split()[0]
    if kind == "fourier" and "delta" in words:
        return f"Δ = {float(words['delta']):g}, N = {words['N']}"
    if kind == "sphere":
        return f"disks, N = {words['N']}"
    return family


def pressure_svg(rows, path, only=()):
    """The stabilised G against the mean pressure, one series per family
    (this run's points and those of --points tables; a family's points come
    from the first source that has it; with `only`, the families whose key
    holds one of those words), with the disks' law
    G ~ p^1/2 through the last point of the first disk family (or of the
    series with the largest p) and G ~ p through the first point of the
    series with the smallest p."""
    series = defaultdict(list)
    source = {}
    for r in rows:
        if only and not any(w in r["family"].split() for w in only):
            continue
        if source.setdefault(r["family"], r["_source"]) != r["_source"]:
            continue
        if r["G_stab"] in ("", None) or float(r["G_stab"]) <= 0:
            continue
        g, se = float(r["G_stab"]), float(r["G_stab_sem"])
        series[r["family"]].append((float(r["p"]), g, se / g))
    if not series:
        return
    curves = [(short_name(f), sorted(c)) for f, c in sorted(series.items(), key=lambda fc: short_name(fc[0]))]
    disks = [c for name, c in curves if name.startswith("disks")]
    top = disks[0] if disks else max((c for _, c in curves), key=lambda c: c[-1][0])
    low = min((c for _, c in curves), key=lambda c: c[0][0])
    loglog_svg(curves, [(top[-1][:2], 0.5), (low[0][:2], 1.0)], "p^(1/2) and p",
               "p", "G (stabilised)", path)


def collapse(groups, deltas, svg=None):
    """The paper's scaling form G = Delta^1/2 G~(delta_phi/Delta) across the
    near-disk families (those with a Delta): per x = delta_phi/Delta of any
    family, G~ = G_stab/Delta^1/2 of each family, measured at that x or
    interpolated linearly in ln G~ against ln x between its two nearest
    points (a decade apart), and the spread (max - min)/mean against the
    s.e.m.s (relative) of the measured ones."""
    curves = {}
    for key, points in groups.items():
        delta = deltas.get(key)
        if not delta:
            continue
        curve = []
        for x in sorted(points):
            vs = [r["G_stab"] for r in points[x] if r["G_stab"] is not None]
            if len(vs) < 2:
                continue
            m, se = mean_sem(vs)
            if m > 0:
                curve.append((x / delta, m / math.sqrt(delta), se / m))
        if curve:
            curves[delta] = curve
    if len(curves) < 2:
        return
    if svg:
        collapse_svg(curves, svg)
    print("## collapse: G~ = G_stab/Delta^1/2 against x = delta_phi/Delta")
    deltas_sorted = sorted(curves)
    print("x | " + " | ".join(f"Delta = {d:g}" for d in deltas_sorted) + " | spread (max-min)/mean | largest s.e.m.")
    xs = sorted({round(math.log10(x), 6) for c in curves.values() for x, _, _ in c})
    for lx in xs:
        x = 10 ** lx
        cells, vals, sems = [], [], []
        for d in deltas_sorted:
            c = curves[d]
            exact = [(g, r) for cx, g, r in c if abs(math.log10(cx) - lx) < 1e-6]
            if exact:
                g, r = exact[0]
                cells.append(f"{g:.3e} ± {r * 100:.0f} %")
                vals.append(g)
                sems.append(r)
                continue
            below = [(cx, g) for cx, g, _ in c if cx < x]
            above = [(cx, g) for cx, g, _ in c if cx > x]
            if below and above:
                (x0, g0), (x1, g1) = below[-1], above[0]
                t = math.log(x / x0) / math.log(x1 / x0)
                g = math.exp(math.log(g0) + t * math.log(g1 / g0))
                cells.append(f"({g:.3e})")
                vals.append(g)
            else:
                cells.append("–")
        if len(vals) >= 2:
            mean = sum(vals) / len(vals)
            spread = f"{(max(vals) - min(vals)) / mean * 100:.0f} %"
        else:
            spread = "–"
        worst = f"{max(sems) * 100:.0f} %" if sems else "–"
        print(f"{x:.3g} | " + " | ".join(cells) + f" | {spread} | {worst}")
    print("(values in brackets are interpolated)")
    print()


def without_n(family):
    """A family key without its `N=` word (to match one N against another)."""
    return " ".join(w for w in family.split() if not w.startswith("N="))


def against(rows, path):
    """This run's points against another's per-point table (--csv of an
    earlier run, e.g. another N), matched by family parameters without N and
    by delta_phi: mean +- s.e.m. of each, the ratio here/there and the
    difference in units of sqrt(se_here^2 + se_there^2) (independent
    ensembles)."""
    ref = {}
    for r in csv.DictReader(open(path)):
        ref[(without_n(r["family"]), round(math.log10(float(r["delta_phi"])), 6))] = r
    quantities = [("G_stab", "G stab."), ("dz_stab", "z_stab − z_J"), ("G_fixed", "G fixed box")]
    print(f"## against {path}: here / there, (here − there)/se")
    print("| family | δφ | packings here/there | " + " | ".join(
        f"{name} here | there | ratio | (h−t)/se" for _, name in quantities) + " |")
    print("|---|---|---|" + "---|---|---|---|" * len(quantities))
    # Per quantity, over the matched points: ln(here/there) with its error
    # (relative s.e.m.s in quadrature), the t values, and the relative
    # s.e.m. here over there.
    totals = {q: {"ln": [], "t": [], "sem": []} for q, _ in quantities}
    for row in rows:
        r = ref.get((without_n(row["family"]), round(math.log10(row["delta_phi"]), 6)))
        if r is None:
            continue
        cells = []
        for q, _ in quantities:
            if row[q] == "" or r[q] == "":
                cells.append("– | – | – | –")
                continue
            mh, eh, mt, et = row[q], row[q + "_sem"], float(r[q]), float(r[q + "_sem"])
            se = math.hypot(eh, et)
            ratio = f"{mh / mt:.2f}" if mt != 0 else "–"
            t = f"{(mh - mt) / se:+.2f}" if se > 0 else "–"
            cells.append(f"{mh:.3e} ± {eh:.1e} | {mt:.3e} ± {et:.1e} | {ratio} | {t}")
            if se > 0:
                totals[q]["t"].append((mh - mt) / se)
            if mh > 0 and mt > 0 and eh > 0 and et > 0:
                totals[q]["ln"].append((math.log(mh / mt), math.hypot(eh / mh, et / mt)))
                totals[q]["sem"].append((eh / mh) / (et / mt))
        print(f"| {without_n(row['family'])} | {row['delta_phi']:g} | {row['packings']}/{r['packings']} | "
              + " | ".join(cells) + " |")
    for q, name in quantities:
        ts, lns, sems = totals[q]["t"], totals[q]["ln"], sorted(totals[q]["sem"])
        if not ts:
            continue
        line = (f"{name}: {len(ts)} points, {sum(t < 0 for t in ts)} below; "
                f"sum t / sqrt(n) = {sum(ts) / math.sqrt(len(ts)):+.2f}")
        if lns:
            w = [1 / e ** 2 for _, e in lns]
            mean = sum(wi * l for wi, (l, _) in zip(w, lns)) / sum(w)
            line += (f"; here/there (weighted mean of ln over {len(lns)} positive points) "
                     f"{math.exp(mean):.3f} ± {math.exp(mean) / math.sqrt(sum(w)):.3f}; "
                     f"relative s.e.m. here/there median {sems[len(sems) // 2]:.2f} "
                     f"(range {sems[0]:.2f} … {sems[-1]:.2f})")
        print(line)
    print()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--boot", type=int, default=4000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--range", action="append", default=[], help="LO:HI, delta_phi range of a fit")
    ap.add_argument("--csv", help="write the per-point table here")
    ap.add_argument("--svg", help="draw the collapse G/Delta^1/2 against delta_phi/Delta here")
    ap.add_argument("--against", action="append", default=[], metavar="POINTS.csv",
                    help="compare the points with another run's --csv table (e.g. another N)")
    ap.add_argument("--svg-p", metavar="OUT.svg",
                    help="draw the stabilised G against p for every family here (and --points tables)")
    ap.add_argument("--points", action="append", default=[], metavar="POINTS.csv",
                    help="with --svg-p: also draw the points of another run's --csv table")
    ap.add_argument("--svg-p-only", action="append", default=[], metavar="WORD",
                    help="with --svg-p: only the families with this word in their key (N=1024, sphere, …)")
    ap.add_argument("--vs-p", action="store_true",
                    help="also fit each quantity against the mean pressure of its points")
    ap.add_argument("--ellipse-delta", action="store_true",
                    help="scale the ellipse family as a near-disk with Delta = aspect - 1")
    ap.add_argument("dirs", nargs="+")
    args = ap.parse_args()
    rng = random.Random(args.seed)
    rng_p = random.Random(f"{args.seed} vs p")
    groups, failed, deltas = read(args.dirs, args.ellipse_delta)
    rows = []
    for key in sorted(groups):
        points = groups[key]
        delta = deltas[key]
        print(f"## {key}" + (f" (Delta^2 = {delta * delta:g})" if delta else ""))
        print("delta_phi | packings | p | G fixed box (G<0) | G stabilised (G<0) | z - z_J | z_stab - z_J (packings)")
        for x in sorted(points):
            rs = points[x]
            row = {"family": key, "delta_phi": x, "packings": len(rs)}
            cells = []
            for q, _ in QUANTITIES:
                vs = [r[q] for r in rs if r[q] is not None]
                if not vs:
                    row[q], row[q + "_sem"] = "", ""
                    cells.append("–")
                    continue
                m, se = mean_sem(vs)
                row[q], row[q + "_sem"] = m, se
                neg = sum(v < 0 for v in vs)
                note = f" ({neg})" if q.startswith("G") else ""
                if q == "dz_stab":
                    margins = [r["stab_margin"] for r in rs if r["stab_margin"] is not None]
                    note = f" ({len(vs)}; rattlers {sum(r['stab_rattlers'] for r in rs if r['stab_rattlers'] is not None) / len(vs):.1f}, margin >= {min(margins)})"
                cells.append(f"{m:.3e} ± {se:.1e}" + note)
            rows.append(row)
            if delta and row["G_stab"] != "":
                # The paper's scaling variables: G / Delta^1/2 against
                # delta_phi / Delta.
                cells.append(f"x = {x / delta:.3g}, G_stab/Delta^1/2 = {row['G_stab'] / math.sqrt(delta):.3e}")
            print(f"{x:g} | {len(rs)} | " + " | ".join(cells))
        xs = sorted(points)
        for q, name in QUANTITIES[1:]:
            local = []
            for a, b in zip(xs, xs[1:]):
                r = fit(points, q, a, b, args.boot, rng)
                if r is None:
                    continue
                if r[0] == "mean <= 0":
                    local.append(f"{a:g}-{b:g}: –")
                else:
                    local.append(f"{a:g}-{b:g}: {r[0]:.2f} ± {r[1]:.2f}")
            if local:
                print(f"local slopes of {name}: " + ", ".join(local))
        ranges = [tuple(float(v) for v in r.split(":")) for r in args.range]
        labels = [f"{lo:g} <= delta_phi <= {hi:g}" for lo, hi in ranges]
        if delta:
            # A crossover in delta_phi/Delta^2 (delta_phi ~ Delta^2) and
            # the paper's (its outlook: G ~ Delta^1/2 G~(delta_phi / Delta)).
            for scale, name in ((delta * delta, "Delta^2"), (delta, "Delta")):
                ranges += [(0.0, scale * (1 - 1e-9)), (scale * (1 + 1e-9), math.inf)]
                labels += [f"delta_phi < {name}", f"delta_phi > {name}"]
        for (lo, hi), label in zip(ranges, labels):
            if sum(lo <= x <= hi for x in points) < 2:
                print(f"fits over {label}: fewer than two points")
                continue
            print(f"fits over {label}:")
            for q, name in QUANTITIES:
                show(f"{name} ~ delta_phi^a", fit(points, q, lo, hi, args.boot, rng), args.boot)
            if args.vs_p:
                # Its own random stream, so that the fits against
                # delta_phi stay those of a run without --vs-p.
                for q, name in QUANTITIES[1:]:
                    show(f"{name} ~ p^a", fit(points, q, lo, hi, args.boot, rng_p, "p"), args.boot)
        print()
    collapse(groups, deltas, args.svg)
    if args.svg_p:
        mine = [dict(r, _source="") for r in rows]
        extra = [dict(r, _source=path) for path in args.points for r in csv.DictReader(open(path))]
        pressure_svg(mine + extra, args.svg_p, args.svg_p_only)
    for path in args.against:
        against(rows, path)
    if failed:
        print(f"{len(failed)} failed samples:")
        for sample, why in failed:
            print(f"  {sample}: {why}")
    if args.csv:
        columns = ["family", "delta_phi", "packings"] + [
            c for q, _ in QUANTITIES for c in (q, q + "_sem")
        ]
        write_csv(args.csv, columns, rows)


if __name__ == "__main__":
    main()
