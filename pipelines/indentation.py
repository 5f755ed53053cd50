#!/usr/bin/env python3
"""Indentation of an elastic punch into an elasto-plastic foundation (paper §4.3, Figs. 7-11).

Usage: indentation.py [--out out/indentation] [--size S] [--quick] [--jobs N]

Runs every study of pipelines/indentation/*.toml in parallel (each case file is copied with
absolute paths and the mesh size into OUT/cases/, each run writes OUT/<run>/), then writes
into OUT:
  tangential_stress_r1.png, tangential_stress_r2.png   p_T along the interface for the friction
                                                       models (a), (b), (c) at r = 1, 2 (Figs. 8-9)
  normalised_contact_stress.png                        p_N/p_m, p_T/p_m against r/a for the ideal
                                                       Coulomb model, mu = 0.1 and 0.2 (Fig. 10)
  deflection_vs_hardening.png                          foundation top deflection against h (Fig. 11)
  (the foundation uses the default, locking-free B-bar element; one extra run repeats h = 0 with
  the fully integrated element, formulation = "full", for the report's comparison)
  stick_slip_zones.png                                 contact status along r/a for every run
  fields_<run>.png                                     von Mises stress and equivalent plastic
                                                       strain on the deformed shape (last step)
  REPORT.md                                            zones vs the paper, equilibrium, tables,
                                                       solver statistics
and exits non-zero with a message if a check fails: expected arrays and columns present;
vertical equilibrium (interface normal resultant and foundation reaction against the applied
load) within 5e-4 relative (the solver's residual tolerance R_n) at every step; for mu_m = 0.2 at r = 2 an inner stick zone and an
outer slip annulus (the paper's hardening model, mu_m = beta = 0.2). A run of the hardening
sweep may stop before Q = 4.6 pi a^2 p0 (without hardening that load is at the collapse load):
it is reported with the last load it carried; any other failed run stops the pipeline.

--quick uses a coarse mesh (size 2.5: 8 elements along the contact instead of 20) and three
hardening values, for CI; --size overrides the mesh size factor of every study.
"""
from __future__ import annotations

import re
import argparse
import os
import subprocess
import sys
import time
import tomllib
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pyvista as pv  # noqa: E402
from vtkmodules.vtkCommonCore import vtkLogger  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from asperity_tools import (  # noqa: E402
    BINARY, ROOT, phase_seconds, read_contact, read_frame, read_history, run_cases, rust_exp, table, variant, write_report,
)

pv.OFF_SCREEN = True

STUDIES = ROOT / "pipelines" / "indentation"
PAIR = "interface"
A_PUNCH = 10.0                  # punch radius a [mm] (the .geo default; the cases use it)
H_FOUNDATION = 40.0             # foundation height H [mm]
P0 = 20.0 * np.pi               # the paper's p0 [MPa]
TOP_PRESSURE = 1.6 * P0         # top pressure at load factor 1 (r = 1) [MPa]
SIGMA_Y = 90.0
HARDENING = [0.0, 100.0, 500.0, 1000.0, 2000.0, 5000.0, 10000.0]
HARDENING_QUICK = [0.0, 1000.0, 10000.0]
SWEEP_FACTOR = 4.6 / 1.6        # Q = 4.6 pi a² p0 in units of r
# Every residual component is at most R_n times the average nodal force (the default criterion,
# [solver] residual_tolerance = 5e-4), so a resultant is out of balance by about R_n at most.
EQUILIBRIUM_TOL = 5e-4
HISTORY_COLUMNS = ["step", "load_factor", "iterations", "reaction_foundation_bottom_y",
                   f"{PAIR}_normal_force", f"{PAIR}_tangential_force", f"{PAIR}_force_on_b_y"]
CONTACT_COLUMNS = ["x", "y", "contact_normal_stress", "contact_pressure", "contact_shear_stress",
                   "tangential_slip", "plastic_slip", "friction_coefficient", "contact_status"]
POINT_ARRAYS = ["displacement", "von_mises", "equivalent_plastic_strain"]
CELL_ARRAYS = ["body", "plastic"]
FOUNDATION = 1                  # index of the foundation in the cases' [[body]] list
STICK, SLIP = 1, 2


def fail(message: str) -> None:
    sys.exit(f"indentation check failed: {message}")


# --- runs ------------------------------------------------------------------------------------
def plan(out: Path, size: float, quick: bool) -> dict[str, dict]:
    """Every run: its case (a variant of a study file) and what it is. The adhesion study's
    set (1), hardening mu_m = beta = 0.1, is friction model (c) (the same case), and Fig. 10's
    ideal Coulomb mu_m = 0.1 is model (a): those runs are reused, not repeated."""
    cases = out / "cases"
    runs = {
        "model_a": dict(study="friction_models", label="(a) ideal Coulomb, μm = 0.1, β = 1, R = 0.05e-3",
                        short="(a) ideal Coulomb μm = 0.1",
                        changes={}),
        "model_b": dict(study="friction_models", label="(b) regularised Coulomb, μm = 0.1, β = 1, R = 1.0e-3",
                        short="(b) regularised μm = 0.1",
                        changes={"contact[0].law.R": 1.0e-3}),
        "model_c": dict(study="friction_models",
                        label="(c) hardening Coulomb, μm = 0.1, β = 0.1, R = 0.05e-3 (adhesion set 1)",
                        short="(c) hardening μm = β = 0.1",
                        changes={"contact[0].law.beta": 0.1}),
        "adhesion_mu0.2": dict(study="adhesion_zones",
                               label="hardening μm = 0.2, β = 0.2, R = 0.05e-3 (adhesion set 2)",
                               short="hardening μm = β = 0.2",
                               changes={}),
        "coulomb_mu0.2": dict(study="normalised_stress", label="ideal Coulomb μm = 0.2, β = 1, R = 0.05e-3",
                              short="ideal Coulomb μm = 0.2", changes={}),
    }
    for h in (HARDENING_QUICK if quick else HARDENING):
        runs[f"hardening_{h:g}"] = dict(study="hardening_sweep", label=f"h = {h:g} MPa", h=h,
                                        changes={f"body[{FOUNDATION}].material.hardening": h})
    # Issue 17: the same perfectly plastic case with the fully integrated (locking) element.
    runs["hardening_0_full"] = dict(study="hardening_sweep", label="h = 0 MPa, fully integrated element", h=0.0,
                                    full=True, changes={f"body[{FOUNDATION}].material.hardening": 0.0},
                                    new={f"body[{FOUNDATION}].formulation": "full"})
    for name, run in runs.items():
        run["case"] = variant(STUDIES / f"{run['study']}.toml", cases / f"{name}.toml", run["changes"], size=size,
                              new=run.get("new"))
        run["out"] = out / name
    return runs


# --- reading and checking ----------------------------------------------------------------
def step_at(history: dict[str, np.ndarray], factor: float, run: str) -> int:
    hit = np.flatnonzero(np.abs(history["load_factor"] - factor) < 1e-9)
    if len(hit) != 1:
        fail(f"{run}: no step at load factor {factor} in history.csv")
    return int(history["step"][hit[0]])


def contact_at(out: Path, step: int) -> dict[str, np.ndarray]:
    data = read_contact(out, PAIR, step)
    missing = [c for c in CONTACT_COLUMNS if c not in data]
    if missing:
        fail(f"{out}/contact_{PAIR}_{step:04d}.csv: columns {missing} missing (have {list(data)})")
    order = np.argsort(data["x"])
    return {k: v[order] for k, v in data.items()}


def bodies(out: Path, step: int) -> pv.UnstructuredGrid:
    """The bodies of output frame `step` in one grid (cell data `body`)."""
    frame = out / f"frame_{step:04d}.vtm"
    grid = read_frame(frame)["bodies"]
    for name in POINT_ARRAYS:
        if name not in grid.point_data:
            fail(f"{frame}: point array '{name}' missing (have {list(grid.point_data)})")
        if not np.all(np.isfinite(grid.point_data[name])):
            fail(f"{frame}: '{name}' has non-finite values")
    for name in CELL_ARRAYS:
        if name not in grid.cell_data:
            fail(f"{frame}: cell array '{name}' missing")
    return grid


def reached(run: dict) -> float:
    """The load factor of the last converged (sub-)increment of a run that stopped: its error
    message gives the pseudo-time t of that state (step k ends at t = k, load factors linear in
    between, README `[steps]`)."""
    m = re.search(r"last converged load factor λ_c = ([0-9.eE+-]+)", run["stopped"] or "")
    if m:
        return float(m.group(1).rstrip("."))
    m = re.search(r"last converged state is at time ([0-9]+(?:\.[0-9]+)?)", run["stopped"] or "")
    factors = tomllib.loads(run["case"].read_text())["steps"]["factors"]
    if not m:
        return float(run["history"]["load_factor"][-1])
    t = float(m.group(1))
    k = min(int(t), len(factors) - 1)
    below = factors[k - 1] if k > 0 else 0.0
    return below + (t - k) * (factors[k] - below)


def check_history(name: str, history: dict[str, np.ndarray]) -> dict[str, float]:
    """Vertical equilibrium at every step: the interface normal resultant (∫ p_N dA, the
    force on the foundation) and the foundation's support reaction against the applied load
    Q = p π a². Returns the largest relative errors."""
    missing = [c for c in HISTORY_COLUMNS if c not in history]
    if missing:
        fail(f"{name}/history.csv: columns {missing} missing (have {list(history)})")
    q = TOP_PRESSURE * history["load_factor"] * np.pi * A_PUNCH**2
    errors = {
        "normal": np.max(np.abs(-history[f"{PAIR}_normal_force"] - q) / q),
        "on_b": np.max(np.abs(-history[f"{PAIR}_force_on_b_y"] - q) / q),
        "support": np.max(np.abs(history["reaction_foundation_bottom_y"] - q) / q),
    }
    worst = max(errors.values())
    if not worst <= EQUILIBRIUM_TOL:
        fail(f"{name}: vertical equilibrium error {worst:.3e} > {EQUILIBRIUM_TOL:g} "
             f"(interface {errors['normal']:.2e}, force on foundation {errors['on_b']:.2e}, "
             f"support {errors['support']:.2e})")
    return errors


def zones(c: dict[str, np.ndarray]) -> dict:
    """Stick/slip zones along the contact (nodes sorted by r): counts, the inner stick zone
    (the stick nodes contiguous with the axis), the slip nodes beyond it, and the status of
    the corner node r = a."""
    r = c["x"] / A_PUNCH
    s = c["contact_status"].astype(int)
    inner = 0
    for v in s:
        if v != STICK:
            break
        inner += 1
    stick, slip = s == STICK, s == SLIP
    return dict(
        nodes=len(s), stick=int(stick.sum()), slip=int(slip.sum()), open=int((s == 0).sum()),
        off_axis_stick=int((stick & (r > 1e-9)).sum()),
        inner_stick=inner,
        inner_stick_to=float(r[inner - 1]) if inner else float("nan"),
        first_slip=float(r[slip].min()) if slip.any() else float("nan"),
        outer_slip=int((slip & (r >= 0.9)).sum()),
        restick=int((stick & (r > (r[slip].min() if slip.any() else 1.0))).sum()),
        corner={0: "open", STICK: "stick", SLIP: "slip"}[s[-1]],
        status="".join({0: "o", STICK: "=", SLIP: "~"}[v] for v in s),
    )


def annulus_problems(z: dict) -> list[str]:
    """Why the contact is not an inner stick zone with an outer slip annulus, if it is not:
    the stick zone must contain the axis and reach at least r = a/2 without interruption,
    and there must be slipping nodes in the outer tenth, r >= 0.9 a. (The corner node itself
    may stick: at higher loads the foundation's plastic flow reverses the slip there.)"""
    problems = []
    if z["open"]:
        problems.append(f"{z['open']} open nodes")
    if z["inner_stick"] == 0:
        problems.append("the node on the axis does not stick")
    elif z["inner_stick_to"] < 0.5:
        problems.append(f"the stick zone around the axis ends at r/a = {z['inner_stick_to']:.3f} < 0.5")
    if z["outer_slip"] == 0:
        problems.append("no node slips in r >= 0.9 a")
    return problems


def check_annulus(name: str, factor: float, z: dict) -> None:
    problems = annulus_problems(z)
    if problems:
        fail(f"{name} at r = {factor:g}: no inner stick zone with an outer slip annulus: "
             f"{'; '.join(problems)} (status from the axis, = stick ~ slip: {z['status']})")


def first_yield(out: Path, history: dict[str, np.ndarray]) -> tuple[int, float]:
    """The first step in which any foundation integration point yielded."""
    for step, factor in zip(history["step"].astype(int), history["load_factor"]):
        if np.asarray(bodies(out, step).cell_data["plastic"]).any():
            return step, float(factor)
    return -1, float("nan")


def top_deflection(out: Path, step: int) -> tuple[np.ndarray, np.ndarray]:
    """r and u_z of the foundation's upper face z = H (foundation nodes only)."""
    grid = bodies(out, step)
    found = grid.extract_cells(np.flatnonzero(np.asarray(grid.cell_data["body"]) == FOUNDATION))
    pts = np.asarray(found.points)
    top = np.abs(pts[:, 1] - H_FOUNDATION) < 1e-9
    if top.sum() < 3:
        fail(f"{out}: the foundation's upper face z = {H_FOUNDATION} has no nodes in body {FOUNDATION}")
    r = pts[top, 0]
    uz = np.asarray(found.point_data["displacement"])[top, 1]
    order = np.argsort(r)
    return r[order], uz[order]


def centre_deflection(out: Path, step: int) -> float:
    """−u_z of the foundation's top on the axis (r = 0, z = H)."""
    grid = read_frame(out / f"frame_{step:04d}.vtm")["bodies"]
    pts = np.asarray(grid.points)
    body = np.zeros(len(pts), dtype=int) - 1
    cells = np.asarray(grid.cell_connectivity).reshape(grid.n_cells, -1)
    body[cells[np.asarray(grid.cell_data["body"]) == FOUNDATION].ravel()] = FOUNDATION
    at = np.flatnonzero((body == FOUNDATION) & (np.abs(pts[:, 0]) < 1e-9) & (np.abs(pts[:, 1] - H_FOUNDATION) < 1e-9))
    if len(at) != 1:
        fail(f"{out}: expected one foundation node at r = 0, z = H, found {len(at)}")
    return -float(np.asarray(grid.point_data["displacement"])[at[0], 1])


# --- pictures ----------------------------------------------------------------------------
def tangential_plot(path: Path, runs: dict, factor: float) -> None:
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for name, marker in (("model_a", "s-"), ("model_b", "^-"), ("model_c", "*-")):
        c = runs[name]["contact"][factor]
        ax.plot(c["x"], c["contact_shear_stress"], marker, ms=5, lw=1, label=runs[name]["label"])
    c = runs["model_a"]["contact"][factor]
    ax.plot(c["x"], 0.1 * c["contact_pressure"], ":", color="gray", label="μm |p_N| (model a)")
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xlabel("r [mm]    (p_T > 0: friction drags the foundation outward, +r, and the punch inward)",
                  fontsize=9)
    ax.set_ylabel("tangential contact stress p_T [MPa]")
    ax.set_title(f"Tangential contact stress at r = {factor:g} "
                 f"(top pressure {factor * 1.6:g} p0 = {factor * TOP_PRESSURE:.1f} MPa)", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def normalised_plot(path: Path, runs: dict, columns: list[tuple[str, float]]) -> None:
    """p_N/p_m and p_T/p_m against r/a; one column per (title, load factor)."""
    fig, axes = plt.subplots(2, len(columns), figsize=(6 * len(columns), 7), sharex=True, squeeze=False)
    rr = np.linspace(0, 0.98, 200)
    for j, (title, factor) in enumerate(columns):
        for name, mu, style in (("model_a", 0.1, "o-"), ("coulomb_mu0.2", 0.2, "s-")):
            c = runs[name]["contact"][factor]
            pm = factor * TOP_PRESSURE
            r = c["x"] / A_PUNCH
            axes[0, j].plot(r, c["contact_normal_stress"] / pm, style, ms=3, lw=1, label=f"ideal Coulomb μ = {mu}")
            line, = axes[1, j].plot(r, c["contact_shear_stress"] / pm, style, ms=3, lw=1,
                                    label=f"ideal Coulomb μ = {mu}")
            slip = c["contact_status"] == SLIP
            axes[1, j].plot(r[slip], mu * c["contact_pressure"][slip] / pm, "x", color=line.get_color(), ms=5,
                            label=f"slip nodes (μ |p_N| / p_m), μ = {mu}")
        axes[0, j].plot(rr, -0.5 / np.sqrt(1 - rr**2), "--", color="gray", lw=1,
                        label="Sneddon: rigid punch, elastic half-space")
        axes[0, j].set_title(title, fontsize=10)
        axes[0, j].set_ylabel("p_N / p_m")
        axes[1, j].set_ylabel("p_T / p_m")
        axes[1, j].set_xlabel("r / a")
        axes[1, j].axhline(0, color="k", lw=0.5)
        for ax in axes[:, j]:
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=7)
        axes[0, j].set_ylim(-3.5, 0)
    fig.suptitle("Normalised contact stresses, ideal Coulomb model (p_m = Q / πa², p_N < 0 in compression)",
                 fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def deflection_plot(path: Path, sweep: list[dict], locking: list[dict]) -> None:
    fig, (left, middle, right) = plt.subplots(1, 3, figsize=(17, 4.8))
    for s in sweep:
        left.plot(s["r"], -s["uz"] * 1e3, "-", lw=1.2, label=s["label"])
    left.axvline(A_PUNCH, color="gray", lw=0.8, ls=":")
    left.set_xlabel("r [mm]")
    left.set_ylabel("deflection −u_z of the foundation top [µm]")
    left.set_title("Upper face of the foundation, Q = 4.6 π a² p0", fontsize=10)
    left.grid(True, alpha=0.3)
    left.legend(fontsize=8)
    h = np.array([s["h"] for s in sweep])
    middle.plot(h, [-s["uz"][0] * 1e3 for s in sweep], "o-", label="centre r = 0")
    middle.plot(h, [-s["edge"] * 1e3 for s in sweep], "s-", label="punch edge r = a")
    middle.plot(h, [-s["mean"] * 1e3 for s in sweep], "^-", label="mean under the punch")
    middle.set_xscale("symlog", linthresh=100.0)
    middle.set_xlim(left=0.0)
    middle.set_xlabel("hardening parameter h [MPa] (linear below 100, log above)")
    middle.set_ylabel("deflection [µm]")
    middle.set_title("Deflection against the hardening (paper Fig. 11)", fontsize=10)
    middle.grid(True, which="both", alpha=0.3)
    middle.legend(fontsize=8)
    for s in sweep:
        right.plot(s["path"][:, 1] * 1e3, s["path"][:, 0] * 1.6 * P0 / SIGMA_Y, ".-", ms=3, lw=1,
                   label=f"h = {s['h']:g} MPa")
    for s in locking[1:]:
        right.plot(s["path"][:, 1] * 1e3, s["path"][:, 0] * 1.6 * P0 / SIGMA_Y, "x--", ms=3, lw=1, color="gray",
                   label="h = 0, fully integrated (locks)")
    right.set_xlabel("centre deflection [µm]")
    right.set_ylabel("mean punch pressure p_m / σ_Y")
    right.axhline(5.69 / np.sqrt(3), color="gray", ls="--", lw=0.8)
    right.text(0.98, 5.69 / np.sqrt(3) - 0.03, "Shield, half-space, h = 0: 5.69 k", ha="right", va="top",
               fontsize=8, color="gray", transform=right.get_yaxis_transform())
    right.set_title("Load against centre deflection", fontsize=10)
    right.grid(True, alpha=0.3)
    right.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def zones_plot(path: Path, runs: dict, rows: list[tuple[str, float]]) -> None:
    fig, ax = plt.subplots(figsize=(8, 0.32 * len(rows) + 1.2))
    colours = {0: "lightgray", STICK: "tab:blue", SLIP: "tab:red"}
    for i, (name, factor) in enumerate(rows):
        c = runs[name]["contact"][factor]
        ax.scatter(c["x"] / A_PUNCH, np.full(len(c["x"]), i), c=[colours[int(v)] for v in c["contact_status"]],
                   s=18, marker="s")
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels([f"{runs[n]['short']}, r = {f:g}" for n, f in rows], fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel("r / a")
    ax.set_title("Contact status along the punch face: blue stick, red slip", fontsize=10)
    ax.grid(True, axis="x", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def fields_picture(args: tuple[str, str, int, str]) -> str:
    """von Mises stress and equivalent plastic strain on the deformed shape, r <= 3a and
    H - 3a <= z <= H + a. The colour ranges stop at the 99.5th percentile (the punch corner is singular)."""
    out, target, step, title = args
    title = title.replace("β", "beta")  # not in VTK's font
    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_ERROR)  # no "bad X server" warnings
    grid = read_frame(Path(out) / f"frame_{step:04d}.vtm")["bodies"]
    centres = np.asarray(grid.cell_centers().points)
    near = np.flatnonzero((centres[:, 0] < 3.0 * A_PUNCH) & (centres[:, 1] > H_FOUNDATION - 3.0 * A_PUNCH)
                          & (centres[:, 1] < H_FOUNDATION + A_PUNCH))
    part = grid.extract_cells(near)
    u = np.asarray(part.point_data["displacement"])
    factor = 0.03 * 3.0 * A_PUNCH / np.abs(u).max()
    warped = part.warp_by_vector("displacement", factor=factor)
    surface = warped.extract_surface(nonlinear_subdivision=3, algorithm="dataset_surface")
    # The elastic-plastic boundary (cyan): the contour eps_p = 1e-4 (8 % of the yield strain;
    # a lower level picks up the noise of the nodal extrapolation) of the foundation.
    boundary = warped.extract_cells(np.flatnonzero(np.asarray(warped.cell_data["body"]) == FOUNDATION)) \
        .contour([1e-4], scalars="equivalent_plastic_strain")
    plotter = pv.Plotter(off_screen=True, window_size=(1600, 760), shape=(1, 2), border=False)
    for j, (field, cmap, label) in enumerate((("von_mises", "viridis", "von Mises [MPa]"),
                                              ("equivalent_plastic_strain", "magma", "eq. plastic strain"))):
        values = np.asarray(part.point_data[field])
        top = float(np.percentile(values, 99.5)) or 1.0
        plotter.subplot(0, j)
        plotter.add_mesh(surface.copy(), scalars=field, cmap=cmap, clim=[0.0, top], above_color="white",
                         scalar_bar_args={"title": label, "vertical": True, "fmt": "%.3g", "n_labels": 6,
                                          "position_x": 0.83, "position_y": 0.1, "height": 0.8,
                                          "title_font_size": 16, "label_font_size": 14})
        plotter.add_mesh(warped.extract_feature_edges(), color="gray", opacity=0.5)
        if boundary.n_points:
            plotter.add_mesh(boundary, color="cyan", line_width=2)
        plotter.add_text(f"{title}\nstep {step}, deformation x {factor:.3g}; white: above "
                         f"{top:.3g} (max {values.max():.3g}); cyan: eps_p = 1e-4", font_size=9)
        plotter.view_xy()
        plotter.camera.zoom(1.15)
    plotter.screenshot(target)
    plotter.close()
    return target


# --- main ----------------------------------------------------------------------------------
def binary_identity() -> str:
    """Which solver produced the results: the binary's build time and the source commit."""
    built = time.strftime("%Y-%m-%d %H:%M", time.localtime(BINARY.stat().st_mtime))
    git = lambda *a: subprocess.run(["git", *a], cwd=ROOT, capture_output=True, text=True).stdout.strip()  # noqa: E731
    commit = git("rev-parse", "--short", "HEAD") or "unknown commit"
    dirty = " + uncommitted changes in src/" if git("status", "--porcelain", "--", "src") else ""
    return f"`target/release/asperity` built {built} from {commit}{dirty}"


def dash(v: float) -> str:
    return "–" if np.isnan(v) else f"{v:.3f}"


def verdict(ok: bool) -> str:
    return "**agrees**" if ok else "**differs**"


def solver_row(name: str, summary: dict) -> list:
    """Counters of a run's summary.json and its solver time (the sum of the phases)."""
    t = summary["totals"]
    if summary.get("status") == "failed":
        # A run stopped at its collapse load (issue 17): no final residual, phases partly timed.
        total = sum(v or 0.0 for v in summary["seconds"].values())
        residual = "(stopped)"
    else:
        total = sum(phase_seconds(summary).values())
        residual = rust_exp(summary["final_residual"])
    return [name, summary["model"]["unknowns"], t["increments"], t["cutbacks"], t["iterations"],
            t["unsymmetric_solves"], t["krylov_iterations"], residual, f"{total:.1f}"]


# --- the steps of the pipeline ---------------------------------------------------------------
# (name, load factor) of the rows of the zone table and picture.
ZONE_ROWS = [(n, f) for n in ("model_a", "model_b", "model_c", "coulomb_mu0.2", "adhesion_mu0.2") for f in (1.0, 2.0)]


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "indentation")
    parser.add_argument("--size", type=float, default=None, help="mesh size factor (default 1, --quick 2.5)")
    parser.add_argument("--quick", action="store_true", help="coarse mesh and three hardening values (CI)")
    parser.add_argument("--jobs", type=int, default=None, help="runs at a time (default: all cores)")
    return parser.parse_args()


def solve(runs: dict, jobs: int | None, size: float) -> float:
    """Runs every case in parallel, keeps each run's summary.json; returns the wall time."""
    started = time.perf_counter()
    summaries = run_cases([(r["case"], r["out"]) for r in runs.values()], jobs=jobs, fail_fast=False)
    solve_seconds = time.perf_counter() - started
    print(f"{len(runs)} runs in {solve_seconds:.1f} s (size factor {size})", flush=True)
    for run, summary in zip(runs.values(), summaries):
        run["summary"] = summary
        run["stopped"] = None
        if summary.get("status") == "failed":
            # Only the hardening sweep may stop early (at the collapse load without hardening).
            if run["study"] != "hardening_sweep" or not (run["out"] / "history.csv").is_file():
                sys.exit(f"run failed: {run['case']}: {summary.get('error')}")
            run["stopped"] = str(summary.get("error") or "stopped").strip().splitlines()[0]
    return solve_seconds


def read_and_check(runs: dict) -> None:
    """Reads every run's history and contact tables at the load factors of its study, checks
    the equilibrium, finds the stick/slip zones, and checks the paper's case: the hardening
    model with mu_m = 0.2 at r = 2."""
    for name, run in runs.items():
        run["history"] = history = read_history(run["out"])
        run["equilibrium"] = check_history(name, history)
        run["steps"] = {}
        run["contact"] = {}
        factors = [SWEEP_FACTOR] if run["study"] == "hardening_sweep" else [1.0, 2.0]
        if run["stopped"]:
            factors = [float(history["load_factor"][-1])]
        run["final"] = factors[-1]
        for f in factors:
            run["steps"][f] = step = step_at(history, f, name)
            run["contact"][f] = contact_at(run["out"], step)
        run["zones"] = {f: zones(c) for f, c in run["contact"].items()}
    check_annulus(f"adhesion_mu0.2 ({runs['adhesion_mu0.2']['label']})", 2.0, runs["adhesion_mu0.2"]["zones"][2.0])


def first_yields(runs: dict) -> tuple[float, float]:
    """The load factors of first yield of the foundation for the ideal Coulomb model with
    mu = 0.2 (the paper's r = 1) and with mu = 0.1 (model a); reads both models' contact
    tables at the first."""
    yield_step, yield_factor = first_yield(runs["coulomb_mu0.2"]["out"], runs["coulomb_mu0.2"]["history"])
    if yield_step < 0:
        fail("coulomb_mu0.2: the foundation never yields up to r = 2")
    for name in ("model_a", "coulomb_mu0.2"):
        step = step_at(runs[name]["history"], yield_factor, name)
        runs[name]["contact"][yield_factor] = contact_at(runs[name]["out"], step)
    yield_a = first_yield(runs["model_a"]["out"], runs["model_a"]["history"])[1]
    return yield_factor, yield_a



def hardening_sweep(runs: dict) -> tuple[list[dict], list[dict]]:
    """Fig. 11: per hardening value the foundation's top deflection at the sweep load (centre,
    edge, mean under the punch), the load path of the centre, and the plastic zone; and the
    perfectly plastic case with B-bar and with full integration (issue 17)."""
    sweep, locking = [], []
    for name, run in runs.items():
        if run["study"] != "hardening_sweep":
            continue
        step = run["steps"][run["final"]]
        r, uz = top_deflection(run["out"], step)
        under = r <= A_PUNCH + 1e-9
        edge = float(np.interp(A_PUNCH, r, uz))
        mean = float(np.trapezoid(uz[under] * r[under], r[under]) / np.trapezoid(r[under], r[under]))
        grid = bodies(run["out"], step)
        path = [(0.0, 0.0)] + [(float(f), float(centre_deflection(run["out"], int(k))))
                               for k, f in zip(run["history"]["step"], run["history"]["load_factor"])]
        label = f"h = {run['h']:g} MPa" + (f" (stopped at Q = {run['final'] * 1.6:.3f} π a² p0)" if run["stopped"] else "")
        entry = dict(h=run["h"], r=r, uz=uz, edge=edge, mean=mean, name=name, path=np.array(path), label=label,
                     final=run["final"], stopped=run["stopped"], reached=reached(run),
                     eps=float(np.max(grid.point_data["equivalent_plastic_strain"])),
                     plastic=int(np.asarray(grid.cell_data["plastic"]).sum()))
        (locking if run.get("full") else sweep).append(entry)
        if run["h"] == 0.0 and not run.get("full"):
            locking.insert(0, entry)
    sweep.sort(key=lambda s: s["h"])
    return sweep, locking


def pictures(out: Path, runs: dict, sweep: list[dict], locking: list[dict], yield_factor: float,
             jobs: int | None) -> None:
    """The figures of the paper and the field pictures of every run."""
    tangential_plot(out / "tangential_stress_r1.png", runs, 1.0)
    tangential_plot(out / "tangential_stress_r2.png", runs, 2.0)
    normalised_plot(out / "normalised_contact_stress.png", runs,
                    [(f"first yield in this mesh, r = {yield_factor:g}", yield_factor),
                     ("r = 1 (the paper's initiation of plastic deformation)", 1.0)])
    deflection_plot(out / "deflection_vs_hardening.png", sweep, locking)
    zones_plot(out / "stick_slip_zones.png", runs, ZONE_ROWS)
    fields = [(str(run["out"]), str(out / f"fields_{name}.png"), int(run["history"]["step"][-1]),
               f"{name}: {run['label']}, load factor {run['history']['load_factor'][-1]:g}")
              for name, run in runs.items()]
    with ProcessPoolExecutor(max_workers=min(len(fields), jobs or 8)) as pool:
        list(pool.map(fields_picture, fields))


# --- the report ------------------------------------------------------------------------------
def setup_section(runs: dict, size: float, solve_seconds: float) -> str:
    nodes = runs["model_a"]["zones"][1.0]["nodes"]
    model = runs["model_a"]["summary"]["model"]
    return f"""
Paper §4.3 (Figs. 7–11): an elastic cylindrical punch (2a = 20 mm, h = 20 mm) pressed into an
elasto-plastic foundation (2A = 80 mm, H = 40 mm), axisymmetric, E = 70 000 MPa, ν = 0.33 for
both, foundation J2 with σ_Y = {SIGMA_Y:g} MPa. Mesh `geo/indentation.geo` at size factor {size:g}:
{nodes} interface nodes along 0 ≤ r ≤ a (quadratic elements graded toward the punch corner),
{model['nodes']} nodes, {model['elements']} elements, {model['unknowns']} unknowns. Foundation
bottom u_z = 0, outer surface free, punch held by the contact only.

Load: uniform pressure 1.6 r p0 on the punch top, p0 = 20π MPa (misprint 6 in `docs/theory.md`,
"Known misprints in the paper"); load factor
= r, steps of 0.1 up to r = 2 (Fig. 11: steps of 0.125 up to 4.6/1.6 = 2.875, i.e. Q = 4.6 π a² p0).
Interface: `rough_joint`, c_n = 1e-7 (paper 0.0001 × 1e-3), m = 0.5, S = 0.5, R = 5e-5 (paper
0.05 × 1e-3) unless stated, n = 275 1/mm (not given in §4.3; taken from §4.1/4.2, it only
matters for β < 1). Side A the punch face, side B the foundation. Sign of p_T: p_T > 0 where
the punch moves outward relative to the foundation, i.e. friction drags the foundation
outward (+r) and the punch inward; p_N < 0 in compression.

Runs ({len(runs)}, in parallel on {os.cpu_count()} cores, {solve_seconds:.1f} s wall time; {binary_identity()}):
""" + table(["run", "study file", "what"], [[n, f"indentation/{r['study']}.toml", r["label"]] for n, r in runs.items()])


def equilibrium_section(runs: dict) -> str:
    return ("Largest relative error over all steps of the vertical interface resultant −∫p_N dA, of "
            "the force on the foundation (`interface_force_on_b_y`) and of the foundation's support "
            f"reaction against the applied load Q = p π a² (check: ≤ {EQUILIBRIUM_TOL:g}).\n\n" + table(
                ["run", "interface ∫p_N dA", "force on foundation", "support reaction"],
                [[n, r["equilibrium"]["normal"], r["equilibrium"]["on_b"], r["equilibrium"]["support"]]
                 for n, r in runs.items()]))


def zones_section(runs: dict) -> str:
    nodes = runs["model_a"]["zones"][1.0]["nodes"]
    zone_table = table(
        ["run", "r", "stick", "slip", "inner stick zone to r/a", "first slip at r/a", "slip in r ≥ 0.9a",
         "corner", "status from the axis (= stick, ~ slip)"],
        [[runs[n]["label"], f, z["stick"], z["slip"], dash(z["inner_stick_to"]), dash(z["first_slip"]), z["outer_slip"],
          z["corner"], f"`{z['status']}`"] for n, f in ZONE_ROWS for z in [runs[n]["zones"][f]]])

    z = {(n, f): runs[n]["zones"][f] for n, f in ZONE_ROWS}
    all_slide_r1 = all(z[(n, 1.0)]["off_axis_stick"] == 0 for n in ("model_c", "adhesion_mu0.2"))
    all_slide_r2 = z[("model_c", 2.0)]["off_axis_stick"] == 0
    ann, ann_c = z[("adhesion_mu0.2", 2.0)], z[("coulomb_mu0.2", 2.0)]
    ext = [(f, z[("model_c", f)]["slip"], z[("model_b", f)]["slip"]) for f in (1.0, 2.0)]
    return f"""
Status of every node of the contact (r = 0 … a, {nodes} nodes; `contact_status` of the step,
1 stick, 2 slip) at r = 1 and r = 2. The node on the axis has u_T = 0 by symmetry, so "all
nodes slide" is read as "all nodes off the axis slide". The paper's mesh is coarser (it
counts three sliding nodes), so zone sizes are compared as fractions of a. Stick/slip is the
state of the load step, so a node whose slip reverses or stops in the step sticks.

{zone_table}

![zones](stick_slip_zones.png)

Paper statements (the hardening models of the adhesion study unless named):
1. "In the case of lower loading all the contact nodes are in the sliding state, for both
   μm = 0.1 and μm = 0.2" (r = 1): {verdict(all_slide_r1)} — stick nodes off the axis:
   μm = 0.1: {z[('model_c', 1.0)]['off_axis_stick']}, μm = 0.2: {z[('adhesion_mu0.2', 1.0)]['off_axis_stick']}.
2. "The same for μm = 0.1" at r = 2: {verdict(all_slide_r2)} — {z[('model_c', 2.0)]['off_axis_stick']} of
   {nodes - 1} nodes off the axis stick (status `{z[('model_c', 2.0)]['status']}`).
3. "μm = 0.2, r = 2: an inner adhesive region and an outer annulus of slip, three outer nodes
   sliding": {verdict(not annulus_problems(ann))} for the inner stick zone and outer slip annulus
   (the CI check: stick from the axis to r/a = {ann['inner_stick_to']:.3f}, {ann['outer_slip']} slipping
   node(s) in r ≥ 0.9a, first slip at r/a = {ann['first_slip']:.3f}, corner node: {ann['corner']});
   the paper's annulus is three nodes wide, ours {ann['slip']} node(s) of {nodes}. The ideal Coulomb model with
   μm = 0.2 at r = 2: {ann_c['stick']} stick, {ann_c['slip']} slip, status `{ann_c['status']}` (not checked: the
   paper's statement is about the hardening model).
4. "The hardening model extends the slip zone more than the regularised Coulomb model" (and
   conclusion 4: the adhesion radius of the regularised model is greater): {verdict(all(c > b for _, c, b in ext))}
   — slip nodes (c) hardening vs (b) regularised: """ + ", ".join(f"r = {f:g}: {c} vs {b}" for f, c, b in ext) + \
        f"""; stick zone around the axis at r = 1: (c) to r/a = {dash(z[('model_c', 1.0)]['inner_stick_to'])},
   (b) to r/a = {dash(z[('model_b', 1.0)]['inner_stick_to'])}.
"""


def tangential_section(runs: dict) -> str:
    def pt_row(n: str, f: float) -> list:
        c = runs[n]["contact"][f]
        k = step_at(runs[n]["history"], f, n) - 1
        return [runs[n]["label"], f, float(c["contact_shear_stress"].max()), float(c["contact_shear_stress"].min()),
                float(c["contact_shear_stress"][-1]), float(c["contact_normal_stress"][-1]),
                float(runs[n]["history"][f"{PAIR}_tangential_force"][k])]
    return """
Figs. 8–9: `tangential_stress_r1.png`, `tangential_stress_r2.png`. The paper finds the
tangential stresses insensitive to the slip model and decreasing, with a change of sign, as
the load grows.

""" + table(["model", "r", "max p_T [MPa]", "min p_T [MPa]", "p_T at r = a", "p_N at r = a", "∫p_T dA [N]"],
            [pt_row(n, f) for n in ("model_a", "model_b", "model_c") for f in (1.0, 2.0)])


def first_yield_section(yield_factor: float, yield_a: float) -> str:
    return f"""
The foundation first yields (a `plastic` cell) at load factor r = {yield_factor:g} for the ideal
Coulomb model with μm = 0.2 and at r = {yield_a:g} with μm = 0.1 (steps of 0.1; the paper's r = 1
is its first yield with μm = 0.2 in its coarser mesh — the corner singularity makes this
load mesh-dependent). `normalised_contact_stress.png` shows both loads.
"""


def deflection_section(sweep: list[dict]) -> str:
    sweep_table = table(["h [MPa]", "Q / (π a² p0)", "centre deflection [µm]", "edge deflection [µm]",
                         "mean under punch [µm]", "max ε̄ᵖ", "plastic cells"],
                        [[f"{s['h']:g}", s["final"] * 1.6, -s["uz"][0] * 1e3, -s["edge"] * 1e3, -s["mean"] * 1e3,
                          s["eps"], s["plastic"]] for s in sweep])
    stopped = [s for s in sweep if s["stopped"]]
    k_units = TOP_PRESSURE / (SIGMA_Y / np.sqrt(3))
    stopped_text = "".join(
        f"\n\nh = {s['h']:g} MPa did not reach the final load: its last completed step is Q = {s['final'] * 1.6:.3f} π a² p0 "
        f"(its row and curves are at that load), and the cut-backs of the next step converged up to "
        f"Q = {s['reached'] * 1.6:.3f} π a² p0 = {s['reached'] * TOP_PRESSURE:.1f} MPa = {s['reached'] * k_units:.2f} k, "
        f"no further (solver: \"{s['stopped'].removeprefix('error: ').removesuffix(' Attempts:')}\"). "
        "The load–deflection curve flattens steeply towards that load: the foundation is at or very near its "
        "collapse load (README, issue 17)."
        for s in stopped)
    return f"""
Deflection −u_z of the foundation's upper face (foundation nodes at z = H) at Q = 4.6 π a² p0
(top pressure {SWEEP_FACTOR * TOP_PRESSURE:.1f} MPa = {SWEEP_FACTOR * TOP_PRESSURE / SIGMA_Y:.2f} σ_Y), ideal
Coulomb μm = 0.2 (the paper does not name the interface law of Fig. 11; our choice), for
h ∈ {{{', '.join(f'{s["h"]:g}' for s in sweep)}}} MPa. The load is
{SWEEP_FACTOR * TOP_PRESSURE / (SIGMA_Y / np.sqrt(3)):.2f} k (k = σ_Y/√3), just below the collapse load of a
perfectly plastic half-space under a flat punch (Shield: 5.69 k), so without hardening the deflection grows steeply over the last steps
(right panel of `deflection_vs_hardening.png`). The model is geometrically linear (small
strains), which the largest plastic strains below exceed.{stopped_text}

{sweep_table}
"""


def locking_section(locking: list[dict]) -> str:
    if len(locking) < 2:
        return "(no comparison run)"
    k_units = TOP_PRESSURE / (SIGMA_Y / np.sqrt(3))
    common = min(s["final"] for s in locking)
    b, f = locking[0], locking[1]
    loads = [x for x in (2.0, 2.5) if x < common - 1e-9] + [common]

    def centre_at(x: dict, factor: float) -> float:
        return float(x["path"][np.flatnonzero(np.abs(x["path"][:, 0] - factor) < 1e-9)[0], 1])
    return f"""
Issue 17: fully integrated 8-node elements lock under isochoric plastic flow (plane strain,
axisymmetry) and overestimate collapse loads; the foundation of every run above uses the
default locking-free B-bar element (README, `[[body]] formulation`). The perfectly plastic case
h = 0 repeated with `formulation = "full"`, centre deflection of the foundation top [µm]:

""" + table(["element", "largest Q converged / (π a² p0)", "last completed step"]
            + [f"at Q = {x * 1.6:.3f} π a² p0" for x in loads] + ["at the last step", "max ε̄ᵖ there"],
            [["B-bar (default)" if i == 0 else "full integration", f"{x['reached'] * 1.6:.3f}", x["final"] * 1.6]
             + [centre_at(x, q) * 1e3 for q in loads] + [-x["uz"][0] * 1e3, x["eps"]]
             for i, x in enumerate((b, f))]) + f"""

The locking element is stiffer: at Q = {loads[0] * 1.6:.3f}, {loads[-1] * 1.6:.3f} π a² p0 the B-bar deflection is
{100 * (centre_at(b, loads[0]) / centre_at(f, loads[0]) - 1):+.1f} %, {100 * (centre_at(b, loads[-1]) / centre_at(f, loads[-1]) - 1):+.1f} % larger.
""" + ("Both reach the final load." if not (b["stopped"] or f["stopped"]) else
       f"With B-bar, load control fails at Q ≈ {b['reached'] * 1.6:.3f} π a² p0 ({b['reached'] * k_units:.2f} k), just "
       f"below the final load, at or very near the collapse load; the fully integrated element carries {f['reached'] * 1.6:.3f} π a² p0 with a centre deflection of "
       f"{-f['uz'][0] * 1e3:.0f} µm." if b["stopped"] else
       "Only the B-bar run reaches the final load.")


def statistics_section(runs: dict) -> str:
    return table(["run", "unknowns", "increments", "cut-backs", "Newton it.", "unsym. solves", "BiCGSTAB it.",
                  "final residual", "solver time [s]"],
                 [solver_row(n, r["summary"]) for n, r in runs.items()])


FILES = """
`tangential_stress_r1.png`, `tangential_stress_r2.png` (Figs. 8–9), `normalised_contact_stress.png`
(Fig. 10), `deflection_vs_hardening.png` (Fig. 11), `stick_slip_zones.png`, `fields_<run>.png`
(von Mises and ε̄ᵖ on the deformed shape near the punch, last step); per run `<run>/results.pvd`
(ParaView), `<run>/contact_interface_NNNN.csv`, `<run>/history.csv`, `<run>/summary.json`; the
case files actually run in `cases/`.
"""


def report(out: Path, runs: dict, sweep: list[dict], locking: list[dict], size: float, solve_seconds: float,
           yields: tuple[float, float]) -> None:
    write_report(out / "REPORT.md", "Indentation of an elastic punch into an elasto-plastic foundation (paper §4.3)",
                 [("Set-up", setup_section(runs, size, solve_seconds)), ("Vertical equilibrium", equilibrium_section(runs)),
                  ("Stick and slip zones against the paper", zones_section(runs)),
                  ("Tangential contact stress (Figs. 8–9)", tangential_section(runs)),
                  ("First yield", first_yield_section(*yields)),
                  ("Deflection against hardening (Fig. 11)", deflection_section(sweep)),
                  ("Locking-free element against full integration (h = 0)", locking_section(locking)),
                  ("Solver statistics (from each run's summary.json)", statistics_section(runs)), ("Files", FILES)])


def main() -> None:
    args = parse_args()
    out = args.out.resolve()
    size = args.size if args.size is not None else (2.5 if args.quick else 1.0)
    out.mkdir(parents=True, exist_ok=True)
    runs = plan(out, size, args.quick)
    solve_seconds = solve(runs, args.jobs, size)
    read_and_check(runs)
    yields = first_yields(runs)
    sweep, locking = hardening_sweep(runs)
    pictures(out, runs, sweep, locking, yields[0], args.jobs)
    report(out, runs, sweep, locking, size, solve_seconds, yields)
    print(f"results: {out} (REPORT.md, *.png; <run>/results.pvd for ParaView)")


if __name__ == "__main__":
    main()
