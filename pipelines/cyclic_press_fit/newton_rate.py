#!/usr/bin/env python3
"""Newton's convergence rate from the log of `asperity -vv run` (its DEBUG lines
`newton iteration=k ... relative_residual=r`): per converged increment the relative
residuals r_1, r_2, ... of its corrections; over the last three above the round-off floor
the order log(r_k+1/r_k) / log(r_k/r_k-1) (2: quadratic, 1: linear) and the last
contraction r_k+1/r_k. Prints the medians and the longest sequence.

Usage: newton_rate.py LOG [FLOOR]   (FLOOR: default 1e-12)
"""

import re
import sys

import numpy as np


def sequences(path):
    """The residual sequences of the converged increments (failed attempts dropped)."""
    done, current = [], []
    for line in open(path):
        m = re.search(r"newton iteration=(\d+) .*relative_residual=(\S+)", line)
        if m:
            if int(m.group(1)) == 0:
                current = []
            current.append(float(m.group(2)))
        elif "increment converged" in line and current:
            done.append(current[1:])
            current = []
    return done


def main(path, floor=1e-12):
    runs = sequences(path)
    orders, contractions = [], []
    for s in runs:
        above = [r for r in s if r > floor]
        if len(above) >= 3 and above[-3] > above[-2] > above[-1]:
            a, b, c = above[-3:]
            orders.append(np.log(c / b) / np.log(b / a))
            contractions.append(c / b)
    iterations = np.array([len(s) for s in runs])
    print(f"{len(runs)} converged increments, {iterations.mean():.1f} iterations each on average")
    if orders:
        o = np.array(orders)
        print(f"terminal order: median {np.median(o):.2f} (quartiles {np.percentile(o, 25):.2f} to "
              f"{np.percentile(o, 75):.2f}), last contraction median {np.median(contractions):.1e}, "
              f"over {len(o)} increments with three or more residuals above {floor:g}")
    print("longest:", " ".join(f"{r:.1e}" for r in max(runs, key=len)))


if __name__ == "__main__":
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    main(sys.argv[1], *(float(a) for a in sys.argv[2:]))
