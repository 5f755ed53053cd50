#!/usr/bin/env python3
"""`make bench` (scale): the tapered press fit refined to about a million unknowns (issue 12,
item 6): axisymmetric, Coulomb friction μ = 0.2 with the whole cone slipping, ten increments.

The case is CalculiX benchmark case 2 (benches/calculix/cases/tapered_press_fit.toml, mesh
geo/bench_tapered_joint.geo: about 1 600 / s² unknowns at size factor s) on a finer mesh;
the default s = 0.0387 gives about 0.97 M unknowns. Meshes with gmsh, runs `asperity run`
under GNU time, and prints the breakdown: gmsh, mesh reading, model building, assembly,
factorisation, solves and output from asperity's closing summary, wall and CPU time, peak
resident memory, the Newton iterations, and the run's floor and its ratio to it (summary.json
`floor`: reading the mesh, one assembly, one factorisation, one solve per increment and the
output; docs/guide/outputs.md). With --write the table is appended to
BENCHMARKS.md with the machine, the date and the load average (a busy machine makes the
wall times unrepresentative; the CPU time suffers less).

--case runs another case on the same .geo script, e.g. benches/cases/tapered_press_fit_heated.toml
(the same fit heated through the cone, thermal–mechanical coupling); the table's *conduction*
is its heat conduction's time (summary.json `seconds.conduction`).

The bar (issue 12): under 5 minutes and under 8 GB on a 2-core machine.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import os
import subprocess
import sys
import tomllib
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "calculix"))

import bench_calculix as bc  # noqa: E402  (the CalculiX comparison's mesh/run/parse helpers)

CASE = bc.CASE_DIR / "tapered_press_fit.toml"
WALL_LIMIT_S, MEMORY_LIMIT_MB = 300.0, 8192.0


def commit() -> str:
    done = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=bc.ROOT, capture_output=True, text=True)
    return done.stdout.strip() or "?"


def run(case: Path, size: float, work: Path, binary: Path, timeout: float) -> dict:
    if not case.is_file():
        sys.exit(f"--case {case}: no such file")
    try:
        spec = tomllib.loads(case.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        sys.exit(f"--case {case}: not a TOML case file ({e})")
    if not isinstance(spec.get("mesh"), dict) or "geo" not in spec["mesh"]:
        sys.exit(f"--case {case}: needs a [mesh] table with `geo` (the .geo script to refine)")
    work.mkdir(parents=True, exist_ok=True)
    msh = work / "mesh.msh"
    gmsh_s = bc.mesh_case(case, spec, size, msh, binary=True)  # as `asperity run` meshes
    run_toml = work / "case.toml"
    bc.case_with_mesh(case, msh.resolve(), run_toml)
    adir = work / "asperity"
    adir.mkdir(exist_ok=True)
    m = bc.measure([str(binary), "run", str(run_toml), "--out", str(adir / "out")], adir, timeout=timeout)
    info = bc.parse_asperity_summary(m.stdout, adir / "out")
    if m.returncode != 0:
        sys.exit(f"asperity failed (exit status {m.returncode}):\n{m.stderr[-2000:]}")
    info.update({"case": case, "size": size, "gmsh_s": gmsh_s, "wall_s": m.wall, "cpu_s": m.cpu, "rss_mb": m.rss_mb})
    return info


def floor_of(r: dict) -> dict | None:
    """The run's `floor` from its summary.json (None from a binary that does not write it)."""
    floor = (r.get("summary_json") or {}).get("floor")
    return floor if isinstance(floor, dict) else None


def beyond_floor(floor: dict | None, phases: dict) -> str:
    """The largest kinds of work a run did beyond its floor (summary.json `floor.work_seconds`
    against `floor.parts`, and the model build), as a sentence; empty without them."""
    work = (floor or {}).get("work_seconds")
    if not work:
        return ""
    parts = floor["parts"]
    beyond = {
        "state evaluations": work["state_evaluations"],
        "K·u products": work["products"],
        "element loops beyond the first": work["assemblies"] + work["force_assemblies"] - parts["assembly"],
        "interface element loops": work["interface_assemblies"] + work["interface_force_assemblies"],
        "factorisations beyond one": work["factorisations"] + work["kept_factorisations"]
        + work["interface_factorisations"] + work["kept_interface_factorisations"] - parts["factorisation"],
        "solves beyond one per increment": work["solves"] - parts["solves"],
        "conduction solves beyond one per increment": work.get("conduction_solves", 0.0)
        - (parts.get("conduction", 0.0) - work.get("conduction_factorisations", 0.0)),
        "the model build": phases.get("model", 0.0),
    }
    largest = sorted(((s, k) for k, s in beyond.items() if s > 0.0), reverse=True)[:4]
    listed = ", ".join(f"{k} {s:.2f} s" for s, k in largest)
    return f"Largest beyond the floor (summary.json `floor.work_seconds`): {listed}." if listed else ""


def table(r: dict, load: tuple[float, float]) -> str:
    p = r.get("phases", {})
    phase = lambda k: f"{p[k]:.2f}" if k in p else "–"  # noqa: E731
    floor = floor_of(r)
    floor_s = f"{floor['seconds']:.2f}" if floor else "–"
    ratio = f"{floor['ratio']:.2f}" if floor and floor.get("ratio") is not None else "–"
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    busy = (" (the machine was busy: wall times are not representative)" if load[0] > 1.5 * (os.cpu_count() or 1)
            else "")
    verdict = ("within" if r["wall_s"] < WALL_LIMIT_S and r["rss_mb"] < MEMORY_LIMIT_MB else "OUTSIDE")
    beyond = beyond_floor(floor, p)
    case_path = Path(r["case"]).resolve()
    case_name = case_path.relative_to(bc.ROOT) if case_path.is_relative_to(bc.ROOT) else case_path
    case_option = "" if Path(r["case"]).resolve() == CASE.resolve() else f" --case {case_name}"
    heated = ", heated through the cone, thermal–mechanical coupling" if "conduction" in p else ""
    return "\n".join([
        f"### Scale: tapered press fit at {r.get('unknowns', 0) / 1e6:.2f} M unknowns, {now}, {bc.cpu_name()}, "
        f"{os.cpu_count()} cores",
        "",
        f"`make bench` (`benches/bench_scale.py --size {r['size']}{case_option}`, commit {commit()}): "
        f"{case_name} (axisymmetric, μ = 0.2, whole cone slipping, "
        f"10 increments{heated}) on a finer mesh; asperity's defaults. Load average (1 min) before the run "
        f"{load[0]:.2f}, after it {load[1]:.2f}{busy}. *gmsh* ran beforehand and is not in *wall*; "
        "*mesh* is reading the mesh file. *CPU* is user + system time over both cores. "
        "*floor* is the run's own floor and *run / floor* its ratio to it (summary.json `floor`). "
        f"Bar: < {WALL_LIMIT_S:.0f} s and < {MEMORY_LIMIT_MB / 1024:.0f} GB: {verdict}.",
        "",
        "| unknowns | elements | increments | Newton its (cut-backs) | gmsh [s] | mesh [s] | model [s] | assembly [s] "
        "| factorisation [s] | solve [s] | output [s] | conduction [s] | wall [s] | CPU [s] | peak RSS [MB] "
        "| floor [s] | run / floor |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
        f"| {r.get('unknowns', '?')} | {r.get('elements', '?')} | {r.get('increments', '?')} | "
        f"{r.get('iterations', '?')} ({r.get('cutbacks', '?')}) | {r['gmsh_s']:.2f} | {phase('mesh')} | "
        f"{phase('model')} | {phase('assembly')} | {phase('factorisation')} | {phase('solve')} | "
        f"{phase('output')} | {phase('conduction')} | {r['wall_s']:.2f} | {r['cpu_s']:.2f} | {r['rss_mb']:.0f} | {floor_s} | {ratio} |",
        "",
        *([beyond, ""] if beyond else []),
    ])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", type=float, default=0.0387, help="mesh size factor (default 0.0387: ~0.97 M unknowns)")
    ap.add_argument("--write", action="store_true", help="append the table to BENCHMARKS.md")
    ap.add_argument("--benchmarks", default=str(bc.ROOT / "BENCHMARKS.md"), help="the file --write appends to")
    ap.add_argument("--bin", default=None, help="asperity binary (default target/release/asperity)")
    ap.add_argument("--out", default=str(bc.ROOT / "build" / "bench_scale"), help="work folder")
    ap.add_argument("--timeout", type=float, default=3600.0, help="seconds allowed for the run")
    ap.add_argument("--case", default=str(CASE), help="case file meshed from its .geo script "
                    "(default benches/calculix/cases/tapered_press_fit.toml)")
    args = ap.parse_args()
    binary = bc.find_binary(args.bin)
    before = os.getloadavg()[0]
    r = run(Path(args.case), args.size, Path(args.out), binary, args.timeout)
    block = table(r, (before, os.getloadavg()[0]))
    print(block)
    if args.write:
        with open(args.benchmarks, "a") as f:
            f.write("\n" + block)
        print(f"appended to {args.benchmarks}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
