#!/usr/bin/env python3
"""Plane elastic punch on an elastic foundation: example 4.1 of Buczkowski & Kleiber (1994).

Usage: plane_punch.py [--out out/plane_punch] [--size S] [--quick]

Runs pipelines/plane_punch/coulomb.toml (ideal Coulomb friction) and hardening.toml
(slip-hardening friction, paper Eq. 4) in parallel at mesh size factor S (default 1; --quick:
3, a coarse mesh for CI: about a second of solving), then writes into the out folder:
  plastic_slip.png      plastic slip along the interface for both models (paper Fig. 3)
                        and the mobilised friction |p_T|/p against mu_F
  friction_vs_slip.png  mu_F against plastic slip, Eq. (4) for (mu_m, beta) = (0.1, 0.1),
                        (0.2, 0.2), (0.3, 0.3) (paper Fig. 4), with the points of both runs
  contact_stresses.png  contact pressure and shear stress along the interface
  von_mises.png         von Mises stress on the deformed shape near the punch (pyvista)
  REPORT.md             parameters, maximum slips against the paper's 10.8 um and
                        Fredriksson's 10.4 um, equilibrium, solver statistics, figures
and, per run, <model>/ (results.pvd, CSVs, and plot_fields.py's von_mises.png,
reactions.png, contact_contact.png).

Exits non-zero (CI check) when an expected array or column is missing, the vertical
equilibrium of the interface (normal resultant against p0 * a * thickness of the half model)
is violated by more than 5e-4 relative (the solver's residual tolerance R_n) at any step, the friction coefficient of the
slip-hardening run leaves Eq. (4), or the slip-hardening model does not slip more than ideal
Coulomb (the paper's statement).
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pyvista as pv  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from asperity_tools import (  # noqa: E402
    ROOT, phase_seconds, read_contact, read_history, read_step, run_cases, rust_exp, table, variant, write_report,
)

pv.OFF_SCREEN = True

CASES = ROOT / "pipelines" / "plane_punch"
MODELS = {"coulomb": "ideal Coulomb (β = 1)", "hardening": "slip hardening (β = 0.2, n = 275/mm)"}
PAIR = "contact"
PAPER_SLIP_UM = 10.8        # paper, Fig. 3 caption: u_T,max^p = 10.8 um
FREDRIKSSON_SLIP_UM = 10.4  # paper §4.1: "u_T,max^p as given by Fredriksson ... 10.4 um"
FIG4_SETS = [(0.1, 0.1), (0.2, 0.2), (0.3, 0.3)]  # (mu_m, beta) of Fig. 4
# Every residual component is at most R_n times the average nodal force (the default criterion,
# [solver] residual_tolerance = 5e-4), so a resultant is out of balance by about R_n at most.
EQUILIBRIUM_TOLERANCE = 5e-4
EQ4_TOLERANCE = 1e-9
CONTACT_COLUMNS = ["x", "contact_pressure", "contact_shear_stress", "normal_gap", "tangential_slip",
                   "plastic_slip", "signed_plastic_slip", "friction_coefficient", "contact_status"]
HISTORY_COLUMNS = ["step", "load_factor", "increments", "iterations", "reaction_foundation_bottom_y",
                   f"{PAIR}_normal_force", f"{PAIR}_tangential_force", f"{PAIR}_force_on_b_y"]
QUICK_SIZE = 3.0


def fail(message: str) -> None:
    sys.exit(f"plane_punch.py: {message}")


def require(columns: dict, names: list[str], where: str) -> None:
    missing = [n for n in names if n not in columns]
    if missing:
        fail(f"{where}: missing column(s) {', '.join(missing)} (have {', '.join(columns)})")


def mu_f(slip: np.ndarray, mu_m: float, beta: float, n: float) -> np.ndarray:
    """Paper Eq. (4): mu_F = mu_m [1 - (1 - beta) exp(-n u)]."""
    return mu_m * (1.0 - (1.0 - beta) * np.exp(-n * slip))


def case_parameters(case: Path) -> dict:
    """Load, geometry and interface parameters read from a case file."""
    spec = tomllib.loads(case.read_text())
    (load,) = [l for l in spec["load"] if l["group"] == "punch_top"]
    (contact,) = spec["contact"]
    return {
        "p0": load["pressure"], "thickness": spec["analysis"]["thickness"],
        "type": spec["analysis"]["type"], "geometry": spec["mesh"]["parameters"],
        "law": contact["law"], "steps": spec["steps"]["count"],
        "material": spec["body"][0]["material"],
    }


def slip_figure(path: Path, results: dict, a: float) -> None:
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7.5, 8), sharex=True)
    colors = {"coulomb": "tab:blue", "hardening": "tab:red"}
    for name, r in results.items():
        for step, c in r["steps"].items():
            last = step == max(r["steps"])
            top.plot(c["x"], 1e3 * c["plastic_slip"], "-", color=colors[name], lw=2 if last else 0.7,
                     alpha=1 if last else 0.35, marker="o" if last else None, ms=3,
                     label=f"{MODELS[name]}, max {1e3 * c['plastic_slip'].max():.2f} µm" if last else None)
        c = r["contact"]
        top.plot(c["x"], 1e3 * c["signed_plastic_slip"], "x", color=colors[name], ms=4)
        p = c["contact_pressure"]
        ok = p > 0
        bottom.plot(c["x"][ok], np.abs(c["contact_shear_stress"][ok]) / p[ok], "o", ms=3, color=colors[name],
                    label=f"|p_T| / p, {name}")
        bottom.plot(c["x"], c["friction_coefficient"], "-", color=colors[name], lw=1, label=f"μ_F, {name}")
    for value, text, va in [(PAPER_SLIP_UM, "paper, Fig. 3", "bottom"), (FREDRIKSSON_SLIP_UM, "Fredriksson", "top")]:
        top.axhline(value, color="gray", ls="--", lw=0.8)
        top.text(0.02 * a, value, f"{text}: {value} µm", va=va, fontsize=8, color="gray")
    top.set_ylabel("accumulated plastic slip ū [µm]")
    top.set_title("Plastic slip along the punch face (thin: increments 1-9; x: signed slip $u_T^p$)", fontsize=10)
    top.legend(fontsize=8, loc="upper left", bbox_to_anchor=(0, 0.85))
    bottom.set_ylabel("mobilised friction")
    bottom.set_xlabel("x [mm] (punch corner at x = a)")
    bottom.set_ylim(bottom=0)
    bottom.legend(fontsize=8, ncol=2)
    for ax in (top, bottom):
        ax.axvline(a, color="k", lw=0.5)
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def friction_figure(path: Path, results: dict, n: float) -> None:
    top = max(20.0, 1.2e3 * max(r["contact"]["plastic_slip"].max() for r in results.values()))
    u = np.linspace(0.0, top, 400)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for (mu_m, beta), ms in zip(FIG4_SETS, [3, 5, 7]):
        ax.plot(u, mu_f(u * 1e-3, mu_m, beta, n), "k-", lw=0.8)
        marks = u[::25]
        ax.plot(marks, mu_f(marks * 1e-3, mu_m, beta, n), "ks", ms=ms, mfc="white",
                label=f"Eq. (4): μ_m = {mu_m}, β = {beta}, n = {n:g}/mm")
    for name, color, marker in [("hardening", "tab:red", "o"), ("coulomb", "tab:blue", "x")]:
        r = results[name]
        slips = np.concatenate([c["plastic_slip"] for c in r["steps"].values()])
        mus = np.concatenate([c["friction_coefficient"] for c in r["steps"].values()])
        ax.plot(1e3 * slips, mus, marker, color=color, ms=4, alpha=0.6, label=f"run: {MODELS[name]}, all increments")
    ax.set_xlabel("accumulated plastic slip ū [µm]")
    ax.set_ylabel("friction coefficient μ_F")
    ax.set_title("Friction coefficient against plastic slip (paper Fig. 4)", fontsize=10)
    ax.set_ylim(0, 0.32)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def contact_figure(path: Path, results: dict, p0: float, a: float) -> None:
    fig, ax = plt.subplots(figsize=(7, 4.5))
    colors = {"coulomb": "tab:blue", "hardening": "tab:red"}
    for name, r in results.items():
        c = r["contact"]
        ax.plot(c["x"], c["contact_pressure"], "o-", ms=3, color=colors[name], label=f"pressure −p_N, {name}")
        ax.plot(c["x"], c["contact_shear_stress"], "s--", ms=3, color=colors[name], label=f"shear p_T, {name}")
    ax.axhline(p0, color="gray", ls=":", lw=1)
    ax.text(0.02 * a, p0, f"p0 = {p0} MPa", va="bottom", fontsize=8, color="gray")
    ax.set_ylim(-0.1 * p0, 4 * p0)
    ax.set_xlabel("x [mm] (punch corner at x = a; the corner value is singular, off the scale)")
    ax.set_ylabel("contact stress [MPa]")
    ax.set_title("Contact stresses along the interface, last increment", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def von_mises_figure(path: Path, out: Path, geometry: dict, p0: float) -> None:
    a, h = geometry["a"], geometry["h"]
    plotter = pv.Plotter(off_screen=True, shape=(1, 2), window_size=(1600, 800), border=False)
    for column, name in enumerate(MODELS):
        grid = read_step(out / name)["bodies"]
        for array in ("displacement", "von_mises"):
            if array not in grid.point_data:
                fail(f"{out / name}: point array '{array}' missing in the last bodies VTU")
        u = np.asarray(grid.point_data["displacement"])
        factor = 0.05 * a / np.abs(u).max()
        warped = grid.warp_by_vector("displacement", factor=factor)
        plotter.subplot(0, column)
        plotter.add_mesh(warped.extract_surface(nonlinear_subdivision=3, algorithm="dataset_surface"),
                         scalars="von_mises", cmap="viridis", clim=(0.0, 2.5 * p0), copy_mesh=True,
                         scalar_bar_args={"title": "von Mises stress [MPa]", "position_x": 0.25, "width": 0.5,
                                          "position_y": 0.04})
        plotter.add_mesh(grid.extract_feature_edges(), color="gray", opacity=0.5)
        plotter.add_text(f"{name}: von Mises on the deformed shape (x {factor:.3g}), last increment;"
                         f" colour scale cut at 2.5 p0", font_size=9)
        plotter.view_xy()
        plotter.enable_parallel_projection()
        cx, cy = 1.1 * a, 0.5 * (h - 1.3 * a)
        plotter.camera.focal_point = (cx, cy, 0.0)
        plotter.camera.position = (cx, cy, 10 * a)
        plotter.camera.parallel_scale = 0.55 * (h + 1.3 * a)
    plotter.screenshot(path)
    plotter.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("out/plane_punch"))
    parser.add_argument("--size", type=float, default=None, help="mesh size factor (default 1, --quick 3)")
    parser.add_argument("--quick", action="store_true", help=f"coarse mesh (size {QUICK_SIZE}) for CI")
    args = parser.parse_args()
    size = args.size if args.size is not None else (QUICK_SIZE if args.quick else 1.0)
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)

    params = {name: case_parameters(CASES / f"{name}.toml") for name in MODELS}
    ref = params["coulomb"]
    p0, t, geometry = ref["p0"], ref["thickness"], ref["geometry"]
    a = geometry["a"]
    for name, p in params.items():
        if (p["p0"], p["thickness"], p["geometry"]) != (p0, t, geometry):
            fail(f"{name}.toml: load, thickness or geometry differ from coulomb.toml")

    cases = [variant(CASES / f"{name}.toml", out / "cases" / f"{name}.toml", size=size) for name in MODELS]
    print(f"running {', '.join(MODELS)} at mesh size {size} ...", flush=True)
    started = time.perf_counter()
    summaries = dict(zip(MODELS, run_cases([(case, out / name) for case, name in zip(cases, MODELS)])))
    wall = time.perf_counter() - started

    results = {}
    for name in MODELS:
        history = read_history(out / name)
        require(history, HISTORY_COLUMNS, f"{out / name}/history.csv")
        steps = [int(s) for s in history["step"]]
        contacts = {}
        for step in steps:
            try:
                contacts[step] = read_contact(out / name, PAIR, step)
            except FileNotFoundError as error:
                fail(f"{out / name}: contact table of step {step} missing ({error})")
            require(contacts[step], CONTACT_COLUMNS, f"{out / name}/contact_{PAIR}_{step:04d}.csv")
        results[name] = {"history": history, "steps": contacts, "contact": contacts[steps[-1]],
                         "summary": summaries[name]}
        done = subprocess.run([sys.executable, str(ROOT / "pipelines" / "plot_fields.py"), str(out / name)],
                              capture_output=True, text=True)
        if done.returncode != 0:
            fail(f"plot_fields.py {out / name} failed: {done.stderr.strip()}")

    failures = []

    # Maximum plastic slip, slip zone, interface elasticity.
    slip_rows, elastic_rows = [], []
    for name, r in results.items():
        c = r["contact"]
        i = int(np.argmax(c["plastic_slip"]))
        r["max_slip_um"] = 1e3 * c["plastic_slip"][i]
        slipping = c["x"][c["plastic_slip"] > 0]
        stick_end = slipping.min() if len(slipping) else a
        slip_rows.append([MODELS[name], r["max_slip_um"], float(c["x"][i]), f"{stick_end:.3g}–{a:g}",
                          float(c["friction_coefficient"][i]), r["max_slip_um"] / PAPER_SLIP_UM,
                          r["max_slip_um"] / FREDRIKSSON_SLIP_UM])
        elastic_t = np.abs(c["tangential_slip"] - c["signed_plastic_slip"]).max()
        closure = np.max(-c["normal_gap"])
        elastic_rows.append([MODELS[name], 1e3 * elastic_t, 1e3 * closure,
                             f"{100 * elastic_t / c['plastic_slip'].max():.2g} %"])
    harder = results["hardening"]["max_slip_um"] > results["coulomb"]["max_slip_um"]
    if not harder:
        failures.append("the slip-hardening model does not slip more than ideal Coulomb")

    # Friction coefficient of the runs against Eq. (4).
    eq4 = {}
    for name, r in results.items():
        law = params[name]["law"]
        dev = 0.0
        for c in r["steps"].values():
            expected = mu_f(c["plastic_slip"], law["mu_m"], law.get("beta", 1.0), law.get("n", 0.0))
            dev = max(dev, float(np.abs(c["friction_coefficient"] - expected).max()))
        eq4[name] = dev
        if not dev <= EQ4_TOLERANCE:
            failures.append(f"{name}: friction_coefficient leaves Eq. (4) by {dev:.3g}")

    # Vertical equilibrium at every increment: half model, load p0 * a * t.
    eq_rows = []
    for name, r in results.items():
        h = r["history"]
        load = p0 * a * t * h["load_factor"]
        errors = {
            "normal": np.abs(h[f"{PAIR}_normal_force"] + load) / load,
            "on_b": np.abs(h[f"{PAIR}_force_on_b_y"] - load) / load,
            "bottom": np.abs(h["reaction_foundation_bottom_y"] - load) / load,
        }
        worst = max(float(e.max()) for e in errors.values())
        eq_rows.append([MODELS[name], float(load[-1]), float(h[f"{PAIR}_normal_force"][-1]),
                        float(errors["normal"].max()), float(errors["on_b"].max()), float(errors["bottom"].max())])
        if not worst <= EQUILIBRIUM_TOLERANCE:
            failures.append(f"{name}: vertical equilibrium violated by {worst:.3g} (relative) > {EQUILIBRIUM_TOLERANCE}")

    # Figures.
    figures = {
        "plastic_slip.png": lambda p: slip_figure(p, results, a),
        "friction_vs_slip.png": lambda p: friction_figure(p, results, params["hardening"]["law"]["n"]),
        "contact_stresses.png": lambda p: contact_figure(p, results, p0, a),
        "von_mises.png": lambda p: von_mises_figure(p, out, geometry, p0),
    }
    for file, make in figures.items():
        make(out / file)

    # Solver statistics.
    stat_rows = []
    for name, r in results.items():
        h, s = r["history"], r["summary"]
        times, totals = phase_seconds(s), s["totals"]
        stat_rows.append([MODELS[name], s["model"]["elements"], s["model"]["unknowns"], len(h["step"]),
                          int(h["increments"].sum()), totals["cutbacks"], int(h["iterations"].sum()),
                          totals["unsymmetric_solves"], totals["krylov_iterations"],
                          float(rust_exp(s["final_residual"])), times["assembly"], times["solve"],
                          float(sum(times.values()))])

    g = geometry
    worst_equilibrium = max(max(row[3:]) for row in eq_rows)
    law_c, law_h = params["coulomb"]["law"], params["hardening"]["law"]
    material = ref["material"]
    c_slip, h_slip = results["coulomb"]["max_slip_um"], results["hardening"]["max_slip_um"]
    a_match = a * FREDRIKSSON_SLIP_UM / c_slip
    model_table = table(["quantity", "value"], [
    ["punch width 2a × height h", f"{2 * g['a']:g} × {g['h']:g} mm"],
    ["foundation width 2W × depth D", f"{2 * g['W']:g} × {g['D']:g} mm (bottom: u_y = 0)"],
    ["model", "half (x ≥ 0), u_x = 0 on the symmetry line"],
    ["analysis", f"{ref['type'].replace('_', ' ')}, thickness {t:g} mm (the paper's “plane stress” problem, §1)"],
    ["E, ν (both bodies)", f"{material['E']:g} MPa, {material['nu']:g}"],
    ["load", f"p0 = {p0:g} MPa on the punch top in {ref['steps']} equal increments"],
    ["interface", f"rough_joint, c_n = {law_c['c_n']:g} mm/MPa^m, m = {law_c['m']:g}, R = {law_c['R']:g}, S = {law_c['S']:g} (paper c_N = 0.0001, R = 0.05 in µm units)"],
    ["ideal Coulomb", f"μ_m = {law_c['mu_m']:g}, β = {law_c['beta']:g}"],
    ["slip hardening", f"μ_m = {law_h['mu_m']:g}, β = {law_h['beta']:g}, n = {law_h['n']:g} 1/mm"],
    ["mesh", f"size factor {size:g}: {g['n_contact']:g}/{size:g} → {int(np.ceil(g['n_contact'] / size))} quadratic interface elements along the half face, corner element {g['grading']:g} × the centre one"],
])
    sections = [
        ("Result", f"""
Maximum plastic slip at the punch corner: **{c_slip:.2f} µm** with ideal Coulomb friction and
**{h_slip:.2f} µm** with slip-hardening friction (paper, Fig. 3: {PAPER_SLIP_UM} µm; Fredriksson:
{FREDRIKSSON_SLIP_UM} µm). The slip-hardening model slips {'more' if harder else '**not** more'}
than ideal Coulomb ({h_slip / c_slip:.2f} ×), {'as' if harder else 'contrary to what'} the paper
states. Vertical equilibrium holds to {worst_equilibrium:.1e} relative or better.
Checks: {'all passed' if not failures else '**FAILED**: ' + '; '.join(failures)}.
"""),
        ("Model", f"""
Example 4.1 of Buczkowski & Kleiber (1994), plane elastic punch on an elastic foundation.
The paper does not give its geometry (it is Fredriksson's, 1976; `docs/theory.md`,
"The paper's examples: data and choices"), so it was chosen (parameters of
`geo/plane_punch.geo`, set in the cases `pipelines/plane_punch/*.toml`):

{model_table}
"""),
        ("Maximum plastic slip", f"""
{table(["model", "max ū [µm]", "at x [mm]", "slip zone x [mm]", "μ_F there", "/ paper 10.8 µm", "/ Fredriksson 10.4 µm"], slip_rows)}

The paper reports u_T,max^p = {PAPER_SLIP_UM} µm (Fig. 3 caption; most likely the larger,
slip-hardening curve) and Fredriksson's {FREDRIKSSON_SLIP_UM} µm (the text does not say for which
friction model). Here the ideal-Coulomb slip is {c_slip / FREDRIKSSON_SLIP_UM:.0%} of Fredriksson's value
and the slip-hardening slip {h_slip / PAPER_SLIP_UM:.0%} of the paper's: the same order of magnitude
and the same ranking, but not the same numbers, and they cannot be expected to be: the
geometry of the example (punch and foundation dimensions, supports, mesh) is not in the
paper and was chosen here. With elastic bodies and a practically rigid, perfectly plastic
Coulomb interface the problem has no length scale of its own, so the ideal-Coulomb slip
grows in proportion to the size of the model: by that scaling, a punch half-width of about
{a_match:.0f} mm (same proportions) would give Fredriksson's {FREDRIKSSON_SLIP_UM} µm. The slip-hardening law has a length
scale, 1/n = {1e3 / law_h['n']:.1f} µm, so its slip grows less than proportionally. The maximum
is at the punch corner x = a in both models; the slip zone of the hardening model, whose
friction starts at β μ_m = {law_h['beta'] * law_h['mu_m']:g}, covers almost the whole face.

Slip-hardening slip larger than ideal Coulomb (paper: "the slip is greater for the slip
hardening model than it is for the ideal Coulomb model"): **{'yes' if harder else 'NO'}**
({h_slip:.2f} µm against {c_slip:.2f} µm).

Interface elasticity (should be negligible against the slip, the interface being practically
rigid):

{table(["model", "max elastic tangential slip, abs(u_T − u_T^p) [µm]", "max normal closure [µm]", "elastic / max plastic slip"], elastic_rows)}

Friction coefficient of the runs against Eq. (4) at every node and increment: largest
deviation {eq4['hardening']:.1e} (slip hardening), {eq4['coulomb']:.1e} (ideal Coulomb).
"""),
        ("Vertical equilibrium", f"""
The half model carries p0 · a · t = {p0 * a * t:g} N (the whole punch {2 * p0 * a * t:g} N). Largest relative
errors over all increments of the interface normal resultant ∫p_N dA (against −p0 a t λ), the
vertical force the foundation exerts on the punch, and the bottom reaction (tolerance
{EQUILIBRIUM_TOLERANCE:g}):

{table(["model", "load [N]", "∫p_N dA [N]", "normal resultant", "force on punch", "bottom reaction"], eq_rows)}
"""),
        ("Solver statistics", f"""
{table(["model", "elements", "unknowns", "steps", "increments", "cut-backs", "Newton iterations", "unsymmetric solves", "BiCGSTAB iterations", "final residual", "assembly [s]", "solve [s]", "total [s]"], stat_rows)}

Both runs together (in parallel): {wall:.1f} s wall time. Per-run summaries:
`coulomb/summary.json`, `hardening/summary.json`.
"""),
        ("Solver notes", """
- Most of the run time is spent in BiCGSTAB on the unsymmetric tangent (about 25-35
  iterations per solve, see the table): its preconditioner keeps the elastic k_T at slipping
  points, where the consistent tangent has no (β = 1) or little tangential stiffness, and
  most of the face slips.
"""),
        ("Figures", """
![plastic slip](plastic_slip.png)

`plastic_slip.png`: accumulated plastic slip ū along the punch face, every increment (paper
Fig. 3), and the mobilised friction |p_T|/p against μ_F (equal where the face slips).

![friction against slip](friction_vs_slip.png)

`friction_vs_slip.png`: μ_F against ū from Eq. (4) for the three sets of Fig. 4, with the
(ū, μ_F) of every interface node and increment of both runs.

![contact stresses](contact_stresses.png)

`contact_stresses.png`: contact pressure and shear stress along the interface.

![von Mises](von_mises.png)

`von_mises.png`: von Mises stress on the deformed shape near the punch (last increment).
Per run: `coulomb/` and `hardening/` hold `results.pvd` (ParaView), the CSV tables and
plot_fields.py's `von_mises.png`, `reactions.png`, `contact_contact.png`.
"""),
    ]
    write_report(out / "REPORT.md", "Plane elastic punch on an elastic foundation (paper example 4.1)", sections)

    for name, r in results.items():
        print(f"{name}: max plastic slip {r['max_slip_um']:.3f} um")
    print(f"equilibrium: largest relative error {worst_equilibrium:.2e}")
    print(f"results: {out} (REPORT.md, {', '.join(figures)}; runs in {', '.join(str(out / n) for n in MODELS)})")
    if failures:
        fail("checks failed: " + "; ".join(failures))


if __name__ == "__main__":
    main()
