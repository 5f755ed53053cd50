#!/usr/bin/env python3
"""Pictures of a cyclic (fretting) run: each contact's hysteresis loops, the dissipation per
cycle and the worn volume against the cycles, and the wear-depth profiles after each jump.

Usage: plot_hysteresis.py OUT

Reads OUT/hysteresis_<contact>.csv, OUT/cycles.csv, OUT/wear_<contact>.csv,
OUT/point_loops_<contact>.csv and OUT/run.json
(README "Output") and writes into OUT:
- hysteresis_<contact>.png: tangential force ∫p_T dA against the mean relative slip, one loop
  per simulated cycle coloured by the cycles it has reached (the steps before the first cyclic
  step in grey), and beside it each loop minus its secant, which shows the loop's opening;
- cycles.png: energy dissipated per cycle and worn volume against the cycles (every contact);
- wear_<contact>.png: wear-depth profile along the contact (arc length of side A) after each
  jump, coloured by the cycles.
- point_loops_<contact>.png (contacts with `hysteresis_points`): each traced point's local
  loop, shear stress p_T against tangential relative displacement u_T, one loop per simulated
  cycle.
cycles.csv and the wear profiles are optional (a run without cyclic steps or without wear has
none): what is missing is said and skipped. Exits with status 2 when OUT holds no hysteresis
file or a file is malformed.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import Normalize  # noqa: E402

from fretting_data import (HYSTERESIS_COLUMNS, POINT_LOOPS_COLUMNS, WEAR_COLUMNS, OutputError,  # noqa: E402
                           contact_files, Loop, contact_rows, cyclic_steps, loops, point_tables, read_case,
                           read_cycles, read_table, wear_profiles)

COLOURS = "viridis"


def _colour_scale(values: list[float]) -> tuple[plt.cm.ScalarMappable, Normalize]:
    norm = Normalize(min(values), max(values) if max(values) > min(values) else min(values) + 1.0)
    return plt.cm.ScalarMappable(norm=norm, cmap=COLOURS), norm


def _save(fig, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def cyclic_step_numbers(out: Path, hysteresis: dict[str, np.ndarray]) -> set[int]:
    """The analysis steps drawn as loops: the case's cyclic steps (run.json), or, without a
    run.json, the steps with more than one simulated cycle."""
    try:
        return set(cyclic_steps(read_case(out)))
    except OutputError:
        steps = hysteresis["analysis_step"].astype(int)
        return {int(k) for k in np.unique(steps) if len(np.unique(hysteresis["cycle"][steps == k])) > 1}


def secant_offset(lp: Loop) -> np.ndarray:
    """The loop's force minus the straight line through its two turning points (largest and
    smallest force): what is left is the opening of the loop, which a nearly elastic loop
    otherwise hides under its slope."""
    hi, lo = int(np.argmax(lp.force)), int(np.argmin(lp.force))
    if lp.slip[hi] == lp.slip[lo]:
        return lp.force - lp.force[hi]
    slope = (lp.force[hi] - lp.force[lo]) / (lp.slip[hi] - lp.slip[lo])
    return lp.force - (lp.force[hi] + slope * (lp.slip - lp.slip[hi]))


def plot_loops(out: Path, contact: str, hysteresis: dict[str, np.ndarray], cyclic: set[int]) -> Path:
    """hysteresis_<contact>.png: the loops (left) and their opening about the secant (right);
    forces in kN, slips in µm."""
    fig, (ax, opening) = plt.subplots(1, 2, figsize=(12, 5), layout="constrained")
    before = hysteresis["analysis_step"] < min(cyclic, default=np.inf)
    if before.any():
        ax.plot(1e3 * hysteresis["relative_slip"][before], 1e-3 * hysteresis["tangential_force"][before], "-",
                color="0.6", lw=1, label="before the cycles (press-in)")
        ax.legend(fontsize=8)
    cycle_loops = loops(hysteresis, cyclic)
    if cycle_loops:
        mappable, norm = _colour_scale([lp.cycles for lp in cycle_loops])
        for lp in cycle_loops:
            colour = mappable.cmap(norm(lp.cycles))
            ax.plot(1e3 * lp.slip, 1e-3 * lp.force, "-", lw=1.2, color=colour)
            opening.plot(1e3 * lp.slip, 1e-3 * secant_offset(lp), "-", lw=1.2, color=colour)
        fig.colorbar(mappable, ax=[ax, opening], label="cycles N at the end of the loop")
    ax.set_xlabel("mean relative tangential slip u_T [µm]")
    ax.set_ylabel("tangential force ∫p_T dA [kN]")
    ax.set_title(f"contact `{contact}`: {len(cycle_loops)} simulated cycles")
    opening.set_xlabel("mean relative tangential slip u_T [µm]")
    opening.set_ylabel("force minus the loop's secant [kN]")
    opening.set_title("loop opening (dissipation)")
    for a in (ax, opening):
        a.grid(True, alpha=0.3)
    fig.savefig(out / f"hysteresis_{contact}.png", dpi=120)
    plt.close(fig)
    return out / f"hysteresis_{contact}.png"


def plot_point_loops(out: Path, contact: str, table: dict[str, np.ndarray], cyclic: set[int]) -> Path:
    """point_loops_<contact>.png: one panel per traced point, p_T (MPa) against u_T (µm), the
    frames before the cyclic steps in grey and one loop per simulated cycle."""
    points = point_tables(table)
    columns = min(len(points), 3)
    rows = -(-len(points) // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(4.5 * columns, 4 * rows), layout="constrained",
                             squeeze=False)
    cycle_loops = [loops(p, cyclic) for p in points]
    everything = [lp.cycles for group in cycle_loops for lp in group]
    mappable, norm = _colour_scale(everything or [0.0])
    for ax, p, group in zip(axes.flat, points, cycle_loops):
        before = p["analysis_step"] < min(cyclic, default=np.inf)
        if before.any():
            ax.plot(1e3 * p["relative_slip"][before], p["tangential_force"][before], "-", color="0.6", lw=1)
        for lp in group:
            ax.plot(1e3 * lp.slip, lp.force, "-", lw=1.2, color=mappable.cmap(norm(lp.cycles)))
        ax.set_title(f"point {int(p['point'][0])} at ({p['x'][0]:.4g}, {p['y'][0]:.4g}) mm", fontsize=10)
        ax.set_xlabel("tangential relative displacement u_T [µm]")
        ax.set_ylabel("shear stress p_T [MPa]")
        ax.grid(True, alpha=0.3)
    for ax in list(axes.flat)[len(points):]:
        ax.set_visible(False)
    if everything:
        fig.colorbar(mappable, ax=axes.ravel().tolist(), label="cycles N at the end of the loop")
    fig.suptitle(f"contact `{contact}`: local loops of the traced points")
    fig.savefig(out / f"point_loops_{contact}.png", dpi=120)
    plt.close(fig)
    return out / f"point_loops_{contact}.png"


def plot_cycles(out: Path, table: dict[str, np.ndarray]) -> Path:
    """cycles.png: dissipation per simulated cycle and worn volume against the cycles."""
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 7), sharex=True)
    for contact in dict.fromkeys(table["contact"]):
        rows = contact_rows(table, contact)
        top.plot(rows["cycles"], rows["dissipation"], "o-", ms=3, label=contact)
        bottom.plot(rows["cycles"], rows["worn_volume"], "o-", ms=3, label=contact)
    top.set_ylabel("dissipation per cycle [N·mm]")
    top.set_title("energy dissipated per cycle (friction)")
    bottom.set_ylabel("worn volume [mm³]")
    bottom.set_xlabel("cycles N")
    for ax in (top, bottom):
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    return _save(fig, out / "cycles.png")


def plot_wear(out: Path, contact: str, wear: dict[str, np.ndarray]) -> Path:
    """wear_<contact>.png: wear depth (µm) along side A after each jump."""
    profiles = wear_profiles(wear)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    mappable, norm = _colour_scale([n for n, _ in profiles])
    for cycles, p in profiles:
        ax.plot(p["s"], 1e3 * p["wear_depth"], "-", lw=1.2, color=mappable.cmap(norm(cycles)))
    fig.colorbar(mappable, ax=ax, label="cycles N")
    ax.set_xlabel("arc length s along side A [mm]")
    ax.set_ylabel("wear depth h_A + h_B [µm]")
    ax.set_title(f"contact `{contact}`: wear-depth profile after each jump")
    ax.grid(True, alpha=0.3)
    return _save(fig, out / f"wear_{contact}.png")


def plot_all(out: Path) -> tuple[list[tuple[str, Path]], list[str]]:
    """Draws every figure the files in `out` allow. Returns (caption, figure) pairs and notes
    on what was skipped; raises OutputError without any hysteresis file or on a bad file."""
    hysteresis_files = contact_files(out, "hysteresis")
    if not hysteresis_files:
        raise OutputError(f"{out}: no hysteresis_<contact>.csv (not the output folder of a run with contact?)")
    figures, notes = [], []
    cyclic_all: set[int] = set()
    for contact, path in hysteresis_files.items():
        hysteresis = read_table(path, HYSTERESIS_COLUMNS)
        cyclic = cyclic_step_numbers(out, hysteresis)
        cyclic_all |= cyclic
        if not cyclic:
            notes.append(f"{path.name}: no cyclic step: the curve is drawn without loops")
        figures.append((f"hysteresis loops of `{contact}`", plot_loops(out, contact, hysteresis, cyclic)))
    for contact, path in contact_files(out, "point_loops").items():
        points = read_table(path, POINT_LOOPS_COLUMNS)
        if len(points["frame"]):
            figures.append((f"local loops of the traced points of `{contact}`",
                            plot_point_loops(out, contact, points, cyclic_all)))
    table = read_cycles(out, cyclic_all)
    if table is None:
        notes.append(f"no {out / 'cycles.csv'} (written by runs with a cyclic step): dissipation and worn volume not drawn")
    elif len(table["contact"]):
        figures.append(("dissipation per cycle and worn volume", plot_cycles(out, table)))
    else:
        notes.append("cycles.csv has no row of a cyclic step: dissipation and worn volume not drawn")
    wear_files = contact_files(out, "wear")
    for contact, path in wear_files.items():
        wear = read_table(path, WEAR_COLUMNS)
        if len(wear["cycles"]):
            figures.append((f"wear-depth profiles of `{contact}`", plot_wear(out, contact, wear)))
        else:
            notes.append(f"{path.name} has no rows: no profile drawn")
    for contact in hysteresis_files.keys() - wear_files.keys():
        notes.append(f"no wear_{contact}.csv (written for a contact with wear): no wear profile of `{contact}`")
    return figures, notes


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="output folder of the run")
    out = parser.parse_args().out
    try:
        figures, notes = plot_all(out)
    except OutputError as error:
        print(f"plot_hysteresis.py: {error}", file=sys.stderr)
        sys.exit(2)
    for note in notes:
        print(f"note: {note}")
    for _, path in figures:
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
