#!/usr/bin/env python3
"""REPORT.md of `make cyclic_press_fit`: the press fit under cyclic external pressure with
isotropic and with kinematic hardening side by side (issue 27).

Reads, for each of the runs OUT/isotropic and OUT/kinematic, history.csv (the loop: the
external pressure against the contact's normal force over the cyclic step), cycles.csv (per
cycle and body the plastic dissipation, the ratcheting strain and the plastic strain
increment) and summary.json (the shakedown verdicts with their threshold), draws
loops.png and cycles.png and writes REPORT.md.

Usage: report.py OUT
"""

import csv
import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

RUNS = ("isotropic", "kinematic")
BODY = "hub"


def table(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def main(out):
    out = Path(out)
    runs = {}
    for name in RUNS:
        folder = out / name
        runs[name] = {
            "history": table(folder / "history.csv"),
            "cycles": table(folder / "cycles.csv"),
            "summary": json.loads((folder / "summary.json").read_text()),
        }

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax, name in zip(axes, RUNS):
        rows = [r for r in runs[name]["history"] if r["analysis_step"] == "2"]
        ax.plot([float(r["factor_load_hub_outer"]) for r in rows],
                [float(r["fit_normal_force"]) / 1e3 for r in rows], lw=1)
        ax.set_title(f"{name} hardening")
        ax.set_xlabel("external pressure / 350 MPa")
    axes[0].set_ylabel("contact normal force (kN, total over the circle)")
    fig.tight_layout()
    fig.savefig(out / "loops.png", dpi=120)

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for name in RUNS:
        rows = [r for r in runs[name]["cycles"] if r["analysis_step"] == "2"]
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

    lines = [
        "# Cyclic press fit: isotropic against kinematic hardening",
        "",
        "A compliant shaft pressed into a steel hub (radial interference 0.1 mm), then 10 cycles",
        "of external pressure 0 → 350 MPa → 0 on the hub. Same elasticity, initial yield stress",
        "and initial hardening slope; `isotropic.toml` hardens by growing the yield surface",
        "(Voce + linear), `kinematic.toml` by moving it (Chaboche: one Armstrong–Frederick and",
        "one Prager backstress).",
        "",
        "![loops](loops.png)",
        "",
        "![per cycle](cycles.png)",
        "",
        "## Shakedown verdicts (summary.json)",
        "",
        "| hardening | body | verdict | last cycle: plastic dissipation (N mm) | ratchet strain | "
        "plastic strain increment | threshold |",
        "|---|---|---|---|---|---|---|",
    ]
    for name in RUNS:
        for v in runs[name]["summary"]["shakedown"]:
            c = v["last_cycle"]
            lines.append(
                f"| {name} | {v['body']} | {v['shakedown']} | {c['plastic_dissipation']:.4g} | "
                f"{c['ratchet_strain']:.3g} | {c['plastic_strain_increment']:.3g} | "
                f"{v['threshold']:g} (ratchet also > {v['ratchet_share']:g} of the increment) |"
            )
    lines += [
        "",
        "With isotropic hardening the first cycles enlarge the yield surface until the pressure",
        "cycle stays inside it (elastic shakedown); with kinematic hardening the surface moves",
        "with the stress, reverse yielding repeats in every cycle (Bauschinger effect) and the",
        "hub dissipates energy cycle after cycle (alternating plasticity, plastic shakedown).",
        "",
    ]
    (out / "REPORT.md").write_text("\n".join(lines))
    print(f"report: {out / 'REPORT.md'}")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
