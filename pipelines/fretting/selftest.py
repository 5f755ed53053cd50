#!/usr/bin/env python3
"""Self-test of the fretting scripts on a synthetic output folder (in a temporary folder; not
results of asperity): check_fretting.py must pass the consistent files and catch each planted
inconsistency, plot_hysteresis.py and report.py must draw and report what the files hold and
say what is missing.

Usage: selftest.py      (exit status 1 if a test fails)

The synthetic run has the fixed formats of issue 14: a press-in step of 4 frames and a cyclic
step of 4 simulated cycles (ΔN = 25) of 4 frames, one contact `cone` on the tapered joint's
cone, wear profiles growing at both ends, and energy records that balance to 1e-7.
"""
from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import re
import shutil
import sys
import tempfile
import tomllib
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
CASE = HERE.parent.parent / "examples" / "fretting" / "tapered_fretting.toml"  # the gallery's case
sys.path.insert(0, str(HERE.parent))
from check_fretting import check_run  # noqa: E402
from fretting_data import (CYCLES_COLUMNS, ENERGY_TERMS, HYSTERESIS_COLUMNS, POINT_LOOPS_COLUMNS,  # noqa: E402
                           WEAR_COLUMNS, OutputError)
from report import write  # noqa: E402

PRESS, INCREMENTS, CYCLES, JUMP = 4, 4, 4, 25


def done(c: int) -> int:
    """Cycles completed after simulated cycle c: the first stands for itself, each later one
    for JUMP cycles."""
    return 1 + (c - 1) * JUMP
F0, STIFFNESS = 18000.0, 2.0e6  # N, N/mm: the synthetic joint's tangential force and stiffness


def _write_csv(path: Path, header: list[str], rows: list[list]) -> None:
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(header)
        writer.writerows(rows)


def _energy(external: float, friction: float, wear: float) -> dict:
    record = {"external_work": external * (1 + 1e-7), "elastic_energy": 0.8 * external - friction - wear,
              "interface_energy": 0.2 * external, "plastic_dissipation": 0.0, "friction_dissipation": friction,
              "wear_work": wear, "numerical_dissipation": 0.0}
    record["imbalance"] = record["external_work"] - sum(record[t] for t in ENERGY_TERMS)
    return record


def synthetic_run(out: Path) -> None:
    """Writes a consistent synthetic output folder."""
    out.mkdir(parents=True)
    case = (CASE).read_text()
    case = case.replace("increments = 10", f"increments = {PRESS}", 1)  # the press-in step
    case = re.sub(r"(?m)^cycles_per_jump = \d+$", f"cycles_per_jump = {JUMP}", case, count=1)
    case = case.replace("cycles = 1000000", f"cycles = {done(CYCLES)}").replace("increments = 10",
                                                                              f"increments = {INCREMENTS}")
    (out / "run.json").write_text(json.dumps({"case": case, "case_file": "synthetic.toml", "host": "test", "threads": 1,
                                              "start": "2026-01-01T00:00:00Z", "end": "2026-01-01T00:00:05Z"}))
    frames = [[i, 1, 1, 1, i / PRESS, F0 * i / PRESS, 5 * F0 * i / PRESS, F0 * i / PRESS / STIFFNESS]
              for i in range(1, PRESS + 1)]
    for c in range(1, CYCLES + 1):
        width = 1e-12 * (1.0 - 0.05 * (c - 1))  # the loop narrows as the contact wears in
        for i in range(1, INCREMENTS + 1):
            t = i / INCREMENTS
            force = F0 * (1.0 - 0.5 * min(2 * t, 2 - 2 * t))
            opening = width * (F0 - force) * (force - 0.5 * F0) * (1 if t <= 0.5 else -1)
            frames.append([len(frames) + 1, 2, c, done(c), t, force, 5 * force, force / STIFFNESS + opening])
    _write_csv(out / "hysteresis_cone.csv", HYSTERESIS_COLUMNS, frames)
    traced = tomllib.loads(case)["contact"][0].get("hysteresis_points", [])
    _write_csv(out / "point_loops_cone.csv", POINT_LOOPS_COLUMNS,
               [[*f[:5], k, x + 0.01, y, 0.2 * f[5] / F0, -f[6] / F0, f[7], 0.5 * f[7]]
                for f in frames for k, (x, y) in enumerate(traced, start=1)])
    s = np.linspace(0.0, 40.0 * math.hypot(1.0, 0.2), 9)
    x = 16.0 + 0.2 * s / math.hypot(1.0, 0.2)
    wear_rows, cycle_rows = [], []
    for c in range(1, CYCLES + 1):
        depth = 1e-5 * c * (np.exp(-s / 3) + np.exp(-(s[-1] - s) / 3))
        wear_rows += [[2, done(c), s[k], x[k], s[k] / math.hypot(1.0, 0.2), 0.7 * depth[k], 0.3 * depth[k], depth[k]]
                      for k in range(len(s))]
        settling = 0.0 if c == 1 else 0.2  # the re-equilibrium after a jump
        cycle_rows.append([2, c, done(c), "cone", 5.0 * (1 - 0.05 * (c - 1)), settling,
                           np.trapezoid(2 * math.pi * x * depth, s), depth.max(), 0.0 if c == 1 else 0.3])
    _write_csv(out / "wear_cone.csv", WEAR_COLUMNS, wear_rows)
    _write_csv(out / "cycles.csv", CYCLES_COLUMNS, cycle_rows)
    friction = sum(r[4] + r[5] for r in cycle_rows)
    steps = [dict(_energy(1000.0, 3.0, 0.0), name="press_in"), dict(_energy(1000.0, friction, 0.04), name="service")]
    total = {k: steps[0][k] + steps[1][k] for k in steps[0] if k != "name"}
    per_cycle = [dict(steps[0], analysis_step=1, cycle=1, cycles=1)]  # the press-in step counts as one cycle
    per_cycle += [dict(_energy(3 * r[4], r[4] + r[5], 0.01), analysis_step=2, cycle=r[1], cycles=r[2])
                  for r in cycle_rows]
    (out / "summary.json").write_text(json.dumps({
        "status": "converged", "steps": [{"step": f[0]} for f in frames],
        "totals": {"steps": len(frames), "increments": len(frames), "cutbacks": 0, "iterations": 3 * len(frames)},
        "seconds": {"total": 1.0}, "energy": {"total": total, "steps": steps, "cycles": per_cycle}}))
    history = [[0, 0.0, 0.0, 0.0]] + [[f[0], float(f[0]), -f[6], f[5]] for f in frames]  # compression negative, as asperity writes it
    _write_csv(out / "history.csv", ["step", "time", "cone_normal_force", "cone_tangential_force"], history)
    (out / "results.pvd").write_text('<VTKFile type="Collection"><Collection>' + "".join(
        f'<DataSet timestep="{f[0]}" part="0" file="frame_{f[0]:04d}.vtm"/>' for f in frames) + "</Collection></VTKFile>")


def _edit_csv(path: Path, row: int, column: str, factor: float) -> None:
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    i = rows[0].index(column)
    rows[row][i] = repr(float(rows[row][i]) * factor)
    _write_csv(path, rows[0], rows[1:])


def _edit_energy(out: Path, record: str, field: str, delta: float, keep_balance: bool) -> None:
    summary = json.loads((out / "summary.json").read_text())
    r = summary["energy"]["cycles"][2] if record == "cycle" else summary["energy"]["total"]
    r[field] += delta
    if keep_balance:  # a consistent record, inconsistent with cycles.csv
        r["imbalance"] += delta if field == "external_work" else -delta
    (out / "summary.json").write_text(json.dumps(summary))


def _drop_last_cycle_record(out: Path) -> None:
    summary = json.loads((out / "summary.json").read_text())
    summary["energy"]["cycles"].pop()
    (out / "summary.json").write_text(json.dumps(summary))


# Planted inconsistencies and a word of the check that must catch each.
MUTATIONS = {
    "a hysteresis frame missing": (lambda o: _write_csv(o / "hysteresis_cone.csv", HYSTERESIS_COLUMNS,
                                                        list(csv.reader(open(o / "hysteresis_cone.csv")))[1:-1]),
                                   "one per frame"),
    "a hysteresis force off history.csv": (lambda o: _edit_csv(o / "hysteresis_cone.csv", 3, "tangential_force", 1.001),
                                           "tangential_force equals"),
    "a cycle row missing": (lambda o: _write_csv(o / "cycles.csv", CYCLES_COLUMNS,
                                                 list(csv.reader(open(o / "cycles.csv")))[1:-1]), "simulated cycles ×"),
    "worn volume off the profile": (lambda o: _edit_csv(o / "cycles.csv", 2, "worn_volume", 1.5), "∫ wear_depth dA"),
    "a traced point's row missing": (lambda o: _write_csv(o / "point_loops_cone.csv", POINT_LOOPS_COLUMNS,
                                                          list(csv.reader(open(o / "point_loops_cone.csv")))[1:-1]),
                                     "one per frame and point"),
    "a jump beyond its limit": (lambda o: _edit_csv(o / "cycles.csv", 3, "jump_limit_share", 4.0),
                                "jump_limit_share within [0, 1]"),
    "a traced point moving": (lambda o: _edit_csv(o / "point_loops_cone.csv", 4, "x", 1.01), "keeps its position"),
    "wear depth healing": (lambda o: _edit_csv(o / "wear_cone.csv", 30, "wear_depth", 0.5), "no point's depth decreased"),
    "per-cycle friction off cycles.csv": (lambda o: _edit_energy(o, "cycle", "friction_dissipation", 0.05, True),
                                          "Σ cycles.csv dissipation"),
    "imbalance not the difference": (lambda o: _edit_energy(o, "total", "wear_work", 1.0, False),
                                     "imbalance = external work"),
    "an energy cycle record missing": (_drop_last_cycle_record, "one energy record per simulated cycle"),
    "large total imbalance": (lambda o: _edit_energy(o, "total", "external_work", 10.0, True), "total imbalance"),
}


def quiet(function, *args):
    """Runs function(*args) with its printing captured."""
    with contextlib.redirect_stdout(io.StringIO()):
        return function(*args)


def main() -> None:
    failures = []

    def expect(ok: bool, what: str) -> None:
        print(f"{'ok    ' if ok else 'FAILED'} {what}")
        if not ok:
            failures.append(what)

    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / "run"
        synthetic_run(base)
        found = quiet(check_run, base, 1e-3)
        expect(not found, f"consistent synthetic output passes check_fretting ({found or 'no failure'})")
        for name, (mutate, word) in MUTATIONS.items():
            out = Path(tmp) / name.replace(" ", "_")
            shutil.copytree(base, out)
            mutate(out)
            try:
                found = quiet(check_run, out, 1e-3)
            except OutputError as error:
                found = [str(error)]
            expect(any(word in f for f in found), f"check_fretting catches: {name} ({found})")
        report = quiet(write, base).read_text()
        expect("fell from 5 N·mm in the first simulated cycle to 4.25 N·mm in the last (-15.0 %)" in report,
               "report.py states the fall of the dissipation per cycle computed from cycles.csv")
        expect("largest wear depth 0.04 µm" in report, "report.py states the largest wear depth of the last profile")
        expect(all((base / f).is_file() for f in ("hysteresis_cone.png", "cycles.png", "wear_cone.png",
                                                   "point_loops_cone.png")),
               "the figures are drawn")
        pressed = Path(tmp) / "press_in_row"
        shutil.copytree(base, pressed)
        rows = list(csv.reader(open(pressed / "cycles.csv")))[1:]
        _write_csv(pressed / "cycles.csv", CYCLES_COLUMNS, [[1, 1, 1, "cone", 3.0, 0.0, 0.0, 0.0, 0.0], *rows])
        found = quiet(check_run, pressed, 1e-3)
        report = quiet(write, pressed).read_text()
        expect(not found and "fell from 5 N·mm in the first simulated cycle" in report,
               f"a step without cycles written as a cycle of cycles.csv passes the check and stays out of the "
               f"per-cycle table ({found or 'no failure'})")
        bare = Path(tmp) / "bare"
        shutil.copytree(base, bare)
        for f in ("cycles.csv", "wear_cone.csv"):
            (bare / f).unlink()
        report = quiet(write, bare).read_text()
        expect("`cycles.csv` is missing although the case has cyclic steps" in report
               and "`wear_cone.csv` is missing although contact `cone` has wear" in report,
               "report.py says which expected files are missing")
    if failures:
        sys.exit(f"selftest.py: {len(failures)} failed")
    print("selftest.py: all passed")


if __name__ == "__main__":
    main()
