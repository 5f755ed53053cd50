#!/usr/bin/env python3
"""Log-log picture of a mesh-convergence study written by `asperity converge`.

Usage: plot_convergence.py OUT_DIR

Reads OUT_DIR/convergence.csv and writes OUT_DIR/convergence.png: for every quantity the
relative error of each level against its reference (solid, where the quantity has one) or
against the Richardson-extrapolated value (dashed), and the relative successive differences
|q_k - q_(k-1)| / |q| (dotted, drawn at the finer level's h), against the relative mesh
size h. The legend gives the observed order. `asperity converge` runs this script itself
when it finds it and a Python with matplotlib (docs/guide/convergence-studies.md, "Where the plot script is found").
"""
import argparse
import csv
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from asperity_tools import run_main, save_figure  # noqa: E402


def number(text: str) -> float | None:
    return float(text) if text not in ("", None) else None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    args = parser.parse_args()
    with open(args.out / "convergence.csv") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise ValueError(f"{args.out / 'convergence.csv'}: no levels to plot")
    quantities: dict[str, list[dict]] = {}
    for row in rows:
        quantities.setdefault(row["quantity"], []).append(row)

    fig, ax = plt.subplots(figsize=(7, 5))
    plotted = False
    for i, (name, levels) in enumerate(quantities.items()):
        color = f"C{i % 10}"
        h = [float(r["h"]) for r in levels]
        q = [float(r["value"]) for r in levels]
        scale = max(abs(v) for v in q) or 1.0
        first = levels[0]
        order = number(first["order"])
        label = f"{name} ({first['status'].replace('_', ' ')}"
        label += f", order {order:.2f})" if order is not None else ")"
        reference = number(first["reference"])
        extrapolated = number(first["extrapolated"])
        if reference is not None:
            err = [abs(v - reference) / (abs(reference) or 1.0) for v in q]
            style, what = "o-", "vs reference"
        elif extrapolated is not None:
            err = [abs(v - extrapolated) / scale for v in q]
            style, what = "o--", "vs extrapolated"
        else:
            err, what = [], ""
        points = [(x, e) for x, e in zip(h, err) if e > 0 and math.isfinite(e)]
        if points:
            ax.loglog(*zip(*points), style, color=color, label=f"{label}: error {what}")
            plotted = True
        diffs = [(float(r["h"]), abs(float(r["difference"])) / scale) for r in levels if r["difference"] != ""]
        diffs = [(x, d) for x, d in diffs if d > 0]
        if diffs:
            ax.loglog(*zip(*diffs), "s:", color=color, ms=4,
                      label=f"{name if points else label}: |difference|")
            plotted = True
    if not plotted:
        ax.text(0.5, 0.5, "no non-zero errors or differences", transform=ax.transAxes, ha="center")
    ax.set_xlabel("relative mesh size h (gmsh size factor)")
    ax.set_ylabel("relative error / difference")
    ax.set_title(f"mesh convergence: {args.out.name}")
    ax.grid(True, which="both", alpha=0.3)
    if plotted:
        ax.legend(fontsize=7)
    fig.tight_layout()
    path = args.out / "convergence.png"
    save_figure(fig, path)
    plt.close(fig)
    print(f"wrote {path}")


if __name__ == "__main__":
    run_main(main)
