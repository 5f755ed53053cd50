"""Readers of a cyclic run's fretting output (README "Output"; issue 14's fixed formats), shared
by plot_hysteresis.py, report.py and check_fretting.py:

- `OUT/hysteresis_<contact>.csv`, one row per frame: frame, analysis_step, cycle, cycles,
  step_time, tangential_force (N), normal_force (N), relative_slip (mm);
- `OUT/cycles.csv`, one row per simulated cycle and contact: analysis_step, cycle, cycles,
  contact, dissipation (N mm), settling_dissipation (N mm, the re-equilibrium after the
  cycle's wear jump), worn_volume (mm^3), max_wear_depth (mm), jump_limit_share (largest
  share of the stability limit the jump added at a point);
- `OUT/point_loops_<contact>.csv` (contacts with `hysteresis_points`), one row per frame and
  traced point: frame, analysis_step, cycle, cycles, step_time, point (1-based), x, y,
  shear_stress, normal_stress (MPa), tangential_displacement, plastic_slip (mm);
- `OUT/wear_<contact>.csv`, the wear-depth profile after each jump: cycles, s (arc length
  along side A), x, y, wear_a, wear_b, wear_depth (mm);
- `OUT/summary.json` (its `energy`) and `OUT/run.json` (the case text as run).

Every reader checks the header and the numbers and raises `OutputError` naming the file, so a
wrong or damaged file gives one clear message instead of a traceback.
"""
from __future__ import annotations

import csv
import json
import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

HYSTERESIS_COLUMNS = ["frame", "analysis_step", "cycle", "cycles", "step_time", "tangential_force",
                      "normal_force", "relative_slip"]
CYCLES_COLUMNS = ["analysis_step", "cycle", "cycles", "contact", "dissipation", "settling_dissipation", "worn_volume",
                  "max_wear_depth", "jump_limit_share"]
WEAR_COLUMNS = ["analysis_step", "cycles", "s", "x", "y", "wear_a", "wear_b", "wear_depth"]
POINT_LOOPS_COLUMNS = ["frame", "analysis_step", "cycle", "cycles", "step_time", "point", "x", "y", "shear_stress",
                       "normal_stress", "tangential_displacement", "plastic_slip"]
# The terms of the energy balance (solver/energy.rs); imbalance = external_work - sum(TERMS).
ENERGY_TERMS = ["elastic_energy", "interface_energy", "plastic_dissipation", "friction_dissipation", "wear_work",
                "numerical_dissipation"]


class OutputError(Exception):
    """A missing, malformed or inconsistent output file."""


def read_table(path: Path, columns: list[str], text: tuple[str, ...] = ()) -> dict[str, np.ndarray]:
    """The CSV at `path` as columns; it must have exactly `columns` in that order; the `text`
    columns are kept as strings, the others must be finite numbers."""
    if not path.is_file():
        raise OutputError(f"{path}: missing")
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows or rows[0] != columns:
        raise OutputError(f"{path}: header {rows[0] if rows else '(empty file)'} is not {columns}")
    table: dict[str, list] = {c: [] for c in columns}
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != len(columns):
            raise OutputError(f"{path}, line {line}: {len(row)} values for {len(columns)} columns")
        for name, value in zip(columns, row):
            if name in text:
                table[name].append(value)
                continue
            try:
                number = float(value)
            except ValueError:
                raise OutputError(f"{path}, line {line}: `{name}` = {value!r} is not a number") from None
            if not math.isfinite(number):
                raise OutputError(f"{path}, line {line}: `{name}` = {value} is not finite")
            table[name].append(number)
    return {name: np.array(values, dtype=object if name in text else float) for name, values in table.items()}


def contact_files(out: Path, prefix: str) -> dict[str, Path]:
    """`OUT/<prefix>_<contact>.csv` by contact name, in name order."""
    return {p.stem[len(prefix) + 1:]: p for p in sorted(out.glob(f"{prefix}_*.csv"))}


def read_json(path: Path) -> dict:
    if not path.is_file():
        raise OutputError(f"{path}: missing")
    try:
        return json.loads(path.read_text())
    except json.JSONDecodeError as error:
        raise OutputError(f"{path}: not JSON ({error})") from None


def read_case(out: Path) -> dict:
    """The case as run: the case-file text that `run.json` records, parsed."""
    info = read_json(out / "run.json")
    try:
        return tomllib.loads(info["case"])
    except (KeyError, TypeError, tomllib.TOMLDecodeError) as error:
        raise OutputError(f"{out / 'run.json'}: no readable case text ({error})") from None


def cyclic_steps(case: dict) -> dict[int, dict]:
    """The cyclic `[[step]]`s of a case (those with `cycles`) by their 1-based number."""
    return {i: s for i, s in enumerate(case.get("step", []), start=1) if "cycles" in s}


def contact_name(contact: dict) -> str:
    """A `[[contact]]`'s name as the output files use it (README: `name`, else the curve, else
    "<side_a>-<side_b>")."""
    return contact.get("name") or contact.get("curve") or f"{contact['side_a']}-{contact['side_b']}"


def cycles_per_jump(step: dict, wear: bool) -> int:
    """ΔN of a cyclic step: its `cycles_per_jump`, else ceil(cycles / 20) when some contact
    wears, else 1 (every cycle simulated) — the case-file rule of issue 14."""
    if "cycles_per_jump" in step:
        return int(step["cycles_per_jump"])
    return math.ceil(step["cycles"] / 20) if wear else 1


def simulated_cycles(step: dict, wear: bool) -> int:
    """How many cycles of a cyclic step are simulated: the first stands for itself (the
    transient after the previous step), each later one for ΔN cycles, the last for what
    remains."""
    return 1 + math.ceil((step["cycles"] - 1) / cycles_per_jump(step, wear))


@dataclass
class Loop:
    """One simulated load cycle of a contact's hysteresis: its frames, closed by the frame
    before its first (where the cycle starts)."""
    analysis_step: int
    cycle: int
    cycles: float
    slip: np.ndarray
    force: np.ndarray


def loops(hysteresis: dict[str, np.ndarray], steps: set[int]) -> list[Loop]:
    """The hysteresis loops of the analysis `steps`, one per simulated cycle, in order."""
    step, cycle = hysteresis["analysis_step"].astype(int), hysteresis["cycle"].astype(int)
    result = []
    for k in sorted(steps):
        for c in np.unique(cycle[step == k]):
            rows = np.flatnonzero((step == k) & (cycle == c))
            # The loop starts where the previous frame left it (the end of the previous cycle
            # or step), so that a closed cycle draws a closed curve.
            rows = np.concatenate([[rows[0] - 1], rows]) if rows[0] > 0 else rows
            result.append(Loop(k, int(c), float(hysteresis["cycles"][rows[-1]]),
                               hysteresis["relative_slip"][rows], hysteresis["tangential_force"][rows]))
    return result


def point_tables(table: dict[str, np.ndarray]) -> list[dict[str, np.ndarray]]:
    """The rows of a point_loops_<contact>.csv per traced point (in point order), each shaped
    like a hysteresis table (`relative_slip` the point's u_T, `tangential_force` its p_T) so
    that `loops` cuts it into cycles."""
    result = []
    for k in np.unique(table["point"].astype(int)):
        rows = {name: values[table["point"] == k] for name, values in table.items()}
        rows["relative_slip"] = rows["tangential_displacement"]
        rows["tangential_force"] = rows["shear_stress"]
        result.append(rows)
    return result


def wear_profiles(wear: dict[str, np.ndarray]) -> list[tuple[float, dict[str, np.ndarray]]]:
    """The profiles of a wear_<contact>.csv, one per jump: consecutive rows of equal
    `analysis_step` and `cycles`."""
    cycles, steps = wear["cycles"], wear["analysis_step"]
    changed = (cycles[1:] != cycles[:-1]) | (steps[1:] != steps[:-1])
    starts = np.flatnonzero(np.concatenate([[True], changed]))
    ends = np.concatenate([starts[1:], [len(cycles)]])
    return [(float(cycles[a]), {name: values[a:b] for name, values in wear.items()}) for a, b in zip(starts, ends)]


def read_cycles(out: Path, steps: set[int]) -> dict[str, np.ndarray] | None:
    """The rows of OUT/cycles.csv that belong to the cyclic analysis `steps` (a step without
    cycles may be written as a cycle of its own, but it is no load cycle of the service), or
    None if the run wrote no cycles.csv."""
    if not (out / "cycles.csv").is_file():
        return None
    table = read_table(out / "cycles.csv", CYCLES_COLUMNS, text=("contact",))
    keep = np.isin(table["analysis_step"].astype(int), sorted(steps))
    return {name: values[keep] for name, values in table.items()}


def contact_rows(table: dict[str, np.ndarray], contact: str) -> dict[str, np.ndarray]:
    """The rows of cycles.csv that belong to `contact`."""
    keep = table["contact"] == contact
    return {name: values[keep] for name, values in table.items()}


def imbalance(energy: dict) -> float:
    """external_work − Σ terms, recomputed from an energy record's fields."""
    return energy["external_work"] - sum(energy[t] for t in ENERGY_TERMS)
