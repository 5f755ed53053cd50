"""Torque on the tapered joint of examples/taper_torque: runs both cases, draws what they show
and checks the slip torque against the friction of the run's own pressure.

    .venv/bin/python pipelines/taper_torque/report.py [--out OUT] [--quick]

Runs `taper_torque.toml` (seated by an axial load, then twisted at the head until the whole cone
slips) and `taper_fretting.toml` (seated, then a reversed torque below the slip torque with
fretting wear), into OUT/twist and OUT/fretting.

Figures (in OUT): `torque_twist.png`, the torque against the head's rotation with the slip
torque marked and, per frame, the friction torque of the frame's pressure ∫ μ|p| r dA (the
bound Coulomb's law on the friction circle puts on it); `cone.png`, pressure and shear along
the cone at full slip; `fretting.png`, the torque against the head's twist in the first and
last simulated cycles, and the dissipation per cycle and the worn volume against the cycles.

Checks (exit status 1 when one fails), all from the runs' own files:
- at full slip every closed node slips with |τ| = μ|p|, |τ| = √(τ² + τ_θ²) from the contact
  CSV (the case integrates on the nodes, `integration = "newton_cotes"`, so the CSV carries
  the integration points' states; 1e-4 covers the CSV's digits);
- the slip torque (the reaction torque of the head's rotation) equals the pair's torque in
  history.csv (equilibrium of the shaft, to the Newton residual: 1e-3) and the friction torque
  of the pressure along the circle, ∫ √((μ p)² − τ²) r dA, Simpson's rule on the CSV's nodes
  being the element's own three-point rule (1e-3);
- it is at most the friction torque ∫ μ|p| r dA, equality when the slip is circumferential;
  the report gives the ratio (the meridional friction still holding the axial load);
- in the fretting run, the torque stays below the slip torque, and the loop area ∮ T dφ of the
  last simulated cycle equals that cycle's friction dissipation (cycles.csv) to 2 %, the
  difference being the trapezoidal rule on the loop's corners and the stored energy a worn
  cycle does not return.
`--quick` runs a coarser mesh and fewer cycles (make test).
"""
from __future__ import annotations

import argparse
import sys
import tomllib
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from asperity_tools import (ROOT, Checks, read_csv, read_history, run_cases, table, variant,  # noqa: E402
                            write_report)

EXAMPLE = ROOT / "examples" / "taper_torque"
PAIR = "cone"
TWIST = "twist"         # the support that turns the head (taper_torque.toml)
TORQUE = "torque"       # the torque load of taper_fretting.toml
TWIST_STEP = 2
SERVICE_STEP = 2


def along_cone(contact: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Simpson weights of the contact CSV's nodes (three per element, ends shared) for
    ∫ f dA = ∫ f 2π r ds, and the radius r of each node."""
    s, r = contact["arc_length"], contact["x"]
    weights = np.zeros_like(s)
    for k in range(0, len(s) - 2, 2):
        h = s[k + 2] - s[k]
        weights[k:k + 3] += h * np.array([1.0, 4.0, 1.0]) / 6.0
    return weights * 2.0 * np.pi * r, r


def friction_torques(contact: dict[str, np.ndarray], mu: float) -> tuple[float, float]:
    """∫ μ|p| r dA and ∫ √((μ p)² − τ²) r dA (the circumferential friction that the friction
    circle leaves beside the meridional shear τ) over the cone."""
    da, r = along_cone(contact)
    limit = mu * contact["contact_pressure"]
    circle = np.sqrt(np.maximum(limit**2 - contact["contact_shear_stress"] ** 2, 0.0))
    return float(np.sum(limit * r * da)), float(np.sum(circle * r * da))


def twist_run(run: Path, case: dict, out: Path, checks: Checks) -> dict:
    mu = case["contact"][0]["law"]["mu_m"]
    phi = next(s for s in case["support"] if s["name"] == TWIST)["rotation"]
    history = read_history(run)
    twist = history["analysis_step"] == TWIST_STEP
    frames = history["step"][twist].astype(int)
    rotation = history[f"factor_support_{TWIST}"][twist] * phi
    torque = history[f"reaction_{TWIST}_torque"][twist]
    pair_torque = history[f"{PAIR}_torque"][twist]
    stick = history[f"{PAIR}_stick_area"][twist]
    bound = np.array([friction_torques(read_csv(run / f"contact_{PAIR}_{k:04d}.csv"), mu)[0] for k in frames])
    full = np.flatnonzero(stick == 0.0)
    first_full = full[0] if full.size else None

    last = read_csv(run / f"contact_{PAIR}_{frames[-1]:04d}.csv")
    closed = last["contact_status"] > 0
    shear = np.hypot(last["contact_shear_stress"], last["contact_shear_stress_theta"])
    limit = mu * last["contact_pressure"]
    all_slip = bool(np.all(last["contact_status"][closed] == 2))
    checks(all_slip, f"at the last frame every closed node slips ({int(closed.sum())} closed nodes)")
    worst = float(np.max(np.abs(shear[closed] - limit[closed]) / limit[closed]))
    checks(worst < 1e-4, f"|τ| = μ|p| at every slipping node: largest relative difference {worst:.2e} (< 1e-4)")
    t_mu, t_circle = friction_torques(last, mu)
    t_slip = abs(torque[-1])
    checks(abs(t_slip - abs(pair_torque[-1])) < 1e-3 * t_slip,
           f"slip torque {t_slip:.6g} N·mm (reaction of the head) = pair torque {abs(pair_torque[-1]):.6g} N·mm "
           f"(1e-3)")
    checks(abs(t_slip - t_circle) < 1e-3 * t_slip,
           f"slip torque {t_slip:.6g} N·mm = ∫ √((μp)² − τ²) r dA = {t_circle:.6g} N·mm from the contact CSV (1e-3)")
    checks(t_slip <= t_mu * (1.0 + 1e-3),
           f"slip torque {t_slip:.6g} N·mm ≤ ∫ μ|p| r dA = {t_mu:.6g} N·mm (ratio {t_slip / t_mu:.4f})")

    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    ax.plot(rotation * 1e3, torque / 1e3, ".-", label="torque at the head")
    ax.plot(rotation * 1e3, bound / 1e3, "--", color="grey", label=r"$\int \mu|p|\,r\,dA$ of the frame's pressure")
    if first_full is not None:
        ax.plot(rotation[first_full] * 1e3, torque[first_full] / 1e3, "o", color="C3",
                label=f"whole cone slips ({torque[first_full] / 1e3:.4g} N·m)")
    ax.axhline(t_slip / 1e3, color="C3", ls=":", lw=1, label=f"slip torque {t_slip / 1e3:.4g} N·m")
    ax.set_xlabel("rotation of the head φ [mrad]")
    ax.set_ylabel("torque [N·m]")
    ax.set_title("tapered joint twisted under its seating load")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "torque_twist.png", dpi=130)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    z = last["y"]
    ax.plot(z, last["contact_pressure"], label="pressure |p|")
    ax.plot(z, limit, "--", color="grey", label="μ|p|")
    ax.plot(z, shear, label="|τ|")
    ax.plot(z, np.abs(last["contact_shear_stress_theta"]), label="circumferential |τ_θ|")
    ax.plot(z, np.abs(last["contact_shear_stress"]), label="meridional |τ|")
    ax.set_xlabel("z along the cone [mm] (narrow end at 0)")
    ax.set_ylabel("stress [MPa]")
    ax.set_title("the cone at full slip")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "cone.png", dpi=130)
    plt.close(fig)
    rows = [[int(k), float(p * 1e3), float(t), float(b), float(s)]
            for k, p, t, b, s in zip(frames, rotation, torque, bound, stick)]
    return {"t_slip": t_slip, "t_mu": t_mu, "t_circle": t_circle, "rows": rows,
            "first_full": None if first_full is None else float(torque[first_full])}


def fretting_run(run: Path, case: dict, out: Path, t_slip: float, checks: Checks) -> str:
    amplitude = next(load for load in case["load"] if load["name"] == TORQUE)[TORQUE]
    history = read_history(run, start=True)
    service = history["analysis_step"] == SERVICE_STEP
    torque = history[f"factor_load_{TORQUE}"] * amplitude
    twist = history["head_twist"]
    cycles = read_csv(run / "cycles.csv")
    cycles = {name: values[cycles["analysis_step"] == SERVICE_STEP] for name, values in cycles.items()}
    checks(np.max(np.abs(torque)) < t_slip,
           f"the service torque ±{amplitude:.6g} N·mm stays below the slip torque {t_slip:.6g} N·mm")

    def loop(cycle: int) -> np.ndarray:
        rows = np.flatnonzero(service & (history["cycle"] == cycle))
        return np.concatenate([[rows[0] - 1], rows])

    simulated = sorted({int(c) for c in history["cycle"][service]})
    last = simulated[-1]
    rows = loop(last)
    area = abs(np.trapezoid(torque[rows], twist[rows]))
    dissipation = float(cycles["dissipation"][-1])
    checks(abs(area - dissipation) <= 2e-2 * dissipation,
           f"loop area ∮ T dφ of the last simulated cycle {area:.6g} N·mm = its friction dissipation "
           f"{dissipation:.6g} N·mm (cycles.csv, 2 %)")

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.4))
    for cycle, colour in ((simulated[0], "C0"), (last, "C1")):
        rows = loop(cycle)
        left.plot(twist[rows] * 1e6, torque[rows] / 1e3, "-", color=colour,
                  label=f"simulated cycle {cycle} (cycle {int(history['cycles'][rows[-1]])})")
    left.set_xlabel("twist of the head [µrad]")
    left.set_ylabel("torque [N·m]")
    left.set_title("torque against twist")
    left.grid(alpha=0.3)
    left.legend(fontsize=8)
    right.semilogx(cycles["cycles"], cycles["dissipation"], "o-", label="dissipation per cycle [N·mm]")
    right.set_xlabel("cycles")
    right.set_ylabel("dissipation per cycle [N·mm]")
    twin = right.twinx()
    twin.semilogx(cycles["cycles"], cycles["worn_volume"], "s-", color="C2", label="worn volume [mm³]")
    twin.set_ylabel("worn volume [mm³]")
    right.set_title("torsional fretting")
    right.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "fretting.png", dpi=130)
    plt.close(fig)
    return (f"Reversed torque ±{amplitude / 1e3:.4g} N·m ({amplitude / t_slip:.0%} of the slip torque), "
            f"{int(cycles['cycles'][-1])} cycles in {len(simulated)} simulated ones. Dissipation per cycle "
            f"{float(cycles['dissipation'][0]):.4g} N·mm in the first cycle, {dissipation:.4g} N·mm in the last; "
            f"worn volume {float(cycles['worn_volume'][-1]):.4g} mm³, largest wear depth "
            f"{float(cycles['max_wear_depth'][-1]) * 1e3:.3g} µm.")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "taper_torque")
    parser.add_argument("--quick", action="store_true", help="coarser mesh, fewer cycles (make test)")
    args = parser.parse_args()
    out = args.out
    out.mkdir(parents=True, exist_ok=True)
    twist_case, fretting_case = EXAMPLE / "taper_torque.toml", EXAMPLE / "taper_fretting.toml"
    if args.quick:
        twist_case = variant(twist_case, out / "quick_twist.toml", size=2.0)
        fretting_case = variant(fretting_case, out / "quick_fretting.toml",
                                {"step[1].cycles": 1000, "step[1].cycles_per_jump": 500}, size=2.0)
    run_cases([(twist_case, out / "twist"), (fretting_case, out / "fretting")])
    checks = Checks()
    twist = twist_run(out / "twist", tomllib.loads(twist_case.read_text()), out, checks)
    fretting = fretting_run(out / "fretting", tomllib.loads(fretting_case.read_text()), out, twist["t_slip"],
                            checks)
    first = ("" if twist["first_full"] is None else
             f" The whole cone first slips at {twist['first_full'] / 1e3:.4g} N·m; the torque then still rises "
             f"as the shaft sinks deeper under its axial load.")
    write_report(out / "REPORT.md", "Torque on a tapered joint", [
        ("What was run", f"`examples/taper_torque/taper_torque.toml`{' (quick: mesh size 2)' if args.quick else ''}: "
                         f"the cone seated by 10 MPa on the shaft's head, then the head turned with the axial "
                         f"load held (`twist/`); `taper_fretting.toml`: seated, then a reversed torque with "
                         f"Archard wear (`fretting/`). Open `results.pvd` of either in ParaView."),
        ("Slip torque", f"Slip torque (the head's reaction at the last frame, whole cone slipping) "
                        f"{twist['t_slip'] / 1e3:.5g} N·m. Friction torque of the run's own pressure "
                        f"∫ μ|p| r dA = {twist['t_mu'] / 1e3:.5g} N·m (ratio {twist['t_slip'] / twist['t_mu']:.4f}: "
                        f"the rest of the friction still holds the axial load, the slip is not purely "
                        f"circumferential); on the friction circle ∫ √((μp)² − τ²) r dA = "
                        f"{twist['t_circle'] / 1e3:.5g} N·m.{first}"),
        ("Torque against rotation", table(["frame", "rotation φ [mrad]", "torque [N·mm]", "∫ μ|p| r dA [N·mm]",
                                           "sticking area [mm²]"], twist["rows"])),
        ("Torsional fretting", fretting),
        ("Figures", "`torque_twist.png`, `cone.png`, `fretting.png`"),
        ("Checks", checks.markdown()),
    ])
    print((out / "REPORT.md").read_text())
    checks.exit_on_failure("taper_torque")
    return 0


if __name__ == "__main__":
    sys.exit(main())
