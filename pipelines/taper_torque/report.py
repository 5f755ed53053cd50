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
- the torque peaks in the first frame in which the whole cone slips (the slip torque);
- at the peak every closed node slips with |τ| = μ|p|, |τ| = √(τ² + τ_θ²) from the contact
  CSV (the case integrates on the nodes, `integration = "newton_cotes"`, so the CSV carries
  the integration points' states; 1e-4 covers the CSV's digits);
- the slip torque (the reaction torque of the head's rotation) equals the pair's torque in
  history.csv (equilibrium of the shaft, to the Newton residual: 1e-3) and the friction torque
  of the pressure along the circle, ∫ √((μ p)² − τ²) r dA, Simpson's rule on the CSV's nodes
  being the element's own three-point rule (1e-3);
- it is at most the friction torque ∫ μ|p| r dA, equality when the slip is circumferential;
  the report gives the ratio (the meridional friction still holding the axial load);
- in the fretting run, the torque stays below the slip torque, and the loop area ∮ T dφ of a
  cycle (the head's `twist` history) equals the cycle's external work in history.csv (1 %).
`--quick` runs a coarser mesh and fewer cycles (make test).
"""
from __future__ import annotations

import argparse
import csv
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
TWIST_STEP = 3         # seat, release, twist
SERVICE_STEP = 3       # seat, release, service


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
    peak = int(np.argmax(np.abs(torque)))
    t_slip = abs(torque[peak])
    full = np.flatnonzero(stick == 0.0)
    checks(full.size > 0 and full[0] == peak,
           f"the torque peaks ({t_slip:.6g} N·mm at φ = {rotation[peak] * 1e3:.3g} mrad) in the first frame in "
           f"which the whole cone slips")

    # Coulomb's law at the peak, from the contact CSV of that frame.
    at_peak = read_csv(run / f"contact_{PAIR}_{frames[peak]:04d}.csv")
    closed = at_peak["contact_status"] > 0
    shear = np.hypot(at_peak["contact_shear_stress"], at_peak["contact_shear_stress_theta"])
    limit = mu * at_peak["contact_pressure"]
    checks(bool(np.all(at_peak["contact_status"][closed] == 2)),
           f"at the peak every closed node slips ({int(closed.sum())} closed nodes)")
    worst = float(np.max(np.abs(shear[closed] - limit[closed]) / limit[closed]))
    checks(worst < 1e-4, f"|τ| = μ|p| at every slipping node: largest relative difference {worst:.2e} (< 1e-4)")
    t_mu, t_circle = friction_torques(at_peak, mu)
    checks(abs(t_slip - abs(pair_torque[peak])) < 1e-3 * t_slip,
           f"slip torque {t_slip:.6g} N·mm (reaction of the head) = pair torque {abs(pair_torque[peak]):.6g} N·mm "
           f"(1e-3)")
    checks(abs(t_slip - t_circle) < 1e-3 * t_slip,
           f"slip torque {t_slip:.6g} N·mm = ∫ √((μp)² − τ²) r dA = {t_circle:.6g} N·mm from the contact CSV (1e-3)")
    checks(t_slip <= t_mu * (1.0 + 1e-3),
           f"slip torque {t_slip:.6g} N·mm ≤ ∫ μ|p| r dA = {t_mu:.6g} N·mm (ratio {t_slip / t_mu:.4f})")
    # Without an axial load, the cone's axial balance at full slip needs the meridional
    # friction to hold p tan γ against the pressure's wedge (for a uniform pressure and
    # a thin wall), leaving √(μ² − tan² γ) of the friction for the torque.
    tan_gamma = case["mesh"]["parameters"]["taper"]
    wedge = np.sqrt(1.0 - (tan_gamma / mu) ** 2)

    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    ax.plot(np.r_[0.0, rotation] * 1e3, np.r_[0.0, torque] / 1e3, ".-", label="torque at the head")
    ax.plot(rotation * 1e3, bound / 1e3, "--", color="grey", label=r"$\int \mu|p|\,r\,dA$ of the frame's pressure")
    ax.plot(rotation[peak] * 1e3, torque[peak] / 1e3, "o", color="C3",
            label=f"slip torque {t_slip / 1e3:.4g} N·m: the whole cone slips")
    ax.axhline(t_slip / 1e3, color="C3", ls=":", lw=1)
    ax.set_xlabel("rotation of the head φ [mrad]")
    ax.set_ylabel("torque [N·m]")
    ax.set_title("seated tapered joint twisted until it slips")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "torque_twist.png", dpi=130)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    z = at_peak["y"]
    ax.plot(z, at_peak["contact_pressure"], label="pressure |p|")
    ax.plot(z, limit, "--", color="grey", label="μ|p|")
    ax.plot(z, shear, label="|τ|")
    ax.plot(z, np.abs(at_peak["contact_shear_stress_theta"]), label="circumferential |τ_θ|")
    ax.plot(z, np.abs(at_peak["contact_shear_stress"]), label="meridional |τ|")
    ax.set_xlabel("z along the cone [mm] (narrow end at 0)")
    ax.set_ylabel("stress [MPa]")
    ax.set_title(f"the cone at the slip torque (φ = {rotation[peak] * 1e3:.3g} mrad)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "cone.png", dpi=130)
    plt.close(fig)
    rows = [[int(k), float(p * 1e3), float(t), float(b), float(s)]
            for k, p, t, b, s in zip(frames, rotation, torque, bound, stick)]
    return {"t_slip": t_slip, "t_mu": t_mu, "t_circle": t_circle, "rows": rows, "wedge": wedge,
            "rotation": float(rotation[peak]), "last": float(abs(torque[-1])), "last_rotation": float(rotation[-1]),
            "normal": (float(abs(history[f"{PAIR}_normal_force"][twist][0])),
                       float(abs(history[f"{PAIR}_normal_force"][twist][-1])))}


def fretting_run(run: Path, case: dict, out: Path, t_slip: float, checks: Checks) -> str:
    amplitude = next(load for load in case["load"] if load["name"] == TORQUE)[TORQUE]
    history = read_history(run, start=True)
    service = history["analysis_step"] == SERVICE_STEP
    torque = history[f"factor_load_{TORQUE}"] * amplitude
    twist = history["head_twist"]
    # cycles.csv: one row per simulated cycle and contact (its `contact` column is the name).
    with open(run / "cycles.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if int(r["analysis_step"]) == SERVICE_STEP and r["contact"] == PAIR]
    cycles = {name: np.array([float(r[name]) for r in rows])
              for name in ("cycles", "dissipation", "worn_volume", "max_wear_depth")}
    checks(np.max(np.abs(torque)) < t_slip,
           f"the service torque ±{amplitude:.6g} N·mm stays below the slip torque {t_slip:.6g} N·mm")

    def loop(cycle: int) -> np.ndarray:
        rows = np.flatnonzero(service & (history["cycle"] == cycle))
        return np.concatenate([[rows[0] - 1], rows])

    simulated = sorted({int(c) for c in history["cycle"][service]})
    last = simulated[-1]
    energy_rows = []
    for cycle in sorted({simulated[0], simulated[1], last}):
        rows = loop(cycle)
        area = float(np.trapezoid(torque[rows], twist[rows]))
        change = {k: float(history[k][rows[-1]] - history[k][rows[0]])
                  for k in ("external_work", "stored_energy", "dissipation")}
        friction = float(cycles["dissipation"][simulated.index(cycle)])
        energy_rows.append([cycle, int(history["cycles"][rows[-1]]), area, change["external_work"],
                            change["stored_energy"], change["dissipation"], friction])
        checks(abs(area - change["external_work"]) <= 1e-2 * abs(change["external_work"]),
               f"simulated cycle {cycle}: loop area ∮ T dφ {area:.6g} N·mm = the cycle's external work "
               f"{change['external_work']:.6g} N·mm (history.csv, 1 %: the head's twist is the torque's "
               f"work-conjugate while the head turns as a whole, and the trapezoidal rule on 12 increments)")

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
    energy = table(["simulated cycle", "cycle", "∮ T dφ", "external work", "Δ stored energy", "Δ dissipation",
                    "friction dissipation (cycles.csv)"], energy_rows)
    return (f"Reversed torque ±{amplitude / 1e3:.4g} N·m ({amplitude / t_slip:.0%} of the slip torque), "
            f"{int(cycles['cycles'][-1])} cycles in {len(simulated)} simulated ones. Dissipation per cycle "
            f"{float(cycles['dissipation'][0]):.4g} N·mm in the first cycle, {float(cycles['dissipation'][-1]):.4g} N·mm in the last; "
            f"worn volume {float(cycles['worn_volume'][-1]):.4g} mm³, largest wear depth "
            f"{float(cycles['max_wear_depth'][-1]) * 1e3:.3g} µm.\n\n"
            f"Energy of a cycle (N·mm; history.csv from the frame before the cycle to its last): the loop's "
            f"area is the torque's work, and the cycle dissipates more than that: the stored energy falls "
            f"in every cycle, the seating's elastic energy released as the cone's ends slip (each cycle "
            f"loosens the seat a little; with wear, the worn surfaces release more).\n\n" + energy)


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
                                {"step[2].cycles": 1000, "step[2].cycles_per_jump": 500}, size=2.0)
    run_cases([(twist_case, out / "twist"), (fretting_case, out / "fretting")])
    checks = Checks()
    twist = twist_run(out / "twist", tomllib.loads(twist_case.read_text()), out, checks)
    fretting = fretting_run(out / "fretting", tomllib.loads(fretting_case.read_text()), out, twist["t_slip"],
                            checks)
    write_report(out / "REPORT.md", "Torque on a tapered joint", [
        ("What was run", f"`examples/taper_torque/taper_torque.toml`{' (quick: mesh size 2)' if args.quick else ''}: "
                         f"the cone seated by 10 MPa on the shaft's head, the load removed, then the head "
                         f"turned (`twist/`); `taper_fretting.toml`: seated and released the same way, then a "
                         f"reversed torque with Archard wear (`fretting/`). Open `results.pvd` of either in "
                         f"ParaView."),
        ("Slip torque", f"The torque peaks at {twist['t_slip'] / 1e3:.5g} N·m (φ = {twist['rotation'] * 1e3:.3g} mrad), "
                        f"in the first frame in which the whole cone slips: the slip torque. The friction "
                        f"torque of the frame's own pressure is ∫ μ|p| r dA = {twist['t_mu'] / 1e3:.5g} N·m; the "
                        f"slip torque is {twist['t_slip'] / twist['t_mu']:.4f} of it, because part of each "
                        f"point's friction still holds the cone in its seat against the wedge of the pressure "
                        f"(a uniform pressure on a thin cone would leave √(1 − tan²γ/μ²) = {twist['wedge']:.4f} "
                        f"of it for the torque). On the friction circle, ∫ √((μp)² − τ²) r dA = "
                        f"{twist['t_circle'] / 1e3:.5g} N·m from the contact CSV's pressure and meridional shear.\n\n"
                        f"Past the peak the slip has an axial part: the cone walks out of its seat as it turns, "
                        f"the contact's normal force falls from {twist['normal'][0] / 1e3:.4g} kN to "
                        f"{twist['normal'][1] / 1e3:.4g} kN and the torque to {twist['last'] / 1e3:.4g} N·m at "
                        f"φ = {twist['last_rotation'] * 1e3:.3g} mrad: a self-locking taper loosened by torque."),
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
