#!/usr/bin/env python3
"""Pictures of a finished run: von Mises stress on the deformed shape (last step) and the
reaction forces of every support against the load factor.

Usage: plot_fields.py OUT_DIR [--case CASE.toml] [--scale S]

Writes OUT_DIR/von_mises.png and OUT_DIR/reactions.png. The deformation is magnified so the
largest displacement is 5 % of the model size unless --scale is given.
"""
import argparse
import csv
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pyvista as pv  # noqa: E402

pv.OFF_SCREEN = True


def von_mises_picture(out: Path, scale: float | None) -> Path:
    reader = pv.get_reader(out / "results.pvd")
    reader.set_active_time_value(reader.time_values[-1])
    grid = reader.read()[0]
    u = np.asarray(grid.point_data["displacement"])
    size = max(grid.bounds[1] - grid.bounds[0], grid.bounds[3] - grid.bounds[2])
    umax = np.abs(u).max()
    factor = scale if scale is not None else (0.05 * size / umax if umax > 0 else 0.0)
    warped = grid.warp_by_vector("displacement", factor=factor)
    plotter = pv.Plotter(off_screen=True, window_size=(1200, 900))
    plotter.add_mesh(warped.extract_surface(nonlinear_subdivision=3, algorithm='dataset_surface'), scalars="von_mises", cmap="viridis",
                     scalar_bar_args={"title": "von Mises stress [MPa]"})
    plotter.add_mesh(grid.extract_feature_edges(), color="gray", opacity=0.4)
    plotter.add_text(f"step {int(reader.time_values[-1])}, deformation x {factor:.3g}", font_size=10)
    plotter.view_xy()
    path = out / "von_mises.png"
    plotter.screenshot(path)
    plotter.close()
    return path


def reaction_plot(out: Path) -> Path:
    with open(out / "history.csv") as f:
        rows = list(csv.DictReader(f))
    factors = [float(r["load_factor"]) for r in rows]
    fig, ax = plt.subplots(figsize=(6, 4))
    for name in rows[0]:
        if name.startswith("reaction_"):
            values = [float(r[name]) for r in rows]
            if any(abs(v) > 0 for v in values):
                ax.plot(factors, values, "o-", label=name.removeprefix("reaction_"))
    ax.set_xlabel("load factor")
    ax.set_ylabel("reaction force [N]")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    path = out / "reactions.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--case", type=Path, help="the case file (for the record)")
    parser.add_argument("--scale", type=float, default=None, help="deformation magnification")
    args = parser.parse_args()
    for path in (von_mises_picture(args.out, args.scale), reaction_plot(args.out)):
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
