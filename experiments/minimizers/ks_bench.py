#!/usr/bin/env python3
"""Compare two arms of `jamkit bench packing` rows (standard library only).

    python3 experiments/minimizers/ks_bench.py FILE.csv [ARM_A ARM_B]

FILE.csv holds `bench packing` rows with an extra first column `arm` (as
docs/minimizers/bench_lbfgs_blocks_*.csv); the arms default to `lbfgs_blocks`
and `default`. For phi_j and z_j it prints the two means with their
standard errors, the difference in units of its standard error, the
paired difference (same seeds) and the two-sample Kolmogorov-Smirnov
statistic with its asymptotic p-value (`compare.py`'s); for cpu_s the
mean, median and maximum of each arm.
"""

import csv
import statistics
import sys

from compare import ks, mean_sem


def main():
    args = sys.argv[1:]
    if len(args) not in (1, 3):
        sys.exit(__doc__)
    arms = args[1:] or ["lbfgs_blocks", "default"]
    rows = {arm: {} for arm in arms}
    with open(args[0], newline="") as f:
        for row in csv.DictReader(f):
            if row["arm"] in rows:
                rows[row["arm"]][int(row["seed"])] = row
    a, b = (rows[arm] for arm in arms)
    seeds = sorted(set(a) & set(b))
    print(f"{args[0]}: {arms[0]} against {arms[1]}, {len(seeds)} seeds")
    for q in ["phi_j", "z_j"]:
        xa = [float(a[s][q]) for s in seeds]
        xb = [float(b[s][q]) for s in seeds]
        (ma, sa), (mb, sb) = mean_sem(xa), mean_sem(xb)
        paired, paired_se = mean_sem([x - y for x, y in zip(xa, xb)])
        lower = sum(x < y for x, y in zip(xa, xb))
        d, p = ks(xa, xb)
        print(f"{q}: {ma:.5f} ± {sa:.5f} against {mb:.5f} ± {sb:.5f}, "
              f"Δ/s.e. {(ma - mb) / (sa * sa + sb * sb) ** 0.5:+.2f}, "
              f"paired {paired:+.5f} ± {paired_se:.5f} (lower in {lower} of {len(seeds)}), "
              f"KS D {d:.3f}, p {p:.3f}")
    for arm, r in zip(arms, (a, b)):
        cpu = [float(r[s]["cpu_s"]) for s in seeds]
        print(f"cpu_s {arm}: mean {statistics.mean(cpu):.1f}, median {statistics.median(cpu):.1f}, "
              f"max {max(cpu):.1f}")


if __name__ == "__main__":
    main()
