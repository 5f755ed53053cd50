"""Plots of a sweep collected by `asperity sweep collect`: for each quantity of sweep.csv,
<quantity>.png with one panel per varied key (the quantity of every converged run against
that key).

    .venv/bin/python pipelines/sweep/plot_sweep.py STUDY   # STUDY holds sweep.csv and manifest.json
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


def number(s):
    try:
        return float(s)
    except ValueError:
        return None


def main(study):
    study = pathlib.Path(study)
    manifest = json.loads((study / "manifest.json").read_text())
    with open(study / "sweep.csv") as f:
        rows = [r for r in csv.DictReader(f) if r["status"] == "converged"]
    keys = manifest["keys"]
    for q in manifest["quantities"]:
        fig, axes = plt.subplots(1, len(keys), figsize=(4.5 * len(keys), 3.8), squeeze=False)
        for ax, key in zip(axes[0], keys):
            pts = [(number(r[key]), number(r[q])) for r in rows]
            pts = sorted(p for p in pts if p[0] is not None and p[1] is not None)
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o")
            ax.set(xlabel=key, ylabel=q)
        fig.suptitle(f"{q} ({len(rows)} converged runs of {len(manifest['runs'])})")
        fig.tight_layout()
        save_figure(fig, study / f"{q}.png")
        plt.close(fig)


if __name__ == "__main__":
    run_main(lambda: main(sys.argv[1]))
