"""Plots of an `asperity fit` result folder: fit.png (measured with error bars and fitted curve
of every test) and residuals.png (weighted residuals (fitted - measured) / sigma).

    .venv/bin/python pipelines/fit/plot_fit.py OUT    # OUT holds curves.csv and fit.json
"""
import csv
import json
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))
from asperity_tools import run_main, save_figure  # noqa: E402

AXES = {  # (x label, y label) of each test kind, in asperity's units
    "normal": ("closure [mm]", "pressure [MPa]"),
    "tangential": ("tangential displacement [mm]", "shear stress [MPa]"),
    "model": ("step", "quantity"),
}


def read(out):
    tests = {}
    with open(out / "curves.csv") as f:
        for row in csv.DictReader(f):
            t = tests.setdefault(row["test"], {k: [] for k in ("x", "measured", "fitted", "sigma", "residual")})
            for k in t:
                t[k].append(float(row[k]))
    return tests


def kind(label):
    return label.split()[1] if len(label.split()) > 1 else "model"


def main(out):
    out = pathlib.Path(out)
    tests = read(out)
    result = json.loads((out / "fit.json").read_text())
    n = len(tests)
    fig, axes = plt.subplots(1, n, figsize=(4.5 * n, 4), squeeze=False)
    for ax, (label, t) in zip(axes[0], tests.items()):
        ax.errorbar(t["x"], t["measured"], yerr=t["sigma"], fmt="o", ms=3, label="measured")
        ax.plot(t["x"], t["fitted"], "-", label="fitted")
        xl, yl = AXES.get(kind(label), ("x", "y"))
        ax.set(xlabel=xl, ylabel=yl, title=label.split(" (")[0])
        ax.legend()
    status = "" if result["identifiable"] else " (NOT identifiable)"
    fig.suptitle(f"{result['law']}: chi2 = {result['chi_square']:.4g} over {result['points']} points{status}")
    fig.tight_layout()
    save_figure(fig, out / "fit.png")
    fig, axes = plt.subplots(1, n, figsize=(4.5 * n, 3.5), squeeze=False)
    for ax, (label, t) in zip(axes[0], tests.items()):
        ax.axhline(0, color="k", lw=0.8)
        ax.plot(t["x"], t["residual"], "o", ms=3)
        ax.set(xlabel=AXES.get(kind(label), ("x",))[0], ylabel="(fitted - measured) / sigma",
               title=label.split(" (")[0])
    fig.tight_layout()
    save_figure(fig, out / "residuals.png")


if __name__ == "__main__":
    run_main(lambda: main(sys.argv[1]))
