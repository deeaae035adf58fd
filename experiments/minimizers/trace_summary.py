#!/usr/bin/env python3
"""Where a jamming run spends its minimiser steps (standard library only).

    jamkit bench packing ... --trace TRACE.csv
    python3 experiments/minimizers/trace_summary.py TRACE.csv

Groups the minimisations of each packing (seed) of the trace by how they
ended and how far below the final phi_J they ran: the early compression
(phi < phi_J - 0.05), the approach (phi_J - 0.05 ... phi_J - 0.01), the
minimisations near jamming that ended on the energy test, and those that
ended on the force test (above phi_J). Prints minimisations, FIRE steps
(and their share), and Newton iterations per group.
"""

import csv
import sys
from collections import defaultdict


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    by_seed = defaultdict(list)
    with open(sys.argv[1], newline="") as f:
        for row in csv.DictReader(f):
            by_seed[row["seed"]].append(row)
    groups = ["early", "approach", "energy near phi_J", "force"]
    print("| seed | group | minimisations | FIRE steps | share | Newton iterations |")
    print("|---|---|---|---|---|---|")
    for seed, rows in by_seed.items():
        phi_j = float(rows[-1]["phi"])
        tally = {g: [0, 0, 0] for g in groups}
        for r in rows:
            phi = float(r["phi"])
            if r["reason"] == "Force":
                g = "force"
            elif phi > phi_j - 0.01:
                g = "energy near phi_J"
            elif phi > phi_j - 0.05:
                g = "approach"
            else:
                g = "early"
            t = tally[g]
            t[0] += 1
            t[1] += int(r["fire_steps"])
            t[2] += int(r["newton_iterations"])
        total = sum(t[1] for t in tally.values()) or 1
        for g in groups:
            n, steps, newton = tally[g]
            print(f"| {seed} | {g} | {n} | {steps} | {100 * steps / total:.0f} % | {newton} |")


if __name__ == "__main__":
    main()
