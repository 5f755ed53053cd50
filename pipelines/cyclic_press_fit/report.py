#!/usr/bin/env python3
"""REPORT.md of `make cyclic_press_fit`: the press fit under cyclic external pressure with
isotropic and with kinematic hardening side by side (issue 27).

Reads, for each of the runs OUT/isotropic and OUT/kinematic:
- history.csv: the global loop (the external pressure against the contact's normal force);
- the hub's VTU file of each frame of the series results.pvd (every frame of the press step and of the
  first and last cycles, the end of the others): the local loop, hoop stress against hoop
  total strain, at the hub's most strained point (the largest equivalent plastic strain of
  the kinematic run's last frame; the same point in both runs, the meshes being equal);
- cycles.csv: per cycle and body the plastic dissipation, the ratcheting strain, the plastic
  strain increment and the verdict the step would get if it ended with that cycle;
- summary.json: the shakedown verdicts, which the report quotes as they are.
Draws loops.png, local_loops.png and cycles.png and writes REPORT.md.

Usage: report.py OUT
"""

import csv
import json
import sys
from pathlib import Path

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pyvista as pv  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from asperity_tools import frame_parts, frames  # noqa: E402

RUNS = ("isotropic", "kinematic")
BODY = "hub"
CYCLIC_STEP = "2"
# VTK tensor order (xx, yy, zz, xy, yz, xz): in axisymmetry x = r, y = z, zz = θθ.
HOOP = 2


def table(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def hub_frames(folder):
    """(step, the hub's VTU file) of every frame the series lists, in order."""
    out = []
    for _, vtm in frames(folder):
        parts = dict(frame_parts(vtm)["bodies"])
        out.append((int(vtm.stem.removeprefix("frame_")), parts[BODY]))
    return out


def local_history(folder, point=None):
    """Per frame: step, hoop stress, hoop strain, equivalent plastic strain at `point` (a
    position; default the hub point of largest equivalent plastic strain at the last frame).
    Returns the arrays and the point."""
    series = hub_frames(folder)
    if point is None:
        last = pv.read(series[-1][1])
        point = last.points[np.argmax(last.point_data["equivalent_plastic_strain"])]
    rows = []
    for step, path in series:
        grid = pv.read(path)
        p = np.argmin(np.linalg.norm(grid.points - point, axis=1))
        rows.append((step, grid.point_data["stress"][p, HOOP], grid.point_data["strain"][p, HOOP],
                     grid.point_data["equivalent_plastic_strain"][p]))
    return np.array(rows), point


def judged_by_last_cycle(run):
    """The sentence on what the last cycle alone would have said after each number of cycles
    (each cycle's reading, by the thresholds summary.json states)."""
    verdict = run["summary"]["shakedown"][0]
    threshold, share = verdict["threshold"], verdict["ratchet_share"]

    def reads(r):
        ratchet = float(r[f"{BODY}_ratchet_strain"])
        flow = float(r[f"{BODY}_plastic_strain_increment"])
        if ratchet > max(threshold, share * flow):
            return "ratcheting"
        return "plastic shakedown" if flow > threshold else "elastic shakedown"

    readings = [(int(r["cycle"]), reads(r)) for r in run["cycles"]]
    changes = [(c, w) for i, (c, w) in enumerate(readings) if i == 0 or w != readings[i - 1][1]]
    spans = ", ".join(f"\"{w}\" from cycle {c}" for c, w in changes)
    settled = next((int(r["cycle"]) for r in run["cycles"]
                    if r[f"{BODY}_verdict"] != "not settled"
                    and all(q[f"{BODY}_verdict"] == r[f"{BODY}_verdict"] for q in run["cycles"]
                            if int(q["cycle"]) >= int(r["cycle"]))), None)
    text = (f"Judged by its last cycle alone, the kinematic hub's verdict would depend on where the "
            f"step stopped: its cycles read {spans} (the loop still closing, its net change falling "
            f"from cycle to cycle).")
    if settled is not None:
        text += (f" With the settling rule the verdict is the same from {settled} cycles on; the "
                 f"case runs {readings[-1][0]}.")
    else:
        text += " Its verdict has not settled within the simulated cycles: simulate more."
    return text


def main(out):
    out = Path(out)
    runs = {}
    for name in RUNS:
        folder = out / name
        runs[name] = {
            "history": table(folder / "history.csv"),
            "cycles": [r for r in table(folder / "cycles.csv") if r["analysis_step"] == CYCLIC_STEP],
            "summary": json.loads((folder / "summary.json").read_text()),
        }
    runs["kinematic"]["local"], point = local_history(out / "kinematic")
    runs["isotropic"]["local"], _ = local_history(out / "isotropic", point)

    # Global loops: the pressure against the contact's normal force.
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax, name in zip(axes, RUNS):
        rows = [r for r in runs[name]["history"] if r["analysis_step"] == CYCLIC_STEP]
        ax.plot([float(r["factor_load_hub_outer"]) for r in rows],
                [float(r["fit_normal_force"]) / 1e3 for r in rows], lw=1)
        ax.set_title(f"{name} hardening")
        ax.set_xlabel("external pressure / 350 MPa")
    axes[0].set_ylabel("contact normal force (kN, total over the circle)")
    fig.tight_layout()
    fig.savefig(out / "loops.png", dpi=120)

    # Local loops at the most strained point: the press, the first cycle and the last cycle
    # are complete in the series (every frame), the cycles between by their ends.
    history = {int(r["step"]): r for r in runs["kinematic"]["history"]}
    last_cycle = max(int(r["cycle"]) for r in history.values() if r["analysis_step"] == CYCLIC_STEP)
    fig, ax = plt.subplots(figsize=(7, 5))
    for name, colour in zip(RUNS, ("tab:blue", "tab:red")):
        local = runs[name]["local"]
        steps = local[:, 0].astype(int)
        in_last = np.array([history[s]["analysis_step"] == CYCLIC_STEP
                            and int(history[s]["cycle"]) == last_cycle for s in steps])
        start = np.flatnonzero(in_last)[0] - 1  # the last cycle starts where the one before ended
        ax.plot(local[:, 2] * 1e3, local[:, 1], ".-", color=colour, lw=0.8, ms=3, alpha=0.5,
                label=f"{name}: press fit and cycles 1 to {last_cycle - 1}")
        ax.plot(local[start:, 2] * 1e3, local[start:, 1], "-", color=colour, lw=2.2,
                label=f"{name}: cycle {last_cycle}")
        # The frames of the last cycle at which the point flowed (ε̄ᵖ grew since the frame
        # before): in both directions where the yield surface moves.
        flowing = start + 1 + np.flatnonzero(np.diff(local[start:, 3]) > 0.0)
        if flowing.size:
            ax.plot(local[flowing, 2] * 1e3, local[flowing, 1], "o", color=colour, ms=5,
                    label=f"{name}: flowing in cycle {last_cycle}")
    ax.set_xlabel("hoop strain ε_θθ (total, 10⁻³)")
    ax.set_ylabel("hoop stress σ_θθ (MPa)")
    ax.set_title(f"hub at r = {point[0]:.2f} mm, z = {point[1]:.2f} mm (largest ε̄ᵖ)")
    ax.axhline(0.0, color="k", lw=0.4)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "local_loops.png", dpi=120)

    # Per cycle.
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for name in RUNS:
        rows = runs[name]["cycles"]
        cycle = [int(r["cycle"]) for r in rows]
        axes[0].semilogy(cycle, [max(float(r[f"{BODY}_plastic_dissipation"]), 1e-12)
                                 for r in rows], "o-", label=name)
        axes[1].semilogy(cycle, [max(float(r[f"{BODY}_plastic_strain_increment"]), 1e-12)
                                 for r in rows], "o-", label=f"{name}: plastic strain increment")
        axes[1].semilogy(cycle, [max(float(r[f"{BODY}_ratchet_strain"]), 1e-12)
                                 for r in rows], "x--", label=f"{name}: ratchet strain")
    axes[0].set_ylabel("hub plastic dissipation per cycle (N mm)")
    axes[1].set_ylabel("strain per cycle (largest at a point)")
    for ax in axes:
        ax.set_xlabel("cycle")
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "cycles.png", dpi=120)

    # The local loop's numbers: stress range of the last cycle and the flow in its halves.
    def last_cycle_flow(name):
        local = runs[name]["local"]
        steps = local[:, 0].astype(int)
        cyc = [i for i, s in enumerate(steps) if history[s]["analysis_step"] == CYCLIC_STEP
               and int(history[s]["cycle"]) == last_cycle]
        i0, i1 = cyc[0] - 1, cyc[-1]
        peak = i0 + np.argmax([float(history[s]["factor_load_hub_outer"]) for s in steps[i0:i1 + 1]])
        p = local[:, 3]
        return (local[i0:i1 + 1, 1].max(), local[i0:i1 + 1, 1].min(), p[peak] - p[i0], p[i1] - p[peak])

    kinematic = runs["kinematic"]["summary"]
    n_cycles = next(s["cycles"] for s in kinematic["analysis_steps"]
                    if s["name"] == "cycling") if "analysis_steps" in kinematic else last_cycle
    lines = [
        "# Cyclic press fit: isotropic against kinematic hardening",
        "",
        f"A compliant shaft pressed into a steel hub (radial interference 0.1 mm), then {n_cycles}",
        "cycles of external pressure 0 → 350 MPa → 0 on the hub. Same elasticity, initial yield stress",
        "and initial hardening slope; `isotropic.toml` hardens by growing the yield surface",
        "(Voce + linear), `kinematic.toml` by moving it (Chaboche: one Armstrong–Frederick and",
        "one Prager backstress).",
        "",
        "## Global loops",
        "",
        "![loops](loops.png)",
        "",
        "## Local loops at the most strained point",
        "",
        f"Hoop stress against hoop total strain at the hub's point of largest equivalent plastic strain "
        f"(r = {point[0]:.2f} mm, z = {point[1]:.2f} mm, the bore; nodal values recovered from the "
        "integration points), both hardenings in one figure: thin, the press fit and the cycles before "
        "the last (complete for the first cycle, by their ends for the others); thick, the last cycle, "
        "with a dot where the point flowed (its ε̄ᵖ grew since the frame before).",
        "",
        "![local loops](local_loops.png)",
        "",
        "| hardening | last cycle: largest σ_θθ (MPa) | smallest σ_θθ (MPa) | ε̄ᵖ added while the pressure rises | while it falls |",
        "|---|---|---|---|---|",
    ]
    for name in RUNS:
        hi, lo, up, down = last_cycle_flow(name)
        lines.append(f"| {name} | {hi:.1f} | {lo:.1f} | {up:.3g} | {down:.3g} |")
    lines += [
        "",
        "The press fit yields the bore in hoop tension; each pressure pulse takes the hoop stress down "
        "and back. Where the yield surface only grows (isotropic) it grew enough in the press fit for "
        "the pulses to stay inside it; where it moved with the stress (kinematic) the reversed stress "
        "meets it early — the Bauschinger effect — so the bore yields again in every pulse, on the way "
        "down and on the way back, and the loop stays open (its area is the dissipation per cycle).",
        "",
        "![per cycle](cycles.png)",
        "",
        "## Shakedown verdicts (summary.json)",
        "",
        "| hardening | body | verdict | last cycle reads | cycles alike (needed) | last cycle: plastic dissipation (N mm) | ratchet strain | "
        "plastic strain increment | threshold |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name in RUNS:
        for v in runs[name]["summary"]["shakedown"]:
            c = v["last_cycle"]
            lines.append(
                f"| {name} | {v['body']} | **{v['shakedown']}** | {v['last_cycle_reads']} | "
                f"{v['cycles_alike']} ({v['settled_cycles']}) | {c['plastic_dissipation']:.4g} | "
                f"{c['ratchet_strain']:.3g} | {c['plastic_strain_increment']:.3g} | "
                f"{v['threshold']:g} (ratchet also > {v['ratchet_share']:g} of the increment) |"
            )
    lines += [
        "",
        "## The verdict against the number of simulated cycles",
        "",
        "A cycle reads as \"ratcheting\" while its net plastic strain change exceeds a tenth of its flow;",
        "a verdict is given once the last three cycles after the first read alike and the trend of that",
        "share does not cross the tenth within three more cycles, else \"not settled\"",
        "([plasticity](../../docs/guide/plasticity.md)). The hub's column `hub_verdict` of cycles.csv",
        "is the verdict the step would get had it ended with that cycle:",
        "",
        "| cycle | " + " | ".join(f"{name}: net change / flow | {name}: verdict if it ended here" for name in RUNS) + " |",
        "|---|" + "---|---|" * len(RUNS),
    ]
    by_cycle = {name: {int(r["cycle"]): r for r in runs[name]["cycles"]} for name in RUNS}
    for cycle in sorted(by_cycle["kinematic"]):
        cells = []
        for name in RUNS:
            r = by_cycle[name].get(cycle)
            if r is None:
                cells += ["", ""]
                continue
            flow = float(r[f"{BODY}_plastic_strain_increment"])
            share = float(r[f"{BODY}_ratchet_strain"]) / flow if flow > 0 else 0.0
            cells += [f"{share:.3f}" if flow > 0 else "no flow", r[f"{BODY}_verdict"]]
        lines.append(f"| {cycle} | " + " | ".join(cells) + " |")
    lines += [
        "",
    ]
    lines += [judged_by_last_cycle(runs["kinematic"]), ""]
    (out / "REPORT.md").write_text("\n".join(lines))
    print(f"report: {out / 'REPORT.md'}")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
