#!/usr/bin/env python3
"""Pictures of a finished run: von Mises stress on the deformed shape (last step), the
reaction forces of every support against the load factor, and, for runs with contact pairs,
the contact stresses along each interface (last step).

Usage: plot_fields.py OUT_DIR [--case CASE.toml] [--scale S]

Writes OUT_DIR/von_mises.png, OUT_DIR/reactions.png and OUT_DIR/contact_<pair>.png. The deformation is magnified so the
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
from asperity_tools import read_step, run_main, save_figure  # noqa: E402

pv.OFF_SCREEN = True


def field_picture(out: Path, scalars: str, title: str, name: str, step: int | None = None,
                  scale: float | None = None) -> Path:
    """The bodies' point field `scalars` on the deformed shape of step `step` (default: the
    last) as OUT/<name>.png."""
    blocks = read_step(out, step)
    grid = blocks["bodies"]
    u = np.asarray(grid.point_data["displacement"])
    size = max(grid.bounds[1] - grid.bounds[0], grid.bounds[3] - grid.bounds[2])
    umax = np.abs(u).max()
    factor = scale if scale is not None else (0.05 * size / umax if umax > 0 else 0.0)
    warped = grid.warp_by_vector("displacement", factor=factor)
    plotter = pv.Plotter(off_screen=True, window_size=(1200, 900))
    plotter.add_mesh(warped.extract_surface(nonlinear_subdivision=3, algorithm='dataset_surface'), scalars=scalars, cmap="viridis",
                     scalar_bar_args={"title": title})
    plotter.add_mesh(grid.extract_feature_edges(), color="gray", opacity=0.4)
    plotter.add_text(f"step {int(blocks.field_data['step'][0])}, deformation x {factor:.3g}", font_size=10)
    plotter.view_xy()
    path = out / f"{name}.png"
    plotter.screenshot(path)
    plotter.close()
    return path


def von_mises_picture(out: Path, scale: float | None) -> Path:
    return field_picture(out, "von_mises", "von Mises stress [MPa]", "von_mises", scale=scale)


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
    save_figure(fig, path)
    plt.close(fig)
    return path


def contact_plots(out: Path) -> list[Path]:
    """Contact pressure and shear stress along each pair's curve at the last step."""
    paths = []
    pairs = sorted({p.name.rsplit("_", 1)[0] for p in out.glob("contact_*_*.csv")})
    for pair in pairs:
        last = sorted(out.glob(f"{pair}_*.csv"))[-1]
        data = np.genfromtxt(last, delimiter=",", names=True)
        fig, ax = plt.subplots(figsize=(6, 4))
        ax.plot(data["arc_length"], data["contact_pressure"], "o-", ms=3, label="contact pressure −p_N")
        ax.plot(data["arc_length"], data["contact_shear_stress"], "s-", ms=3, label="shear stress p_T")
        ax.set_xlabel("arc length along side B [mm]")
        ax.set_ylabel("contact stress [MPa]")
        ax.set_title(f"{pair.removeprefix('contact_')}, {last.stem.rsplit('_', 1)[1]}")
        ax.grid(True, alpha=0.3)
        ax.legend()
        fig.tight_layout()
        path = out / f"{pair}.png"
        save_figure(fig, path)
        plt.close(fig)
        paths.append(path)
    return paths


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--case", type=Path, help="the case file (for the record)")
    parser.add_argument("--scale", type=float, default=None, help="deformation magnification")
    args = parser.parse_args()
    for path in [von_mises_picture(args.out, args.scale), reaction_plot(args.out), *contact_plots(args.out)]:
        print(f"wrote {path}")


if __name__ == "__main__":
    run_main(main)
