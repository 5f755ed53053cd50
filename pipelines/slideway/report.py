"""The sliding slideway joint of examples/slideway: runs the case and draws what it shows.

    .venv/bin/python pipelines/slideway/report.py [--case CASE] [--out OUT] [--quick]

Figures (in OUT): `force_displacement.png`, the drive force against the drive's displacement
(the hysteresis loop of the joint: pre-sliding, then gross slip at mu_m times the clamping
force); `stick_zone.png`, the stick and slip lengths of the joint through the stroke and the
contact status along the joint at every frame (the stick zone shrinking from the driven rear
face forwards). `REPORT.md` lists the gross-slip force against mu_m N and the friction work of
each cycle three ways: the loop's area (the drive's work, trapezoidal), `cycles.csv` and the
energy balance of `summary.json`.

Checks (exit status 1 when one fails): the gross-slip force is mu_m times the joint's normal
force (Coulomb's law, to 1e-6), and in the second cycle, which starts where the first ended,
the loop's area equals the cycle's friction work of cycles.csv to 1 % (the difference is the
work of the clamping pressure on the carriage's tilt, which a closed cycle returns, and the
trapezoidal rule's error on the loop's corners). `--quick` runs a coarser mesh (make test).
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
from asperity_tools import (ROOT, read_csv, read_summary, run_cases, table, variant,  # noqa: E402
                            write_report)

PAIR = "slideway"
DRIVE = "carriage_rear"


def contact_status_map(out: Path, frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The contact status (0 open, 1 stick, 2 slip) along the joint (x, mm) at each frame."""
    rows = []
    for frame in frames:
        table_ = read_csv(out / f"contact_{PAIR}_{int(frame):04d}.csv")
        rows.append(table_["contact_status"])
    return table_["x"], np.array(rows)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", type=Path, default=ROOT / "examples" / "slideway" / "slideway.toml")
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "slideway")
    parser.add_argument("--quick", action="store_true", help="coarser mesh (make test)")
    args = parser.parse_args()
    out = args.out
    case_file = args.case
    if args.quick:
        case_file = variant(args.case, out / "quick.toml", size=2.0)
    (summary,) = run_cases([(case_file, out / "run")])
    run = out / "run"
    case = tomllib.loads(args.case.read_text())
    mu = next(c for c in case["contact"] if c["name"] == PAIR)["law"]["mu_m"]
    amplitude = next(s for s in case["support"] if s["group"] == DRIVE)["ux"]

    history = read_csv(run / "history.csv")
    stroke = history["analysis_step"] == 2
    u = history[f"factor_support_{DRIVE}"] * amplitude * 1e3  # um
    force = history["drive_force"]
    normal = -history[f"{PAIR}_normal_force"]
    cycles = [row for row in csv.DictReader(open(run / "cycles.csv")) if row["analysis_step"] == "2"]

    # The loop of each cycle: the drive's work over it, from the frame before its first one.
    areas = []
    for c in sorted({int(x) for x in history["cycle"][stroke]}):
        rows = np.flatnonzero(stroke & (history["cycle"] == c))
        rows = np.concatenate([[rows[0] - 1], rows])
        areas.append(np.trapezoid(force[rows], u[rows] * 1e-3))
    plateau = force[stroke][np.argmax(np.abs(force[stroke]))]
    gross_slip = mu * normal[stroke][np.argmax(np.abs(force[stroke]))]
    energy = next(s for s in summary["energy"]["steps"] if s["name"] == "stroke")

    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    for c, color in zip(sorted({int(x) for x in history["cycle"][stroke]}), ["C0", "C1"]):
        rows = np.flatnonzero(stroke & (history["cycle"] == c))
        rows = np.concatenate([[rows[0] - 1], rows])
        ax.plot(u[rows], force[rows] / 1e3, "-", color=color, label=f"cycle {c}")
    ax.axhline(gross_slip / 1e3, color="grey", ls=":", lw=1)
    ax.axhline(-gross_slip / 1e3, color="grey", ls=":", lw=1, label=r"$\pm\mu_m N$")
    ax.set_xlabel("drive displacement [µm]")
    ax.set_ylabel("drive force [kN]")
    ax.set_title("slideway: force against displacement (pre-sliding and gross slip)")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "force_displacement.png", dpi=130)
    plt.close(fig)

    frames = history["step"][stroke]
    x, status = contact_status_map(run, frames)
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(6.4, 6.4), sharex=True,
                                      gridspec_kw={"height_ratios": [1, 1.4]})
    # load_factor is the analysis time: the stroke step runs from 1 to 2, its cycles dividing it.
    time = (history["load_factor"][stroke] - 1.0) * len(areas)
    top.plot(time, history["stick_length"][stroke], label="stick")
    top.plot(time, history["slip_length"][stroke], label="slip")
    top.set_ylabel("length along the joint [mm]")
    top.legend()
    top.grid(alpha=0.3)
    colours = matplotlib.colors.ListedColormap(["white", "tab:green", "tab:red"])
    bottom.pcolormesh(time, x - x.min(), status.T, cmap=colours, vmin=-0.5, vmax=2.5, shading="nearest")
    bottom.set_ylabel("x from the driven rear face [mm]")
    bottom.set_xlabel("stroke [cycles]")
    bottom.set_title("contact status: green stick, red slip", fontsize=10)
    fig.tight_layout()
    fig.savefig(out / "stick_zone.png", dpi=130)
    plt.close(fig)

    checks = []
    ok_force = abs(abs(plateau) - gross_slip) <= 1e-6 * gross_slip
    checks.append(("gross-slip force = μ_m N", ok_force, f"{abs(plateau):.6g} N against {gross_slip:.6g} N"))
    second = float(cycles[-1]["dissipation"])
    ok_loop = len(areas) > 1 and abs(areas[-1] - second) <= 1e-2 * second
    checks.append(("loop area = friction work (cycle 2)", ok_loop,
                   f"{areas[-1]:.6g} N·mm against {second:.6g} N·mm"))
    rows = [[int(c["cycle"]), areas[i], float(c["dissipation"])] for i, c in enumerate(cycles)]
    write_report(out / "REPORT.md", "Sliding slideway joint", [
        ("What was run", f"`{args.case.relative_to(ROOT) if args.case.is_relative_to(ROOT) else args.case}`"
                         f"{' (quick: mesh size 2)' if args.quick else ''}: the carriage clamped by "
                         f"{normal[stroke][0] / 1e3:.4g} kN, then its rear face driven ±{amplitude * 1e3:.3g} µm "
                         f"for {len(areas)} cycles; results in `run/` (open `results.pvd` in ParaView)."),
        ("Gross slip", f"Largest drive force {abs(plateau):.6g} N; μ_m N = {mu} × {normal[stroke][0]:.6g} N = "
                       f"{gross_slip:.6g} N."),
        ("Friction work per cycle (N·mm)",
         table(["cycle", "loop area ∮F du", "cycles.csv dissipation"], rows)
         + f"\n\nStroke step in `summary.json`: friction dissipation {energy['friction_dissipation']:.6g} N·mm, "
           f"external work {energy['external_work']:.6g} N·mm (the first cycle starts from the clamped, "
           f"unslipped state, so its loop is not closed)."),
        ("Figures", "`force_displacement.png`, `stick_zone.png`"),
        ("Checks", "\n".join(f"- {'ok' if ok else 'FAILED'}: {name}: {detail}" for name, ok, detail in checks)),
    ])
    print((out / "REPORT.md").read_text())
    return 0 if all(ok for _, ok, _ in checks) else 1


if __name__ == "__main__":
    sys.exit(main())
