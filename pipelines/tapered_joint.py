#!/usr/bin/env python3
"""Tapered press fit (paper §4.2, Figs. 5-6): push-in force against axial displacement for
Coulomb friction without interface compliance and for two interface-compliance sets,
compared with the slice model of Kollmann / DIN 7190 (docs/theory.md, "Conical press fit: the
slice model"), and the self-locking of the joint on unloading (tan gamma <= mu).

Usage: tapered_joint.py [--out out/tapered_joint] [--size S] [--quick]

Runs examples/tapered_joint/{coulomb,compliant_1,compliant_2}.toml, and the Coulomb case
with mu = 0.1 < tan gamma (not self-locking) for contrast, in parallel, and writes into the
output folder: one run folder per case (VTU/PVD, CSV), force_displacement.png,
contact_stress.png, the contour pictures of each run, and REPORT.md. Exits non-zero when a
check fails: axial equilibrium of the interface force against the applied load (5e-4
relative, the solver's residual tolerance R_n), linearity of F(u_a) for Coulomb friction (1 %), its slope against the slice
model (10 %), self-locking on unloading (tan gamma <= mu: u_a returns by less than 5 %,
what local back-slip at the sleeve edge allows) against the joint with mu = 0.1, which must
slide back by more than half.
"""
from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from asperity_tools import (ROOT, read_contact, read_history, run_cases, solver_statistics, table, variant,  # noqa: E402
                            write_report)  # noqa: E402

RESIDUAL_TOLERANCE = 5e-4  # [solver] residual_tolerance default (README): equilibrium accuracy
HERE = Path(__file__).resolve().parent
CASES_DIR = HERE.parent / "examples" / "tapered_joint"
CASES = {
    "coulomb": "Coulomb friction, no interface compliance",
    "compliant_1": "interface compliance, c_N = 5e-4 mm/MPa^0.5",
    "compliant_2": "interface compliance, c_N = 1e-3 mm/MPa^0.5",
}
# Geometry and material of the case files (examples/tapered_joint/tapered_joint.geo parameters).
TAPER, L, R_M, R_O, E, NU, MU, P0 = 0.2, 40.0, 20.0, 40.0, 206000.0, 0.3, 0.2, 10.0
R_TOP = R_M + 0.5 * L * TAPER


def slice_model_slope() -> float:
    """dF/du_a of the slice model: 2 pi tan(gamma) tan(gamma + rho) int_0^L dz / K(r(z)),
    with the plane-stress Lame compliance per unit radius K of sleeve and solid shaft."""
    z = np.linspace(0.0, L, 2001)
    r = R_M - 0.5 * L * TAPER + z * TAPER
    k = ((R_O**2 + r**2) / (R_O**2 - r**2) + NU) / E + (1.0 - NU) / E
    rho = np.arctan(MU)
    return 2 * np.pi * TAPER * np.tan(np.arctan(TAPER) + rho) * np.trapezoid(1.0 / k, z)


def axial_displacement(contact: dict[str, np.ndarray]) -> float:
    """u_a: mean axial relative displacement of the faces, shaft into sleeve (positive),
    from u_T and u_N (body B minus body A) and the frame of side B (t along the curve order,
    n = rot90(t))."""
    x, y = contact["x"], contact["y"]
    t = np.array([x[-1] - x[0], y[-1] - y[0]])
    t /= np.linalg.norm(t)
    n = np.array([-t[1], t[0]])
    d_z = contact["tangential_slip"] * t[1] + contact["normal_gap"] * n[1]
    return float(np.mean(d_z))


def curve(out: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
    """Load factors, push-in forces F and axial displacements u_a of every step."""
    history = read_history(out)
    steps = history["step"].astype(int)
    u_a = np.array([axial_displacement(read_contact(out, "cone", s)) for s in steps])
    force = history["load_factor"] * P0 * np.pi * R_TOP**2
    return history["load_factor"], force, u_a, history


def check(condition: bool, message: str, failures: list[str]) -> str:
    if not condition:
        failures.append(message)
    return "ok" if condition else "**FAILED**"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "tapered_joint")
    parser.add_argument("--size", type=float, default=None, help="mesh size factor (default: the case files')")
    parser.add_argument("--quick", action="store_true", help="coarse mesh for CI (size 2)")
    args = parser.parse_args()
    size = 2.0 if args.quick and args.size is None else args.size
    out = args.out.resolve()
    runs = [(variant(CASES_DIR / f"{c}.toml", out / "cases" / f"{c}.toml", size=size), out / c) for c in CASES]
    # Not self-locking: unloaded only to 10 % of the load, since at F = 0 the shaft would
    # slide out until it is loose and has no equilibrium position.
    loose = variant(CASES_DIR / "coulomb.toml", out / "cases" / "loose.toml",
                    {"contact[0].law.mu_m": 0.1, "steps.factors[-1]": 0.1}, size=size)
    all_summaries = run_cases(runs + [(loose, out / "loose")])
    summaries = dict(zip(CASES, all_summaries))

    slope_ref = slice_model_slope()
    failures: list[str] = []
    results = {c: curve(out / c) for c in CASES}
    rows, checks = [], []
    fig, ax = plt.subplots(figsize=(7, 5))
    for name, (factors, force, u_a, history) in results.items():
        loading = np.arange(len(factors)) <= int(np.argmax(factors))
        # The curve straight from history.csv (the case's [[history]] u_a, from the unloaded
        # start); the table's numbers use the node mean of the contact CSVs (within ~0.2 %).
        start = read_history(out / name, start=True)
        ax.plot(1e3 * start["u_a"], start["load_factor"] * P0 * np.pi * R_TOP**2 / 1e3, "o-", ms=3,
                label=CASES[name])
        # Axial equilibrium: the shaft pushes the sleeve down with the applied force. Every
        # residual component is at most R_n times the average nodal force (the default
        # convergence criterion, [solver] residual_tolerance = 5e-4), so a resultant over the
        # loaded nodes is out of balance by at most about R_n of the load.
        eq = np.max(np.abs(history["cone_force_on_b_y"] + force)) / force.max()
        checks.append(f"{name}: axial equilibrium of the interface force, max relative error {eq:.1e}: "
                      + check(eq < RESIDUAL_TOLERANCE, f"{name}: axial equilibrium error {eq:.1e}", failures))
        slope = np.polyfit(u_a[loading], force[loading], 1)[0]
        i_max = int(np.argmax(factors))
        back = (u_a[i_max] - u_a[-1]) / u_a[i_max]
        rows.append([CASES[name], slope / 1e3, slope / slope_ref, 1e3 * u_a[i_max], 1e3 * u_a[-1], back])
        if name == "coulomb":
            fit = force[loading] / slope
            linearity = np.max(np.abs(u_a[loading] - fit)) / u_a[loading].max()
            checks.append(f"Coulomb: F(u_a) linear, max deviation {100 * linearity:.2f} % of u_a: "
                          + check(linearity < 0.01, f"F(u_a) not linear ({linearity:.3f})", failures))
            checks.append(f"Coulomb: slope {slope / 1e3:.1f} kN/mm vs slice model {slope_ref / 1e3:.1f} kN/mm "
                          f"({100 * (slope / slope_ref - 1):+.1f} %): "
                          + check(abs(slope / slope_ref - 1) < 0.10, "slope off the slice model by > 10 %", failures))
            factors_l, _, u_l, _ = curve(out / "loose")
            i_l = int(np.argmax(factors_l))
            back_loose = (u_l[i_l] - u_l[-1]) / u_l[i_l]
            gamma, rho = np.arctan(TAPER), np.arctan(0.1)
            back_slice = 1.0 - factors_l[-1] * np.tan(gamma + rho) / np.tan(gamma - rho)
            checks.append(f"Coulomb: self-locking (tan γ = {TAPER} <= μ = {MU}): u_a moves back by "
                          f"{100 * back:.2f} % on unloading to F = 0 (local back-slip at the sleeve edge): "
                          + check(abs(back) < 0.05, f"axial motion on unloading ({back:.3f})", failures))
            checks.append(f"Contrast, μ = 0.1 < tan γ (not self-locking), unloaded to {factors_l[-1]:.1f} F: u_a moves back "
                          f"by {100 * back_loose:.1f} % (slice model {100 * back_slice:.1f} %): "
                          + check(back_loose > 0.5, f"the loose joint did not slide back ({back_loose:.3f})", failures))
    u_ref = np.linspace(0.0, results["coulomb"][2].max(), 10)
    ax.plot(1e3 * u_ref, slope_ref * u_ref / 1e3, "k-", lw=1, label="slice model (Kollmann), no compliance")
    ax.set_xlabel("axial displacement u_a [µm]")
    ax.set_ylabel("push-in force F [kN]")
    ax.set_title(f"Tapered joint, tan γ = {TAPER}, μ = {MU}")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "force_displacement.png", dpi=120)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(7, 4))
    for name in CASES:
        last_load = int(np.argmax(results[name][0])) + 1
        c = read_contact(out / name, "cone", last_load)
        ax.plot(c["y"], c["contact_pressure"], "-", label=f"pressure, {name}")
        ax.plot(c["y"], np.abs(c["contact_shear_stress"]), "--", label=f"|shear|, {name}")
    ax.set_xlabel("axial position z along the cone [mm]")
    ax.set_ylabel("contact stress [MPa]")
    ax.set_title("contact stresses at full load")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "contact_stress.png", dpi=120)
    plt.close(fig)

    for name in CASES:
        done = subprocess.run([sys.executable, str(HERE / "plot_fields.py"), str(out / name)], capture_output=True, text=True)
        if done.returncode != 0:
            failures.append(f"plot_fields.py failed on {name}: {done.stderr.strip()[-300:]}")

    stats = table(["case", "steps / iterations", "time"], [[name, *solver_statistics(summaries[name])] for name in CASES])
    write_report(out / "REPORT.md", "Tapered joint (paper §4.2)", [
        ("Set-up", f"""Axisymmetric conical press fit, `examples/tapered_joint/tapered_joint.geo`: taper 1:2.5 read as tan γ = {TAPER}
(`docs/theory.md`, "The paper's examples: data and choices"), contact length L = {L} mm,
mean contact radius r_m = {R_M} mm, sleeve outer radius
R_o = {R_O} mm, solid shaft; E = {E:.0f} MPa, ν = {NU}; μ = {MU}. The shaft is pushed in by
p0 = {P0} MPa on its top face (F = p0 π r² = {P0 * np.pi * R_TOP**2 / 1e3:.2f} kN at load factor 1) in
ten increments, then unloaded to zero in five. Cases: {", ".join(f"`{c}` ({d})" for c, d in CASES.items())}.
Mesh size factor: {size or "as in the case files"}."""),
        ("Force against axial displacement (Fig. 6)", table(
            ["case", "slope dF/du_a [kN/mm]", "slope / slice model", "u_a at full load [µm]", "u_a after unloading [µm]",
             "relative return on unloading"], rows) + f"""

Slice model (Kollmann 1984; `docs/theory.md`, "Conical press fit: the slice model"):
dF/du_a = 2π tan γ tan(γ+ρ) ∫dz/K(r) = {slope_ref / 1e3:.1f} kN/mm.
The FE slope differs from it by end effects (the slice model ignores the shear coupling
between slices and the free ends of the sleeve). With interface compliance the joint is
softer (larger u_a at the same force), as the paper reports, the more so the larger c_N.
The figure's curves are `history.csv`'s `u_a` column (a `[[history]]` entry of the cases:
the length-weighted mean relative axial displacement of the cone faces, from the unloaded
start); the table's u_a and slopes are the mean over the interface nodes of the per-step
contact CSVs, which differs from it by about 0.2 %.

![force-displacement](force_displacement.png)"""),
        ("Checks", "\n".join(f"- {c}" for c in checks)),
        ("Contact stresses", "![contact stresses](contact_stress.png)\n\n"
         + "\n".join(f"- `{c}`: ![von Mises]({c}/von_mises.png)" for c in CASES)),
        ("Solver statistics", stats),
    ])
    print(f"results: {out} (REPORT.md, force_displacement.png, run folders with results.pvd)")
    if failures:
        sys.exit("tapered joint checks failed:\n  " + "\n  ".join(failures))


if __name__ == "__main__":
    main()
