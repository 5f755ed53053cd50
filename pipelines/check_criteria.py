#!/usr/bin/env python3
"""Engineering convergence criteria against a tight-tolerance run, case by case.

Runs every shipped case twice with the same binary: with the default `[solver]` criteria and
with the relative-norm tolerances tightened to 1e-10 (`force_tolerance`,
`displacement_tolerance`, required on top of the defaults). Compares every column of
`history.csv` (reactions, contact forces, load factors; every step) and the displacement
field of the last output frame (all bodies): the relative difference of a column is its largest
difference over the steps divided by the largest magnitude of the column in the tight run.
A column is compared relative to its largest magnitude, but at least 1e-2 of the case's
largest force (reactions that vanish physically hold only solver noise). A case
fails when a difference exceeds --tolerance (default 1e-4). With --baseline BIN it also runs
an older binary on the default case to report its Newton iterations ("before").

    .venv/bin/python pipelines/check_criteria.py                 # all cases, table on stdout
    .venv/bin/python pipelines/check_criteria.py --only rigid_punch --markdown table.md

Shipped cases: the TOML files under examples/ and pipelines/ (examples, pipelines, convergence-study base
levels) and benches/calculix/cases/ (at the --bench-size mesh factor of
benches/calculix/bench_calculix.py's quick sizes unless --full).
"""
from __future__ import annotations

import argparse
import csv
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np
import tomli_w

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benches" / "calculix"))
from bench_calculix import CASES as BENCH_CASES  # noqa: E402
from asperity_tools import read_step  # noqa: E402

TIGHT = {"force_tolerance": 1e-10, "displacement_tolerance": 1e-10}


def shipped_cases() -> list[Path]:
    """The case files among the shipped TOML files: those with a [mesh] table (fit and sweep
    specifications, which name a case, are left out)."""
    pipelines = sorted((ROOT / "pipelines").rglob("*.toml")) + sorted((ROOT / "examples").rglob("*.toml"))
    bench = sorted((ROOT / "benches" / "calculix" / "cases").glob("*.toml"))
    return [p for p in pipelines + bench if "mesh" in tomllib.loads(p.read_text())]


def absolute_paths(spec: dict, base: Path) -> None:
    """Makes the case's relative mesh paths absolute, so the copy runs from anywhere."""
    mesh = spec.get("mesh", {})
    for key in ("geo", "file"):
        if key in mesh:
            mesh[key] = str((base / mesh[key]).resolve())


def prepared(case: Path, work: Path, solver: dict, size: float | None) -> Path:
    spec = tomllib.loads(case.read_text())
    absolute_paths(spec, case.parent)
    spec.setdefault("solver", {}).update(solver)
    spec.pop("output", None)
    if size is not None:
        spec["mesh"]["size"] = size
    out = work / "case.toml"
    out.write_text(tomli_w.dumps(spec))
    return out


def run(binary: Path, case: Path, out: Path) -> dict:
    t = time.perf_counter()
    done = subprocess.run([str(binary), "run", str(case), "--out", str(out)], capture_output=True, text=True)
    wall = time.perf_counter() - t
    if done.returncode != 0:
        return {"ok": False, "error": (done.stderr.strip() or done.stdout.strip()).splitlines()[-1:], "wall": wall}
    with open(out / "history.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    history = {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}
    return {"ok": True, "history": history, "wall": wall, "displacement": last_displacement(out),
            "iterations": int(history["iterations"].sum()), "increments": int(history["increments"].sum())}


def last_displacement(out: Path) -> np.ndarray | None:
    """The displacement field of all bodies at the last output frame (None: no field output)."""
    if not (out / "results.pvd").is_file():
        return None
    return np.asarray(read_step(out)["bodies"].point_data["displacement"])


def difference(default: dict, tight: dict) -> tuple[float, str]:
    """The largest relative difference over the compared columns, and its column. A column's
    difference is taken relative to its largest magnitude, but at least 1e-2 of the case's
    largest force: a reaction that vanishes physically (the radial reaction of the axis in
    axisymmetry, a symmetry plane's shear) holds only solver noise, which must not be judged
    against itself."""
    skip = {"step", "increments", "iterations", "residual", "load_factor"}
    columns = {k: v for k, v in tight["history"].items() if k not in skip}
    scale = max([np.abs(v).max() for v in columns.values()] + [0.0])
    worst = (0.0, "-")
    for key, ref in columns.items():
        denominator = max(np.abs(ref).max(), 1e-2 * scale)
        if denominator == 0.0:
            continue
        mine = default["history"][key]
        if mine.shape != ref.shape:
            # Arc-length control chooses its own increments: compare the extremes (the peak
            # load, the largest reaction) rather than step by step.
            d = abs(np.abs(mine).max() - np.abs(ref).max()) / denominator
        else:
            d = np.abs(mine - ref).max() / denominator
        worst = max(worst, (d, key))
    a, b = default["displacement"], tight["displacement"]
    arc_length = len(default["history"]["step"]) != len(tight["history"]["step"])
    # Arc-length runs end where their own increments end: their last fields are not comparable.
    if a is not None and b is not None and not arc_length and np.abs(b).max() > 0:
        worst = max(worst, (np.abs(a - b).max() / np.abs(b).max(), "displacement field"))
    return worst


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--bin", default=str(ROOT / "target" / "release" / "asperity"))
    p.add_argument("--baseline", help="an older asperity binary: its iterations on the default case")
    p.add_argument("--only", action="append", help="run only cases whose file stem contains this")
    p.add_argument("--full", action="store_true", help="benchmark cases at their full (issue) sizes")
    p.add_argument("--tolerance", type=float, default=1e-4)
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="a [solver] setting for the default run (to try other criteria)")
    p.add_argument("--markdown", help="also write the table to this file")
    args = p.parse_args()
    binary = Path(args.bin).resolve()
    trial = {k: float(v) for k, v in (item.split("=", 1) for item in args.set)}
    sizes = {c.toml: (c.size_full if args.full else c.size_quick) for c in BENCH_CASES}
    rows, failed = [], []
    header = ("| case | increments | its before | its after | its tight | wall after [s] | wall tight [s] "
              "| max rel. difference | where |\n|---|---|---|---|---|---|---|---|---|")
    print(header, flush=True)
    for case in shipped_cases():
        name = str(case.relative_to(ROOT))
        if args.only and not any(o in case.stem for o in args.only):
            continue
        size = sizes.get(case.name) if "benches" in name else None
        with tempfile.TemporaryDirectory() as tmp:
            work = Path(tmp)
            (work / "a").mkdir()
            (work / "b").mkdir()
            runs = {"default": run(binary, prepared(case, work / "a", trial, size), work / "a" / "out"),
                    "tight": run(binary, prepared(case, work / "b", TIGHT, size), work / "b" / "out")}
            before = "-"
            if args.baseline:
                (work / "c").mkdir()
                old = run(Path(args.baseline), prepared(case, work / "c", {}, size), work / "c" / "out")
                before = str(old["iterations"]) if old["ok"] else "failed"
        d, t = runs["default"], runs["tight"]
        if not (d["ok"] and t["ok"]):
            row = f"| `{name}` | failed: {d.get('error') or t.get('error')} |||||||"
            failed.append(name)
        else:
            rel, where = difference(d, t)
            if rel > args.tolerance:
                failed.append(name)
            row = (f"| `{name}` | {d['increments']} | {before} | {d['iterations']} | {t['iterations']} "
                   f"| {d['wall']:.2f} | {t['wall']:.2f} | {rel:.1e} | {where} |")
        rows.append(row)
        print(row, flush=True)
    if args.markdown:
        Path(args.markdown).write_text(header + "\n" + "\n".join(rows) + "\n")
    if failed:
        print(f"cases above {args.tolerance:g} or failing: {', '.join(failed)}", file=sys.stderr)
        return 1
    print(f"all {len(rows)} cases within {args.tolerance:g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
