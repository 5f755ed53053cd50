#!/usr/bin/env python3
"""Runs contact cases with each global contact algorithm (newton, two_step, elastic_contact)
and appends their iteration counts and times, with the machine and date, to BENCHMARKS.md.

Usage: compare_algorithms.py CASE.toml [CASE.toml ...] [--out build/algorithms] [--size S]

Each case must set `contact_algorithm` in its [solver] section; the variants set it to each
algorithm and allow 500 iterations per increment to all three, since the paper's schemes
converge only linearly. Runs execute one at a time, so the times compare. The counts come
from each run's summary.json.
"""
from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path

from asperity_tools import ROOT, run_cases, variant

ALGORITHMS = ["newton", "two_step", "elastic_contact"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cases", nargs="+", type=Path)
    parser.add_argument("--out", type=Path, default=ROOT / "build" / "algorithms")
    parser.add_argument("--size", type=float, default=None)
    args = parser.parse_args()
    rows = []
    for case in args.cases:
        runs = []  # run one at a time below: their times are compared
        for algorithm in ALGORITHMS:
            path = args.out / f"{case.parent.name}_{case.stem}_{algorithm}.toml"
            # The same generous iteration limit for all: the paper's schemes converge linearly.
            variant(case, path, {"solver.contact_algorithm": algorithm}, size=args.size,
                    new={"solver.max_iterations": 500})
            runs.append((path, args.out / path.stem))
        for (path, out), algorithm in zip(runs, ALGORITHMS):
            start = time.perf_counter()
            summary = run_cases([(path, out)], jobs=1, fail_fast=False)[0]
            seconds = time.perf_counter() - start
            if summary["status"] != "converged":
                first = summary["error"].splitlines()[0].removeprefix("error: ")
                rows.append(f"| {case.parent.name}/{case.stem} | | {algorithm} | | did not converge: {first[:120]} | {seconds:.2f} |")
                print(rows[-1])
                continue
            unknowns, totals = summary["model"]["unknowns"], summary["totals"]
            rows.append(f"| {case.parent.name}/{case.stem} | {unknowns} | {algorithm} | {totals['increments']} "
                        f"| {totals['iterations']} | {seconds:.2f} |")
            print(rows[-1])
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), platform.processor())
    with open(ROOT / "BENCHMARKS.md", "a") as f:
        f.write(f"\n### Global contact algorithms on the paper's examples, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
                f"{cpu}, {os.cpu_count()} cores\n\n")
        f.write("| case | unknowns | algorithm | increments | Newton iterations | wall time [s] |\n|---|---|---|---|---|---|\n")
        f.write("\n".join(rows) + "\n")


if __name__ == "__main__":
    main()
