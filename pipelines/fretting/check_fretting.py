#!/usr/bin/env python3
"""Consistency check of a cyclic (fretting) run's output: the files of issue 14 exist, have
their columns, and agree with the case, with each other and with history.csv.

Usage: check_fretting.py OUT                check the finished run in OUT
       check_fretting.py --quick OUT        run a tiny variant of tapered_fretting.toml (coarse
                                            mesh, 100 cycles in 4 jumps of 25) into OUT, then check

Checks (each printed; exit status 1 if one fails, 2 if a file is missing or malformed):
- the run converged; every contact has OUT/hysteresis_<contact>.csv with one row per frame
  (the frames of results.pvd), frames numbered 1..n, `increments` rows per simulated cycle,
  as many simulated cycles per cyclic step as the case asks (1 + ceil((cycles − 1) / ΔN)), the last
  frame of a cyclic step at its `cycles`, and forces equal to history.csv's
  <contact>_tangential_force / _normal_force of the same frame;
- OUT/cycles.csv: one row per simulated cycle and contact, cycles as in the hysteresis,
  dissipation and settling_dissipation >= 0, jump_limit_share within [0, 1], worn volume and largest depth >= 0 and never decreasing (zero without wear);
- OUT/wear_<contact>.csv for each wearing contact: one profile per jump at the cycles of
  cycles.csv, wear_depth = wear_a + wear_b, depths never decreasing from one jump to the next,
  and the worn volume of cycles.csv equal to the integral of the profile (10 %: the profile is
  nodal, the volume integrated at the interface's points);
- OUT/point_loops_<contact>.csv for each contact with `hysteresis_points`: one row per frame
  and traced point, in frame order, each point at a fixed position within one element length
  of the point asked for, the frame columns as in the hysteresis;
- summary.json's `energy`: every record's imbalance equals external work minus its terms, the
  steps (each holding what happened in it) add up to the total, one cycle record per simulated
  cycle and per step without cycles (README, summary.json), the friction dissipation of each
  cycle is the sum of cycles.csv's dissipation and settling_dissipation over the contacts
  (1e-6), and the total imbalance within
  --energy-tolerance (default 1e-3) of the external work: the work of the out-of-balance forces
  that the solver's residual tolerance (5e-4 by default) leaves.
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
CASE = HERE.parent.parent / "examples" / "fretting" / "tapered_fretting.toml"  # the gallery's case
sys.path.insert(0, str(HERE.parent))
from asperity_tools import read_csv, run_cases, variant  # noqa: E402
from fretting_data import (CYCLES_COLUMNS, ENERGY_TERMS, HYSTERESIS_COLUMNS, POINT_LOOPS_COLUMNS, WEAR_COLUMNS,  # noqa: E402
                           OutputError, contact_name, contact_rows, cyclic_steps, imbalance, read_case, read_json,
                           read_table, simulated_cycles, wear_profiles)

ROUND_OFF = 1e-9  # relative: values that are the same number written twice (CSV and JSON, ~16 digits)


class Checks:
    """Collects the outcome of each check."""

    def __init__(self) -> None:
        self.failures: list[str] = []

    def __call__(self, ok: bool, what: str) -> bool:
        print(f"{'ok    ' if ok else 'FAILED'} {what}")
        if not ok:
            self.failures.append(what)
        return ok


def close(a, b, rel: float, scale: float = 0.0) -> bool:
    """|a − b| ≤ rel × max(|a|, |b|, scale), elementwise for arrays."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return bool(np.all(np.abs(a - b) <= rel * np.maximum(np.maximum(np.abs(a), np.abs(b)), scale)))


def frame_count(out: Path) -> int:
    """The frames of the run: the converged increments history.csv lists after the unloaded
    state (results.pvd lists fewer in a cyclic step with `[output] cycle_frames = "ends"`)."""
    path = out / "history.csv"
    if not path.is_file():
        raise OutputError(f"{path}: missing")
    return len(path.read_text().splitlines()) - 2


def check_hysteresis(out: Path, case: dict, contact: str, frames: int, history: dict, check: Checks) -> dict:
    h = read_table(out / f"hysteresis_{contact}.csv", HYSTERESIS_COLUMNS)
    name = f"hysteresis_{contact}.csv"
    check(len(h["frame"]) == frames, f"{name}: {len(h['frame'])} rows, one per frame ({frames} in history.csv)")
    check(np.array_equal(h["frame"], np.arange(1, len(h["frame"]) + 1)), f"{name}: frames numbered 1..n")
    step, cycle = h["analysis_step"].astype(int), h["cycle"].astype(int)
    check(bool(np.all(np.diff(step) >= 0)), f"{name}: analysis steps in order")
    check(bool(np.all((h["step_time"] >= 0) & (h["step_time"] <= 1))), f"{name}: step_time within [0, 1]")
    wear = any("wear" in c for c in case.get("contact", []))
    for k, s in cyclic_steps(case).items():
        rows = step == k
        expected = simulated_cycles(s, wear)
        cycles_seen = np.unique(cycle[rows])
        check(np.array_equal(cycles_seen, np.arange(1, expected + 1)),
              f"{name}: step {k} has simulated cycles 1..{expected} (1 + ceil((cycles − 1) / ΔN)); found {len(cycles_seen)}")
        per_cycle = [int(np.sum(rows & (cycle == c))) for c in cycles_seen]
        check(all(n == s.get("increments", 1) for n in per_cycle),
              f"{name}: step {k}: {s.get('increments', 1)} frames per simulated cycle (found {sorted(set(per_cycle))})")
        if rows.any():
            check(bool(np.all(np.diff(h["cycles"][rows]) >= 0)), f"{name}: step {k}: `cycles` never decreases")
            check(h["cycles"][rows][-1] == s["cycles"],
                  f"{name}: step {k} ends at cycles = {s['cycles']} (found {h['cycles'][rows][-1]:.0f})")
    for column in ("tangential_force", "normal_force"):
        key = f"{contact}_{column}"
        if key in history and len(history[key]) == len(h[column]):
            # hysteresis: ∫|p_N| dA (a magnitude); history.csv: the signed resultant.
            theirs = np.abs(history[key]) if column == "normal_force" else history[key]
            check(close(h[column], theirs, ROUND_OFF, scale=np.abs(theirs).max()),
                  f"{name}: {column} equals history.csv's {key} in every frame (magnitude for the normal force)")
        else:
            check(False, f"{name}: history.csv has a `{key}` column with one row per frame")
    return h


def check_cycles(out: Path, case: dict, contacts: list[str], hysteresis: dict, check: Checks) -> dict:
    table = read_table(out / "cycles.csv", CYCLES_COLUMNS, text=("contact",))
    steps = cyclic_steps(case)
    wear = {n: "wear" in c for n, c in zip(contacts, case.get("contact", []))}
    any_wear = any(wear.values())
    expected = sum(simulated_cycles(s, any_wear) for s in steps.values())
    # A non-cyclic step may be written as one cycle of its own: accepted, but no other rows.
    extra = sorted({int(k) for k in table["analysis_step"]} - set(steps))
    n_extra = len(extra)
    check(len(table["contact"]) == (expected + n_extra) * len(contacts),
          f"cycles.csv: {len(table['contact'])} rows = {expected} simulated cycles"
          + (f" (+ {n_extra} non-cyclic steps {extra})" if n_extra else "") + f" × {len(contacts)} contacts")
    for contact in contacts:
        rows = contact_rows(table, contact)
        h = hysteresis[contact]
        ends = {}
        for k, c, n in zip(h["analysis_step"].astype(int), h["cycle"].astype(int), h["cycles"]):
            ends[(k, c)] = n  # the last frame of each cycle
        keys = list(zip(rows["analysis_step"].astype(int), rows["cycle"].astype(int)))
        check(keys == [key for key in ends if key[0] in steps or key[0] in extra],
              f"cycles.csv `{contact}`: one row per simulated cycle of the hysteresis, in order")
        check(all(ends.get(key) == n for key, n in zip(keys, rows["cycles"])),
              f"cycles.csv `{contact}`: `cycles` as at the end of the cycle in the hysteresis")
        scale = max(np.abs(rows["dissipation"]).max(initial=0.0), 1e-300)
        for column in ("dissipation", "settling_dissipation"):
            check(bool(np.all(rows[column] >= -ROUND_OFF * scale)), f"cycles.csv `{contact}`: {column} >= 0")
        share = rows["jump_limit_share"]
        check(bool(np.all((share >= 0) & (share <= 1))), f"cycles.csv `{contact}`: jump_limit_share within [0, 1]")
        for column in ("worn_volume", "max_wear_depth"):
            v = rows[column]
            if wear[contact]:
                check(bool(np.all(v >= 0) and np.all(np.diff(v) >= -ROUND_OFF * np.abs(v).max(initial=0.0))),
                      f"cycles.csv `{contact}`: {column} >= 0 and never decreasing")
            else:
                check(bool(np.all(v == 0)), f"cycles.csv `{contact}`: {column} = 0 (no wear)")
    return table


def area_weight(case: dict, x: np.ndarray) -> np.ndarray:
    """dA per unit arc length: 2πr in axisymmetry, the thickness in a plane analysis."""
    analysis = case["analysis"]
    if analysis["type"] == "axisymmetric":
        return 2 * math.pi * x
    return np.full_like(x, analysis.get("thickness", 1.0))


def check_wear(out: Path, case: dict, contact: str, cycles: dict, check: Checks) -> None:
    name = f"wear_{contact}.csv"
    profiles = wear_profiles(read_table(out / name, WEAR_COLUMNS))
    rows = contact_rows(cycles, contact)
    cyclic = np.isin(rows["analysis_step"].astype(int), list(cyclic_steps(case)))
    key = lambda steps, cycles: list(zip(steps.astype(int).tolist(), cycles.tolist()))  # noqa: E731
    jumps = key(rows["analysis_step"][cyclic], rows["cycles"][cyclic])
    written = [(int(p["analysis_step"][0]), n) for n, p in profiles]
    check(written == jumps or written == key(rows["analysis_step"], rows["cycles"]),
          f"{name}: one profile per jump (and perhaps per step without cycles), at the cycles of cycles.csv "
          f"({len(profiles)} profiles, {len(jumps)} jumps)")
    previous = None
    for n, p in profiles:
        depth = p["wear_depth"]
        check(close(depth, p["wear_a"] + p["wear_b"], ROUND_OFF, scale=depth.max(initial=0.0))
              and bool(np.all(p["wear_a"] >= 0) and np.all(p["wear_b"] >= 0)),
              f"{name} at N = {n:.0f}: wear_depth = wear_a + wear_b, both >= 0")
        check(bool(np.all(np.diff(p["s"]) >= 0)), f"{name} at N = {n:.0f}: s in order along side A")
        if previous is not None and len(previous) == len(depth):
            check(bool(np.all(depth >= previous - ROUND_OFF * depth.max(initial=0.0))),
                  f"{name} at N = {n:.0f}: no point's depth decreased since the previous jump")
        previous = depth
        same = (rows["cycles"] == n) & (rows["analysis_step"] == p["analysis_step"][0])
        volume = rows["worn_volume"][same]
        if len(volume):
            integral = float(np.trapezoid(depth * area_weight(case, p["x"]), p["s"]))
            check(close(integral, volume[-1], 0.10, scale=1e-300),
                  f"{name} at N = {n:.0f}: ∫ wear_depth dA = {integral:.4g} mm³ vs worn_volume {volume[-1]:.4g} mm³ (10 %)")


def check_energy(summary: dict, case: dict, hysteresis: dict, cycles: dict | None, tolerance: float,
                 check: Checks) -> None:
    energy = summary.get("energy")
    if not check(isinstance(energy, dict) and {"total", "steps", "cycles"} <= energy.keys(),
                 "summary.json has `energy` with `total`, `steps` and `cycles`"):
        return
    records = [energy["total"], *energy["steps"], *energy["cycles"]]
    fields = ["external_work", *ENERGY_TERMS, "imbalance"]
    if not check(all(all(isinstance(r.get(f), (int, float)) for f in fields) for r in records),
                 "every energy record has finite numbers for " + ", ".join(fields)):
        return
    check(all(close(r["imbalance"], imbalance(r), ROUND_OFF,
                    scale=max(abs(r["external_work"]), *(abs(r[t]) for t in ENERGY_TERMS))) for r in records),
          "every energy record: imbalance = external work − Σ terms")
    total = energy["total"]
    relative = abs(total["imbalance"]) / abs(total["external_work"]) if total["external_work"] else math.inf
    check(relative <= tolerance, f"total imbalance {relative:.2e} of the external work (<= {tolerance:g})")
    names = [s.get("name", f"step-{i}") for i, s in enumerate(case.get("step", []), start=1)]
    check([s.get("name") for s in energy["steps"]] == names, f"one energy record per step, named {names}")
    scale = max(abs(total["external_work"]), 1e-300)
    for f in fields:
        check(close(sum(s[f] for s in energy["steps"]), total[f], ROUND_OFF, scale),
              f"energy: the steps' {f} add up to the total")
    # One record per simulated load cycle, a step without cycles counting as one (README,
    # summary.json): the cycles of the frames, each with the `cycles` of its last frame.
    frames = next(iter(hysteresis.values()), None)
    if frames is not None:
        ends = {}
        for k, c, n in zip(frames["analysis_step"].astype(int), frames["cycle"].astype(int), frames["cycles"]):
            ends[(k, c)] = float(n)
        expected = [(k, c, n) for (k, c), n in ends.items()]
        found = [(r["analysis_step"], r["cycle"], r["cycles"]) for r in energy["cycles"]]
        check(found == expected, f"one energy record per simulated cycle and per step without cycles "
                                 f"({len(found)} records, {len(expected)} in the frames)")
    if cycles is None:
        return
    for r in energy["cycles"]:
        rows = (cycles["analysis_step"] == r["analysis_step"]) & (cycles["cycle"] == r["cycle"])
        if not rows.any():
            continue  # a step without cycles that cycles.csv leaves out
        # The energy record of a simulated cycle holds its re-equilibrium after the jump too.
        dissipated = float((cycles["dissipation"][rows] + cycles["settling_dissipation"][rows]).sum())
        if not check(close(r["friction_dissipation"], dissipated, 1e-6, scale=1e-300),
                     f"cycle {r['analysis_step']}.{r['cycle']}: friction dissipation {r['friction_dissipation']:.6g} "
                     f"N·mm = Σ cycles.csv dissipation + settling_dissipation {dissipated:.6g} N·mm"):
            break


def check_point_loops(out: Path, contact: str, wanted: list, hysteresis: dict, check: Checks) -> None:
    """The traced points' table of `contact` against the points the case asks for and the
    contact's hysteresis (the same frames)."""
    name = f"point_loops_{contact}.csv"
    t = read_table(out / name, POINT_LOOPS_COLUMNS)
    n, frames = len(wanted), len(hysteresis["frame"])
    check(len(t["frame"]) == n * frames, f"{name}: {len(t['frame'])} rows, one per frame and point ({n} × {frames})")
    if len(t["frame"]) != n * frames:
        return
    check(np.array_equal(t["point"], np.tile(np.arange(1, n + 1), frames)), f"{name}: points 1..{n} in every frame")
    for column in ("frame", "analysis_step", "cycle", "cycles", "step_time"):
        check(np.array_equal(t[column], np.repeat(hysteresis[column], n)),
              f"{name}: `{column}` as in hysteresis_{contact}.csv")
    for k, (x, y) in enumerate(wanted, start=1):
        rows = t["point"] == k
        fixed = np.all(t["x"][rows] == t["x"][rows][0]) and np.all(t["y"][rows] == t["y"][rows][0])
        distance = math.hypot(t["x"][rows][0] - x, t["y"][rows][0] - y)
        check(bool(fixed), f"{name}: point {k} keeps its position")
        print(f"       point {k}: asked ({x}, {y}), traced ({t['x'][rows][0]:.6g}, {t['y'][rows][0]:.6g}), "
              f"{distance:.3g} mm apart")


def check_run(out: Path, tolerance: float) -> list[str]:
    check = Checks()
    summary = read_json(out / "summary.json")
    case = read_case(out)
    check(summary.get("status") == "converged", f"the run converged (status {summary.get('status')!r})")
    frames = frame_count(out)
    history = read_csv(out / "history.csv")
    history = {k: v[1:] for k, v in history.items()}  # the unloaded state (step 0) is no frame
    check(len(history["step"]) == frames, f"history.csv: one row per frame after the unloaded state ({frames})")
    contacts = [contact_name(c) for c in case.get("contact", [])]
    hysteresis = {c: check_hysteresis(out, case, c, frames, history, check) for c in contacts}
    cycles = None
    if cyclic_steps(case):
        cycles = check_cycles(out, case, contacts, hysteresis, check)
        for contact, c in zip(contacts, case.get("contact", [])):
            if "wear" in c:
                check_wear(out, case, contact, cycles, check)
    for contact, c in zip(contacts, case.get("contact", [])):
        if c.get("hysteresis_points"):
            check_point_loops(out, contact, c["hysteresis_points"], hysteresis[contact], check)
    check_energy(summary, case, hysteresis, cycles, tolerance, check)
    return check.failures


QUICK_CHANGES = {"mesh.size": 4.0, "step[0].increments": 2, "step[1].cycles": 100, "step[1].increments": 4,
                 "step[1].cycles_per_jump": 25}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="output folder of the run (with --quick: where to run)")
    parser.add_argument("--quick", action="store_true",
                        help="first run a tiny variant of tapered_fretting.toml into OUT")
    parser.add_argument("--energy-tolerance", type=float, default=1e-3,
                        help="largest total imbalance relative to the external work (default 1e-3)")
    args = parser.parse_args()
    out = args.out.resolve()
    if args.quick:
        case = variant(CASE, out.parent / f"{out.name}.toml", QUICK_CHANGES)
        run_cases([(case, out)])
    try:
        failures = check_run(out, args.energy_tolerance)
    except OutputError as error:
        print(f"check_fretting.py: {error}", file=sys.stderr)
        sys.exit(2)
    if failures:
        sys.exit(f"check_fretting.py: {len(failures)} check(s) failed in {out}")
    print(f"check_fretting.py: {out}: all checks passed")


if __name__ == "__main__":
    main()
