#!/usr/bin/env python3
"""Shrink fit made by heating the hub (issue 26): the hub is heated until its bore clears the
shaft, the shaft goes in, the assembly cools and the fit closes; the contact pressure at every
hub temperature against Lamé's closed form, computed here from the case file's data.

Usage: shrink_fit_thermal.py [--out out/shrink_fit_thermal] [--size S] [--quick]

Runs pipelines/shrink_fit_thermal/case.toml twice, in parallel:
  eps_z_0      as written: both end planes held axially (ε_z = 0), friction 0.2; the bore of
               the heated hub grows by (1 + ν) α ΔT b;
  free_axial   held on the bottom planes only, frictionless: the slice expands axially, the
               bore grows by α ΔT b (with friction the hub's axial contraction on cooling
               would load the joint in shear, which Lamé's solution leaves out);
and writes into OUT: one run folder per case, pressure_temperature.png, the pictures of
plot_fields.py for each run, and REPORT.md. Checks (each in the report with its numbers;
exit status 1 if one fails):
- the pressure of every interface node at every frame equals Lamé's
  p = max(0, δ − κ α ΔT b) / (C + 1/k_N) (κ = 1 + ν for ε_z = 0, 1 when free; C the plane
  strain or plane stress compliance of the solid shaft and the hub, docs/theory.md) to 1e-3
  of the cold pressure (6 quadratic elements through each wall; the solver tests measure
  6e-6 for the cold fit, the free slice's axial sliding leaves ~1e-4);
- the opening temperature: the straight line through the closed frames' (ΔT, p) reaches
  p = 0 at δ / (κ α b) to 1e-3;
- hot and open: the clearance (normal gap) is κ α ΔT b − δ to 1e-3 of δ, and the bodies
  carry only the free thermal stress (zero, or σ_zz = −E α ΔT in the hub with ε_z = 0) to
  1e-6 of E α ΔT: a uniform temperature strains a free body without stress;
- the energy balance of summary.json: imbalance below 1e-6 of the stored energy.

--quick runs the coarse mesh (size 2, 3 elements through each wall; the pressure tolerance
is then 1e-2) for `make test`.
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import tomllib
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from asperity_tools import (ROOT, Checks, body_points, read_contact, read_history, read_step, run_cases, solver_statistics,  # noqa: E402
                            table, variant, write_report)

HERE = Path(__file__).resolve().parent
CASE = HERE / "shrink_fit_thermal" / "case.toml"
FREE = {"support[0].group": "shaft_bottom", "support[1].group": "hub_bottom", "contact[0].law.friction": 0.0}
RUNS = {"eps_z_0": "end planes held (ε_z = 0), μ = 0.2", "free_axial": "free to expand axially, frictionless"}


class Fit:
    """Lamé's shrink fit of a solid shaft (radius b) in a hub (outer radius c), of one
    material, with the linear interface law k_N and the hub heated uniformly by ΔT; the data
    are read from the case file."""

    def __init__(self, case: dict, free_axial: bool) -> None:
        geometry = case["mesh"]["parameters"]
        self.b, self.c = geometry["b"], geometry["c"]
        hub = next(body for body in case["body"] if body["group"] == "hub")["material"]
        self.e, self.nu, self.alpha = hub["E"], hub["nu"], hub["expansion"]
        contact = case["contact"][0]
        self.delta, self.k_n = contact["interference"], contact["law"]["normal_stiffness"]
        self.hot = next(t for t in case["temperature"] if t["group"] == "hub")["change"]
        self.free_axial = free_axial

    @property
    def kappa(self) -> float:
        """The bore's thermal growth per α ΔT b: 1 free, 1 + ν with ε_z = 0."""
        return 1.0 if self.free_axial else 1.0 + self.nu

    def compliance(self) -> float:
        """C: interference closed per unit pressure, shaft plus hub (docs/theory.md, "Lamé
        cylinders and the shrink fit"); plane stress when free, plane strain otherwise."""
        e, nu = (self.e, self.nu) if self.free_axial else (self.e / (1 - self.nu**2), self.nu / (1 - self.nu))
        b2, c2 = self.b**2, self.c**2
        return self.b * ((1 - nu) / e + ((c2 + b2) / (c2 - b2) + nu) / e)

    def pressure(self, dt: np.ndarray) -> np.ndarray:
        interference = self.delta - self.kappa * self.alpha * dt * self.b
        return np.maximum(interference, 0.0) / (self.compliance() + 1.0 / self.k_n)

    def opening(self) -> float:
        return self.delta / (self.kappa * self.alpha * self.b)

    def clearance(self, dt: float) -> float:
        return self.kappa * self.alpha * dt * self.b - self.delta


def frames(out: Path, fit: Fit) -> dict[str, np.ndarray]:
    """Per converged frame: the hub's ΔT, the pressures and gaps of the interface nodes."""
    history = read_history(out)
    steps = history["step"].astype(int)
    contact = [read_contact(out, "fit", s) for s in steps]
    return {"step": steps, "dt": fit.hot * history["factor_thermal_hub_heat"],
            "analysis_step": history["analysis_step"].astype(int),
            "pressure": np.array([c["contact_pressure"] for c in contact]),
            "gap": np.array([c["normal_gap"] for c in contact])}


def free_stress_error(out: Path, step: int, fit: Fit, dt: float) -> float:
    """Largest deviation of the bodies' stress at `step` from the free thermal state (zero,
    and σ_zz = −E α ΔT in the hub with ε_z = 0), relative to E α ΔT."""
    grid = read_step(out, step)["bodies"]
    stress = np.asarray(grid.point_data["stress"])  # xx, yy, zz, xy, yz, xz: rr, zz, θθ, rz
    expected = np.zeros_like(stress)
    if not fit.free_axial:
        expected[body_points(grid, "hub"), 1] = -fit.e * fit.alpha * dt
    return float(np.abs(stress - expected).max() / (fit.e * fit.alpha * dt))


def check_run(name: str, out: Path, fit: Fit, summary: dict, tolerance: float, checks: Checks) -> dict:
    """The checks of one run; returns its frames for the figure and tables."""
    f = frames(out, fit)
    cold = float(fit.pressure(np.array(0.0)))
    reference = fit.pressure(f["dt"])
    error = np.abs(f["pressure"] - reference[:, None]).max() / cold
    checks(error <= tolerance, f"`{name}`: contact pressure of every node at every frame against Lamé "
           f"(cold: {cold:.4f} MPa), largest error {error:.2e} of the cold pressure (tolerance {tolerance:g})")
    closed = f["pressure"].min(axis=1) > 0
    heating = closed & (f["analysis_step"] == 1)
    slope, intercept = np.polyfit(f["dt"][heating], f["pressure"][heating].mean(axis=1), 1)
    opening = -intercept / slope
    ratio = opening / fit.opening() - 1
    checks(abs(ratio) <= tolerance, f"`{name}`: the fit opens at ΔT = {opening:.3f} K (the heating frames' "
           f"p(ΔT) extrapolated to 0); δ/(κ α b) = {fit.opening():.3f} K with κ = {fit.kappa:g} "
           f"(relative difference {ratio:.1e}, tolerance {tolerance:g})")
    hot = int(np.argmax(f["dt"]))
    dt = float(f["dt"][hot])
    gap_error = np.abs(f["gap"][hot] - fit.clearance(dt)).max() / fit.delta
    checks(not closed[hot] and gap_error <= tolerance,
           f"`{name}`: hot (ΔT = {dt:g} K) the fit is open with clearance {1e3 * f['gap'][hot].mean():.4f} µm "
           f"against κ α ΔT b − δ = {1e3 * fit.clearance(dt):.4f} µm (error {gap_error:.1e} of δ)")
    stress = free_stress_error(out, int(f["step"][hot]), fit, dt)
    checks(stress <= 1e-6, f"`{name}`: hot and open, the bodies' stress is the free thermal state "
           f"({'zero' if fit.free_axial else 'σ_zz = −E α ΔT in the hub, zero elsewhere'}) to {stress:.1e} of E α ΔT")
    energy = summary["energy"]["total"]
    imbalance = abs(energy["imbalance"]) / max(energy["elastic_energy"] + energy["interface_energy"], 1e-300)
    checks(imbalance <= 1e-6, f"`{name}`: energy imbalance {imbalance:.1e} of the stored energy "
           f"(external work {energy['external_work']:.4g}, thermal work {energy['thermal_work']:.4g} N·mm)")
    f["reference"], f["opening"], f["cold"] = reference, opening, cold
    return f


def pressure_figure(out: Path, fits: dict[str, Fit], results: dict[str, dict]) -> Path:
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for (name, fit), colour in zip(fits.items(), ["C0", "C1"]):
        f = results[name]
        dt = np.linspace(0.0, fit.hot, 301)
        ax.plot(dt, fit.pressure(dt), "-", color=colour, lw=1, label=f"Lamé, {RUNS[name]}")
        heat, cool = f["analysis_step"] == 1, f["analysis_step"] == 2
        ax.plot(f["dt"][heat], f["pressure"][heat].mean(axis=1), "o", color=colour, ms=6, mfc="none",
                label=f"asperity, heating ({name})")
        ax.plot(f["dt"][cool], f["pressure"][cool].mean(axis=1), "x", color=colour, ms=6, label=f"asperity, cooling ({name})")
        ax.axvline(fit.opening(), color=colour, ls=":", lw=1)
    ax.set_xlabel("hub temperature change ΔT [K]")
    ax.set_ylabel("contact pressure [MPa]")
    ax.set_title("Shrink fit: pressure against the hub's temperature (dotted: δ/(κ α b))")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    path = out / "pressure_temperature.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def pictures(out: Path, run: str) -> list[str]:
    """plot_fields.py's pictures of a run (von Mises, reactions, contact stresses); the
    failures, if any."""
    done = subprocess.run([sys.executable, str(HERE / "plot_fields.py"), str(out / run)], capture_output=True, text=True)
    return [] if done.returncode == 0 else [f"plot_fields.py failed on {run}: {done.stderr.strip()[-300:]}"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "shrink_fit_thermal")
    parser.add_argument("--size", type=float, default=None, help="mesh size factor (default: the case file's)")
    parser.add_argument("--quick", action="store_true", help="coarse mesh for CI (size 2)")
    args = parser.parse_args()
    size = 2.0 if args.quick and args.size is None else args.size
    tolerance = 1e-2 if (size or 1.0) > 1.0 else 1e-3
    out = args.out.resolve()
    cases = {"eps_z_0": variant(CASE, out / "cases" / "eps_z_0.toml", size=size),
             "free_axial": variant(CASE, out / "cases" / "free_axial.toml", FREE, size=size)}
    summaries = dict(zip(cases, run_cases([(case, out / name) for name, case in cases.items()])))
    fits = {name: Fit(tomllib.loads(case.read_text()), name == "free_axial") for name, case in cases.items()}

    checks = Checks()
    results = {name: check_run(name, out / name, fits[name], summaries[name], tolerance, checks) for name in cases}
    figure = pressure_figure(out, fits, results)
    for name in cases:
        for failure in pictures(out, name):
            checks(False, failure)

    fit = fits["eps_z_0"]
    rows = []
    for name, f in results.items():
        for k, step in enumerate(f["step"]):
            rows.append([name, int(step), ["heat", "cool"][f["analysis_step"][k] - 1], float(f["dt"][k]),
                         float(f["pressure"][k].mean()), float(f["reference"][k]),
                         float(1e3 * f["gap"][k].mean())])
    setup = f"""Axisymmetric slice of `examples/shrink_fit/shrink_fit.geo`: solid shaft of radius b = {fit.b} mm in a hub of
outer radius c = {fit.c} mm, radial interference δ = {fit.delta} mm, E = {fit.e:.0f} MPa, ν = {fit.nu},
α = {fit.alpha:g} 1/K, interface stiffness k_N = {fit.k_n:g} MPa/mm (`linear_coulomb`). The hub is
heated by ΔT = {fit.hot:g} K in six increments (`[[temperature]] hub_heat`, step `heat`) and cooled
back to the reference in six (`cool`). The shaft is in place from the start: the bodies are
elastic, so once the fit is open (ΔT > δ/(κ α b)) the state, and the cooling that follows,
are those of a shaft slid into the hot hub. Runs: {", ".join(f"`{n}` ({d})" for n, d in RUNS.items())}.
Mesh size factor: {size or "as in the case file"}.

Closed form (computed in this script from the case data): the hub's free thermal growth
κ α ΔT b (κ = 1 + ν with ε_z = 0, 1 when free) takes from the interference, so
p = max(0, δ − κ α ΔT b) / (C + 1/k_N), C = b (C_shaft + C_hub) in plane strain (ε_z = 0) or
plane stress (free ends: uniform ε_z in each body, exact without friction);
C = {fit.compliance():.6g} mm/MPa (ε_z = 0), {fits['free_axial'].compliance():.6g} mm/MPa (free)."""
    write_report(out / "REPORT.md", "Shrink fit by heating the hub", [
        ("Set-up", setup),
        ("Checks", checks.markdown()),
        ("Pressure against the hub's temperature", f"![pressure against temperature]({figure.name})\n\n"
         + table(["run", "frame", "step", "ΔT [K]", "pressure, mean [MPa]", "Lamé [MPa]", "normal gap, mean [µm]"], rows)),
        ("Fields at the end (cold fit)", "\n\n".join(
            f"`{name}`: ![von Mises]({name}/von_mises.png) ![contact stresses]({name}/contact_fit.png)" for name in cases)),
        ("Solver statistics", table(["run", "steps / iterations", "time [s]"],
                                    [[name, *solver_statistics(summaries[name])] for name in cases])),
    ])
    print(f"results: {out} (REPORT.md, pressure_temperature.png, run folders with results.pvd)")
    print("\n".join(checks.lines))
    checks.exit_on_failure("shrink_fit_thermal")


if __name__ == "__main__":
    main()
