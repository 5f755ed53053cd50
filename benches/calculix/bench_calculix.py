#!/usr/bin/env python3
"""asperity against CalculiX 2.20 on the same meshes, increments and answers (issue 12, item 7).

For every case in CASES (case files in benches/calculix/cases/, geometry in geo/bench_*.geo):
  1. mesh the case's .geo script once with gmsh, with the options `asperity run` uses;
  2. run asperity on that mesh (a copy of the case whose [mesh] reads the .msh file);
  3. translate the same model into a CalculiX input deck (CAX8/CAX6 elements, face-to-face
     penalty contact with the same linear pressure-overclosure slope k_N and stick slope k_T,
     the same increments as fixed increments) and run `ccx` (SPOOLES, OMP_NUM_THREADS=2);
  4. compare the displacement under the load (the case's probe point) to 2e-3 relative and
     print wall time, Newton iterations and peak memory of both side by side. asperity runs
     --repeat times (default 5) and its median wall time is the one compared (the machine's
     moments decide less); CalculiX, whose runs take minutes, runs once.

Usage (from the repository root; `make bench-calculix` runs the full mode with --write):
    .venv/bin/python benches/calculix/bench_calculix.py --quick            # small meshes, minutes
    .venv/bin/python benches/calculix/bench_calculix.py --write            # issue sizes; table into BENCHMARKS.md
    .venv/bin/python benches/calculix/bench_calculix.py --quick --case shrink_fit --case rigid_punch

Exit status: 0 when every compared case agrees, 1 when one disagrees or a run fails, 2 on
bad usage. Timings are benchmarks, never tests: nothing here fails because of a time.
Work files: build/bench_calculix/<mode>/<case>/{mesh.msh, case.toml, asperity/, calculix/}.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import math
import os
import platform
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
import tomllib
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
CASE_DIR = HERE / "cases"
sys.path.insert(0, str(ROOT / "pipelines"))  # asperity_tools, imported where the results are read
TOLERANCE = 2e-3  # relative difference of the displacement under the load (issue 12)
BLOCK_BEGIN = "<!-- bench-calculix:begin (written by benches/calculix/bench_calculix.py --write; reruns replace this block) -->"
BLOCK_END = "<!-- bench-calculix:end -->"


@dataclass
class Case:
    """One benchmark case. `size_quick`/`size_full` are gmsh size factors (-clscale); the full
    sizes give the unknown counts of issue 12's table. `probe` is a physical point of the mesh
    and `component` (0 = r, 1 = z) the displacement compared there. `master` is the contact side
    CalculiX takes as its master (independent) surface. `calculix = False` runs asperity only."""
    name: str
    title: str
    toml: str
    size_quick: float
    size_full: float
    probe: str
    component: int
    master: str = "side_b"
    calculix: bool = True
    note: str = ""


CASES = [
    Case("shrink_fit", "shrink fit, frictionless, 1 step", "shrink_fit.toml",
         0.25, 0.0667, "probe", 0),
    Case("tapered_press_fit", "tapered press fit, μ = 0.2, 10 increments, full slip", "tapered_press_fit.toml",
         0.5, 0.158, "top_centre", 1),
    Case("flat_punch_elastic", "flat punch, elastic, μ = 0.2, 5 increments", "flat_punch_elastic.toml",
         1.0, 0.1265, "top_centre", 1),
    Case("flat_punch_plastic", "flat punch, elasto-plastic (J2), q = 150 MPa, μ = 0.2, 10 increments",
         "flat_punch_plastic.toml", 1.0, 0.256, "top_centre", 1),
    Case("rigid_punch", "near-rigid flat punch (E ratio 1000, k_N = k_T = 1e8), μ = 0.2, 10 increments",
         "rigid_punch.toml", 1.0, 0.51, "top_centre", 1),
    Case("rigid_punch_frictionless", "near-rigid flat punch, frictionless twin, 10 increments", "rigid_punch_frictionless.toml",
         1.0, 0.51, "top_centre", 1),
]


# --------------------------------------------------------------------------------------------
# tools
# --------------------------------------------------------------------------------------------
def sudo() -> list[str]:
    return [] if os.geteuid() == 0 else ["sudo"]


def apt_install(package: str, command: str) -> None:
    """Installs a Debian package with apt-get when `command` is missing (as the Makefile's gmsh
    target does)."""
    if shutil.which(command):
        return
    print(f"installing {package} (apt-get)", flush=True)
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    subprocess.run(sudo() + ["apt-get", "update", "-qq"], check=True, env=env)
    subprocess.run(sudo() + ["apt-get", "install", "-y", "-qq", package], check=True, env=env,
                   stdout=subprocess.DEVNULL)
    if not shutil.which(command):
        sys.exit(f"{package} installed but `{command}` is not on PATH")


def ccx_version() -> str:
    done = subprocess.run(["ccx", "-v"], capture_output=True, text=True)
    m = re.search(r"Version\s+([0-9.]+)", done.stdout + done.stderr)
    return m.group(1) if m else "?"


def find_binary(explicit: str | None) -> Path:
    if explicit:
        return Path(explicit).resolve()
    for candidate in (ROOT / "target" / "release" / "asperity", Path("/work/baseline_bin/asperity")):
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return candidate
    sys.exit("asperity binary not found: build it with `cargo build --release` or pass --bin")


@dataclass
class Measured:
    returncode: int
    wall: float
    rss_mb: float
    stdout: str
    stderr: str
    cpu: float = 0.0  # user + system seconds of the run (wait4's rusage)


GNU_TIME = Path("/usr/bin/time")


def measure(cmd: list[str], cwd: Path, env: dict | None = None, timeout: float | None = None) -> Measured:
    """Runs `cmd` and returns its wall time (measured here) and peak resident memory.

    The memory comes from GNU time (`/usr/bin/time -f %M`) when it is installed: the kernel
    carries a process's RSS high-water mark over fork and exec, so ru_maxrss of a child forked
    straight from this Python process (numpy and pyvista loaded, ~100 MB) would never be below
    Python's own size. Without GNU time, wait4's ru_maxrss is used (an upper bound)."""
    cwd = cwd.resolve()
    out_path, err_path = cwd / "stdout.txt", cwd / "stderr.txt"
    rss_path = cwd / "time_rss.txt"
    use_time = GNU_TIME.is_file() and os.access(GNU_TIME, os.X_OK)
    full = ([str(GNU_TIME), "-f", "%M", "-o", str(rss_path)] if use_time else []) + cmd
    with open(out_path, "w") as out, open(err_path, "w") as err:
        start = time.perf_counter()
        proc = subprocess.Popen(full, cwd=cwd, env=env, stdout=out, stderr=err, start_new_session=True)
        # A blocking wait ends the clock when the run ends (polling would add up to its period,
        # several per cent of a 0.1 s run); a timer kills the run's own process group at the limit.
        killed = threading.Event()

        def kill() -> None:
            killed.set()
            os.killpg(proc.pid, signal.SIGKILL)

        timer = threading.Timer(timeout, kill) if timeout is not None else None
        if timer:
            timer.start()
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - start
        if timer:
            timer.cancel()
        if killed.is_set():
            err.write(f"\nkilled after the time limit of {timeout:g} s\n")
    proc.returncode = os.waitstatus_to_exitcode(status)
    rss_kb = float(usage.ru_maxrss)
    if use_time and rss_path.is_file():
        numbers = re.findall(r"^\s*(\d+)\s*$", rss_path.read_text(), re.M)
        if numbers:
            rss_kb = float(numbers[-1])
    return Measured(proc.returncode, wall, rss_kb / 1024.0, out_path.read_text(errors="replace"),
                    err_path.read_text(errors="replace"), usage.ru_utime + usage.ru_stime)


# --------------------------------------------------------------------------------------------
# gmsh mesh (MSH 4.1: ascii for read_msh41, binary as `asperity run` meshes)
# --------------------------------------------------------------------------------------------
def mesh_case(case_file: Path, spec: dict, size: float, out: Path, binary: bool = False) -> float:
    """Meshes the case's .geo script with the options `asperity run` uses; returns gmsh's time.

    ASCII unless `binary` (as `asperity run` meshes): `read_msh41` reads ASCII only."""
    geo = (case_file.parent / spec["mesh"]["geo"]).resolve()
    cmd = ["gmsh", str(geo), "-2", "-order", "2", "-format", "msh41", "-v", "2",
           "-setnumber", "Mesh.SecondOrderIncomplete", "1", "-clscale", repr(float(size))]
    if binary:
        cmd.append("-bin")
    for name, value in spec["mesh"].get("parameters", {}).items():
        cmd += ["-setnumber", name, repr(float(value))]
    cmd += ["-o", str(out)]
    start = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0 or "Error" in done.stdout + done.stderr or not out.is_file():
        sys.exit(f"gmsh failed on {geo}:\n{done.stdout}{done.stderr}")
    return time.perf_counter() - start


QUAD8, TRI6, LINE3, POINT = 16, 9, 8, 15
NODES_PER_TYPE = {QUAD8: 8, TRI6: 6, LINE3: 3, POINT: 1, 1: 2, 2: 3, 3: 4, 10: 9, 21: 10, 26: 4, 27: 5, 28: 6}


@dataclass
class Mesh:
    coords: dict[int, tuple[float, float]]
    groups: dict[str, tuple[int, list[tuple[int, np.ndarray]]]] = field(default_factory=dict)
    # name -> (dim, [(gmsh element type, connectivity array (n, k))])


def read_msh41(path: Path) -> Mesh:
    lines = path.read_text().splitlines()
    sections: dict[str, list[str]] = {}
    i = 0
    while i < len(lines):
        line = lines[i].strip()
        if line.startswith("$") and not line.startswith("$End"):
            name = line[1:]
            j = lines.index("$End" + name, i)
            sections[name] = lines[i + 1:j]
            i = j + 1
        else:
            i += 1
    fmt = sections["MeshFormat"][0].split()
    if not fmt[0].startswith("4.1") or fmt[1] != "0":
        sys.exit(f"{path}: expected an ascii MSH 4.1 file, found format {fmt}")
    names = {}
    for line in sections.get("PhysicalNames", [])[1:]:
        dim, tag, name = line.split(maxsplit=2)
        names[(int(dim), int(tag))] = name.strip('"')
    # entities -> physical tags
    ent = sections["Entities"]
    counts = [int(v) for v in ent[0].split()]
    phys_of: dict[tuple[int, int], list[int]] = {}
    k = 1
    for dim, count in enumerate(counts):
        for _ in range(count):
            v = ent[k].split()
            k += 1
            tag = int(v[0])
            pos = 4 if dim == 0 else 7
            nphys = int(v[pos])
            phys_of[(dim, tag)] = [abs(int(t)) for t in v[pos + 1:pos + 1 + nphys]]
    # nodes
    nd = sections["Nodes"]
    nblocks = int(nd[0].split()[0])
    coords: dict[int, tuple[float, float]] = {}
    k = 1
    for _ in range(nblocks):
        _, _, parametric, n = (int(v) for v in nd[k].split())
        if parametric:
            sys.exit(f"{path}: parametric node blocks are not supported")
        tags = [int(nd[k + 1 + j]) for j in range(n)]
        for j, tag in enumerate(tags):
            x, y, _z = nd[k + 1 + n + j].split()
            coords[tag] = (float(x), float(y))
        k += 1 + 2 * n
    # elements
    el = sections["Elements"]
    nblocks = int(el[0].split()[0])
    mesh = Mesh(coords)
    k = 1
    for _ in range(nblocks):
        dim, tag, etype, n = (int(v) for v in el[k].split())
        conn = np.array([[int(t) for t in el[k + 1 + j].split()[1:]] for j in range(n)], dtype=np.int64)
        k += 1 + n
        for ptag in phys_of.get((dim, tag), []):
            name = names.get((dim, ptag), str(ptag))
            gdim, blocks = mesh.groups.setdefault(name, (dim, []))
            blocks.append((etype, conn))
    return mesh


# --------------------------------------------------------------------------------------------
# CalculiX input deck
# --------------------------------------------------------------------------------------------
FACES = {  # local (corner, corner, mid) node indices of each face, numbered as CalculiX does
    QUAD8: [(0, 1, 4), (1, 2, 5), (2, 3, 6), (3, 0, 7)],
    TRI6: [(0, 1, 3), (1, 2, 4), (2, 0, 5)],
}


def signed_area(xy: np.ndarray) -> float:
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def load_factors(spec: dict) -> list[float]:
    steps = spec.get("steps", {})
    if "factors" in steps:
        return [float(f) for f in steps["factors"]]
    n = int(steps.get("count", 1))
    return [(k + 1) / n for k in range(n)]


def fmt(v: float) -> str:
    return f"{v:.12g}"


def write_calculix(spec: dict, mesh: Mesh, case: Case, path: Path) -> dict:
    """Writes the CalculiX deck of the case `spec` on `mesh`; returns what the comparison needs
    (probe node, support node sets)."""
    if spec["analysis"]["type"] != "axisymmetric":
        sys.exit(f"{case.name}: only axisymmetric cases are translated (CAX8/CAX6)")
    factors = load_factors(spec)
    n_inc = len(factors)
    if any(abs(f - (k + 1) / n_inc) > 1e-12 for k, f in enumerate(factors)):
        sys.exit(f"{case.name}: only equal increments up to load factor 1 are translated")
    if any("factors" in s for s in spec.get("support", []) + spec.get("load", [])):
        sys.exit(f"{case.name}: per-load factors are not translated")

    out: list[str] = ["** written by benches/calculix/bench_calculix.py from " + case.toml,
                      "** axisymmetric: x = r, y = z; CAX elements are expanded to a 2-degree 3D wedge"]
    used: set[int] = set()
    elements: list[tuple[int, str, int, list[int]]] = []  # (id, body, type, nodes)
    edge_owner: dict[tuple[int, int], list[tuple[int, int, str]]] = {}
    eid = 0
    for body in spec["body"]:
        dim, blocks = mesh.groups[body["group"]]
        for etype, conn in blocks:
            if etype not in FACES:
                sys.exit(f"{case.name}: element type {etype} in body {body['group']} (need quad8/tri6)")
            ncorner = 4 if etype == QUAD8 else 3
            for row in conn:
                nodes = [int(v) for v in row]
                xy = np.array([mesh.coords[v] for v in nodes[:ncorner]])
                if signed_area(xy) < 0:  # clockwise: CalculiX wants counter-clockwise
                    nodes = ([nodes[0], nodes[3], nodes[2], nodes[1], nodes[7], nodes[6], nodes[5], nodes[4]]
                             if etype == QUAD8 else [nodes[0], nodes[2], nodes[1], nodes[5], nodes[4], nodes[3]])
                eid += 1
                elements.append((eid, body["group"], etype, nodes))
                used.update(nodes)
                for face, (a, b, _) in enumerate(FACES[etype], start=1):
                    key = (min(nodes[a], nodes[b]), max(nodes[a], nodes[b]))
                    edge_owner.setdefault(key, []).append((eid, face, body["group"]))

    xs = np.array([mesh.coords[n] for n in used])
    scale = float(np.max(np.abs(xs))) or 1.0
    out.append("*NODE, NSET=NALL")
    for n in sorted(used):
        x, y = mesh.coords[n]
        out.append(f"{n}, {fmt(x)}, {fmt(y)}, 0")
    for body in spec["body"]:
        for etype in (QUAD8, TRI6):
            rows = [e for e in elements if e[1] == body["group"] and e[2] == etype]
            if not rows:
                continue
            out.append(f"*ELEMENT, TYPE={'CAX8' if etype == QUAD8 else 'CAX6'}, ELSET=E_{body['group']}")
            for e, _, _, nodes in rows:
                out.append(f"{e}, " + ", ".join(str(v) for v in nodes))
    plastic = False
    for body in spec["body"]:
        m = body["material"]
        g = body["group"]
        out += [f"*MATERIAL, NAME=M_{g}", "*ELASTIC", f"{fmt(m['E'])}, {fmt(m['nu'])}"]
        if "yield_stress" in m:
            plastic = True
            sy, hh = float(m["yield_stress"]), float(m.get("hardening", 0.0))
            out.append("*PLASTIC")
            out.append(f"{fmt(sy)}, 0.")
            if hh != 0.0:  # linear isotropic hardening: (stress, plastic strain) pairs
                out.append(f"{fmt(sy + hh * 10.0)}, 10.")
        out.append(f"*SOLID SECTION, ELSET=E_{g}, MATERIAL=M_{g}")

    def curve_faces(group: str) -> list[tuple[int, int]]:
        dim, blocks = mesh.groups[group]
        faces = []
        for etype, conn in blocks:
            if etype != LINE3:
                sys.exit(f"{case.name}: group {group} has elements of type {etype}, expected 3-node lines")
            for row in conn:
                key = (min(int(row[0]), int(row[1])), max(int(row[0]), int(row[1])))
                owners = edge_owner.get(key, [])
                if len(owners) != 1:
                    sys.exit(f"{case.name}: boundary line {list(row)} of {group} belongs to {len(owners)} elements")
                faces.append(owners[0][:2])
        return faces

    def group_nodes(group: str) -> list[int]:
        dim, blocks = mesh.groups[group]
        return sorted({int(v) for _, conn in blocks for v in conn.ravel()})

    # node sets: supports, probe, axis
    sets: dict[str, list[int]] = {}
    axis = sorted(n for n in used if abs(mesh.coords[n][0]) <= 1e-9 * scale)
    if axis:
        sets["AXIS"] = axis
    for s in spec.get("support", []):
        sets[f"R_{s['group']}"] = group_nodes(s["group"])
    probe_nodes = group_nodes(case.probe)
    sets["PROBE"] = probe_nodes
    for name, nodes in sets.items():
        out.append(f"*NSET, NSET={name}")
        for i in range(0, len(nodes), 12):
            out.append(", ".join(str(v) for v in nodes[i:i + 12]))
    # contact surfaces
    pairs = []
    for c in spec.get("contact", []):
        if "side_a" not in c:
            sys.exit(f"{case.name}: only contact pairs given by side_a/side_b are translated")
        law = c["law"]
        if law["type"] != "linear_coulomb":
            sys.exit(f"{case.name}: only the linear_coulomb law has a CalculiX equivalent")
        for side in ("side_a", "side_b"):
            out.append(f"*SURFACE, NAME=S_{c[side]}")
            out += [f"{e}, S{f}" for e, f in curve_faces(c[side])]
        master = c[case.master]
        slave = c["side_b" if case.master == "side_a" else "side_a"]
        pairs.append((c, slave, master))
    for c, slave, master in pairs:
        law = c["law"]
        name = c.get("name", f"{c['side_a']}-{c['side_b']}")
        inter = f"I_{re.sub(r'[^A-Za-z0-9_]', '_', name)}"
        out += [f"*CONTACT PAIR, INTERACTION={inter}, TYPE=SURFACE TO SURFACE", f"S_{slave}, S_{master}",
                f"*SURFACE INTERACTION, NAME={inter}",
                "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR", fmt(law["normal_stiffness"])]
        mu = float(law.get("friction", 0.0))
        if mu > 0:
            out += ["*FRICTION", f"{fmt(mu)}, {fmt(law['tangential_stiffness'])}"]
        delta = float(c.get("interference", 0.0))
        if delta != 0.0:
            out.append(f"*CLEARANCE, MASTER=S_{master}, SLAVE=S_{slave}, VALUE={fmt(-delta)}")
    # fixed supports (model data); prescribed nonzero values go into the step (ramped)
    out.append("*BOUNDARY")
    if axis:
        out.append("AXIS, 1, 1, 0.")
    ramped = []
    for s in spec.get("support", []):
        for dof, keys in ((1, ("ux", "ur")), (2, ("uy", "uz"))):
            for key in keys:
                if key in s:
                    if float(s[key]) == 0.0:
                        out.append(f"R_{s['group']}, {dof}, {dof}, 0.")
                    else:
                        ramped.append(f"R_{s['group']}, {dof}, {dof}, {fmt(float(s[key]))}")
    # the step: equal fixed increments as asperity's
    out.append("*STEP, INC=10000" + (", NLGEOM=NO" if plastic else ""))
    out += ["*STATIC, DIRECT", f"{fmt(1.0 / n_inc)}, 1."]
    if ramped:
        out += ["*BOUNDARY"] + ramped
    dload, cload = [], []
    for ld in spec.get("load", []):
        if "pressure" in ld:
            dload += [f"{e}, P{f}, {fmt(float(ld['pressure']))}" for e, f in curve_faces(ld["group"])]
        elif "force" in ld:  # axisymmetric CLOAD: total over the circumference (CalculiX manual, CAX8)
            for n in group_nodes(ld["group"]):
                for dof, value in enumerate(ld["force"], start=1):
                    if value:
                        cload.append(f"{n}, {dof}, {fmt(float(value))}")
        else:
            sys.exit(f"{case.name}: load {ld} is not translated (pressure and force only)")
    if dload:
        out += ["*DLOAD"] + dload
    if cload:
        out += ["*CLOAD"] + cload
    out += ["*NODE PRINT, NSET=PROBE", "U"]
    for s in spec.get("support", []):
        out += [f"*NODE PRINT, NSET=R_{s['group']}, TOTALS=ONLY", "RF"]
    out += ["*NODE FILE", "U", "*EL FILE", "S" + (", PEEQ" if plastic else ""), "*END STEP"]
    path.write_text("\n".join(out) + "\n")
    return {"probe_nodes": probe_nodes, "nodes": len(used), "elements": len(elements), "increments": n_inc,
            "supports": [s["group"] for s in spec.get("support", [])]}


def read_dat(path: Path, probe_nodes: list[int]) -> dict:
    """Displacements of the probe set and reaction totals at the last time in the .dat file."""
    text = path.read_text(errors="replace")
    result: dict = {"time": None, "u": None, "rf": {}}
    blocks = re.split(r"\n\s*(?=displacements|total force|forces)", text)
    for block in blocks:
        head, _, body = block.partition("\n")
        m = re.search(r"time\s+([-+0-9.Ee]+)", head)
        if head.lstrip().startswith("displacements") and "PROBE" in head.upper():
            rows = []
            for line in body.splitlines():
                v = line.split()
                if len(v) >= 4 and v[0].isdigit() and int(v[0]) in probe_nodes:
                    rows.append([float(x) for x in v[1:4]])
                elif v and not v[0].isdigit():
                    break
            if rows:
                result["u"] = np.mean(np.array(rows), axis=0)
                result["time"] = float(m.group(1)) if m else None
        elif head.lstrip().startswith("total force"):
            g = re.search(r"set\s+R_(\S+)", head, re.I)
            v = body.split()
            if g and len(v) >= 3:
                result["rf"][g.group(1).lower()] = [float(x) for x in v[:3]]
    return result


def read_sta(path: Path) -> dict:
    """Increments, attempts and Newton iterations from CalculiX's .sta file (one line per
    converged increment: STEP INC ATT ITRS ...)."""
    inc = its = cut = 0
    last_time = 0.0
    if path.is_file():
        for line in path.read_text(errors="replace").splitlines():
            v = line.split()
            if len(v) >= 7 and v[0].isdigit() and v[1].isdigit():
                inc += 1
                cut += int(v[2].rstrip("U")) - 1 if v[2].rstrip("U").isdigit() else 0
                its += int(v[3])
                last_time = float(v[4])
    return {"increments": inc, "iterations": its, "cutbacks": cut, "time": last_time}


def count_cvg(path: Path) -> int:
    """All Newton iterations including those of abandoned attempts (.cvg: one line each)."""
    if not path.is_file():
        return 0
    n = 0
    for line in path.read_text(errors="replace").splitlines():
        v = line.split()
        if len(v) >= 5 and all(x.isdigit() for x in v[:4]):
            n += 1
    return n


# --------------------------------------------------------------------------------------------
# asperity
# --------------------------------------------------------------------------------------------
def case_with_mesh(case_file: Path, msh: Path, path: Path) -> None:
    """A copy of the case reading the pre-made mesh: its [mesh] table replaced by file = msh."""
    out, skip = [], False
    for line in case_file.read_text().splitlines():
        header = re.match(r"^\s*\[\[?([^\]]+)\]\]?\s*(#.*)?$", line)
        if header:
            skip = header.group(1).strip() == "mesh"
            if skip:
                out += ["[mesh]", f'file = "{msh}"']
                continue
        if not skip:
            out.append(line)
    path.write_text("\n".join(out) + "\n")


def parse_asperity_summary(stdout: str, folder: Path) -> dict:
    info: dict = {}
    summary = folder / "summary.json"
    if summary.is_file():
        try:
            info["summary_json"] = json.loads(summary.read_text())
        except ValueError:
            pass
    m = re.search(r"model:\s*(\d+) nodes,\s*(\d+) elements,\s*(\d+) unknowns", stdout)
    if m:
        info["nodes"], info["elements"], info["unknowns"] = (int(v) for v in m.groups())
    m = re.search(r"steps:.*?in (\d+) increments \((\d+) cut-backs\),\s*(\d+) Newton iterations", stdout)
    if m:
        info["increments"], info["cutbacks"], info["iterations"] = (int(v) for v in m.groups())
    m = re.search(r"\((\d+) unsymmetric solves, (\d+) BiCGSTAB iterations\)", stdout)
    if m:
        info["unsymmetric_solves"], info["krylov_iterations"] = (int(v) for v in m.groups())
    m = re.search(r"^time \[s\]:(.*)$", stdout, re.M)
    if m:
        info["phases"] = {k.strip(): float(v) for k, v in re.findall(r"([a-z+ ]+?)\s+([0-9.]+)", m.group(1))}
    js = info.get("summary_json")
    if isinstance(js, dict):  # prefer the machine-readable summary where it has the numbers
        for key in ("iterations", "newton_iterations"):
            if isinstance(js.get(key), int):
                info["iterations"] = js[key]
        for key in ("unknowns", "increments", "cutbacks"):
            if isinstance(js.get(key), int):
                info[key] = js[key]
    return info


def last_bodies(folder: Path):
    """All bodies of the last output frame of the series `folder`/results.pvd as one pyvista
    grid: a series of `frame_NNNN.vtm` files (pipelines/asperity_tools.py reads them), or,
    from an older binary, of `bodies_NNNN.vtu` files (part 0)."""
    import pyvista as pv  # only needed here; imported late so --help works without the venv
    from asperity_tools import read_step

    pvd = folder / "results.pvd"
    if not pvd.is_file():
        raise FileNotFoundError(f"no {pvd}")
    files = sorted((float(ds.get("timestep", "0")), ds.get("file"))
                   for ds in ET.parse(pvd).getroot().iter("DataSet") if ds.get("part", "0") == "0")
    if not files:
        raise FileNotFoundError(f"{pvd} lists no files")
    if files[-1][1].endswith(".vtm"):
        return read_step(folder)["bodies"]
    return pv.read(str(folder / files[-1][1]))


def asperity_probe(folder: Path, xy: np.ndarray, scale: float) -> np.ndarray:
    grid = last_bodies(folder)
    pts = np.asarray(grid.points)[:, :2]
    u = np.asarray(grid.point_data["displacement"])
    picked = []
    for p in xy:
        d = np.linalg.norm(pts - p, axis=1)
        hit = d <= 1e-7 * scale
        if not hit.any():
            raise ValueError(f"probe point {p} not among the output nodes of {folder}")
        picked.append(u[hit].mean(axis=0))
    return np.mean(np.array(picked), axis=0)


def read_history_last(folder: Path) -> dict[str, float]:
    path = folder / "history.csv"
    if not path.is_file():
        return {}
    rows = path.read_text().strip().splitlines()
    head, last = rows[0].split(","), rows[-1].split(",")
    return {k: float(v) for k, v in zip(head, last)}


# --------------------------------------------------------------------------------------------
# one case
# --------------------------------------------------------------------------------------------
def run_case(case: Case, size: float, work: Path, binary: Path, timeout: float, repeat: int = 1) -> dict:
    case_file = CASE_DIR / case.toml
    spec = tomllib.loads(case_file.read_text())
    work.mkdir(parents=True, exist_ok=True)
    msh = work / "mesh.msh"
    t_mesh = mesh_case(case_file, spec, size, msh)
    mesh = read_msh41(msh)
    probe_nodes = [int(v) for _, conn in mesh.groups[case.probe][1] for v in conn.ravel()]
    probe_xy = np.array([mesh.coords[n] for n in probe_nodes])
    scale = max(max(abs(x), abs(y)) for x, y in mesh.coords.values())
    res: dict = {"case": case.name, "title": case.title, "size": size, "gmsh_s": t_mesh,
                 "probe": case.probe, "component": "rz"[case.component], "probe_xy": probe_xy.tolist()}
    print(f"== {case.name} (size factor {size}): {len(mesh.coords)} mesh nodes, gmsh {t_mesh:.2f} s", flush=True)

    # asperity
    adir = work / "asperity"
    if adir.exists():
        shutil.rmtree(adir)
    adir.mkdir()
    run_toml = work / "case.toml"
    case_with_mesh(case_file, msh.resolve(), run_toml)
    # The same run `repeat` times (the answers are the same bits every time): its median wall
    # time is the one compared, so that one slow or fast moment of the machine decides nothing.
    runs = []
    for _ in range(repeat):
        m = measure([str(binary), "run", str(run_toml), "--out", str(adir / "out"), "--force"], adir,
                    timeout=timeout)
        runs.append((m, parse_asperity_summary(m.stdout, adir / "out")))
        if m.returncode != 0:
            break
    walls = sorted(m.wall for m, _ in runs)
    m, summary = sorted(runs, key=lambda run: run[0].wall)[(len(runs) - 1) // 2]
    a = {"wall_s": m.wall, "walls_s": walls, "rss_mb": max(m.rss_mb for m, _ in runs),
         "ok": all(m.returncode == 0 for m, _ in runs)}
    a.update(summary)
    if m.returncode == 0:
        try:
            a["u"] = asperity_probe(adir / "out", probe_xy, scale).tolist()
        except (OSError, ValueError, KeyError) as e:
            a["ok"], a["error"] = False, f"reading the probe: {e}"
        hist = read_history_last(adir / "out")
        a["reactions"] = {s["group"]: hist.get(f"reaction_{s['group']}_y") for s in spec.get("support", [])}
    else:
        a["error"] = (m.stderr.strip() or m.stdout.strip()).splitlines()[-1:] or ["failed"]
    res["asperity"] = a
    print(f"   asperity: {'ok' if a['ok'] else 'FAILED'} {a.get('unknowns', '?')} unknowns, "
          f"{a['wall_s']:.2f} s" + (f" (median of {len(walls)}: {walls[0]:.2f}–{walls[-1]:.2f})" if len(walls) > 1 else "")
          + f", {a.get('iterations', '?')} Newton its, {a.get('cutbacks', '?')} cut-backs, "
          f"{a['rss_mb']:.0f} MB" + (f"  u_{res['component']} = {a['u'][case.component]:.9e}" if "u" in a else "")
          + (f"  ERROR {a.get('error')}" if not a["ok"] else ""), flush=True)

    # CalculiX
    if case.calculix:
        cdir = work / "calculix"
        if cdir.exists():
            shutil.rmtree(cdir)
        cdir.mkdir()
        deck = write_calculix(spec, mesh, case, cdir / "job.inp")
        env = dict(os.environ, OMP_NUM_THREADS="2")
        m = measure(["ccx", "-i", "job"], cdir, env=env, timeout=timeout)
        sta = read_sta(cdir / "job.sta")
        eq = re.search(r"number of equations\s+(\d+)", m.stdout)
        c = {"wall_s": m.wall, "rss_mb": m.rss_mb, "increments": sta["increments"], "iterations": sta["iterations"],
             "equations": int(eq.group(1)) if eq else None,
             "cutbacks": sta["cutbacks"], "all_iterations": count_cvg(cdir / "job.cvg"),
             "nodes": deck["nodes"], "elements": deck["elements"]}
        finished = "Job finished" in m.stdout and abs(sta["time"] - 1.0) < 1e-6
        dat = read_dat(cdir / "job.dat", deck["probe_nodes"]) if (cdir / "job.dat").is_file() else {"u": None}
        c["ok"] = m.returncode == 0 and finished and dat.get("u") is not None
        if dat.get("u") is not None:
            c["u"] = [float(v) for v in dat["u"]]
        # reaction totals: CalculiX reports them for the 2-degree segment of the expansion
        c["reactions"] = {g: (dat["rf"][g.lower()][1] * 180.0 if g.lower() in dat.get("rf", {}) else None)
                          for g in deck["supports"]}
        if not c["ok"]:
            spooles = cdir / "spooles.out"
            text = m.stdout + m.stderr + (spooles.read_text(errors="replace") if spooles.is_file() else "")
            err = [l.strip() for l in text.splitlines()
                   if "ERROR" in l or "error" in l.lower() or "singular" in l or "killed after" in l]
            c["error"] = err[-3:] + [f"exit status {m.returncode}, step time reached {sta['time']:g}"]
        res["calculix"] = c
        print(f"   CalculiX: {'ok' if c['ok'] else 'FAILED'} {c['equations']} equations, {c['wall_s']:.2f} s, "
              f"{c['increments']} increments, {c['iterations']} Newton its ({c['all_iterations']} incl. "
              f"cut-back attempts), {c['rss_mb']:.0f} MB"
              + (f"  u_{res['component']} = {c['u'][case.component]:.9e}" if "u" in c else "")
              + (f"  ERROR {c.get('error')}" if not c["ok"] else ""), flush=True)
        if a["ok"] and c["ok"]:
            ua, uc = a["u"][case.component], c["u"][case.component]
            rel = abs(ua - uc) / max(abs(uc), 1e-300)
            res["rel_diff"] = rel
            res["agree"] = rel <= TOLERANCE
            res["speedup"] = c["wall_s"] / a["wall_s"] if a["wall_s"] > 0 else None
            print(f"   displacement under the load u_{res['component']}: CalculiX {uc:.9e}, asperity {ua:.9e}, "
                  f"relative difference {rel:.2e} -> {'agree' if res['agree'] else 'DIFFER'} (tolerance {TOLERANCE:g})")
            for g in deck["supports"]:
                ra, rc = a.get("reactions", {}).get(g), c["reactions"].get(g)
                if ra is not None and rc is not None:
                    print(f"   reaction {g} (z, full ring): CalculiX {rc:.6e} N, asperity {ra:.6e} N")
    return res


# --------------------------------------------------------------------------------------------
# table
# --------------------------------------------------------------------------------------------
def cpu_name() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "?"


def table(results: list[dict], mode: str, version: str, binary: Path, load: tuple[float, float]) -> str:
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    rev = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    try:
        shown = str(binary.relative_to(ROOT))
    except ValueError:
        shown = str(binary)
    counts = sorted({len(r["asperity"].get("walls_s", [])) for r in results if r.get("asperity")})
    repeats = (f"; asperity's wall is the median of {'/'.join(map(str, counts))} runs of the same case "
               "(their range is the column *asperity range*), CalculiX's that of one run"
               if counts and counts[-1] > 1 else "")
    lines = [BLOCK_BEGIN,
             f"### asperity against CalculiX {version}, {mode} meshes, {now}, {cpu_name()}, {os.cpu_count()} cores",
             "",
             f"`make bench-calculix` (`benches/calculix/bench_calculix.py`; asperity: `{shown}`, repository at "
             f"commit {rev or '?'}; ccx from Debian's `calculix-ccx`). "
             "Both programs solve the same gmsh mesh (quadratic quads; CalculiX CAX8), the same loads and "
             "supports, and the same linear penalty interface (CalculiX face-to-face penalty contact, "
             "PRESSURE-OVERCLOSURE=LINEAR with slope k_N, *FRICTION with μ and stick slope k_T) in the same "
             "fixed increments (*STATIC, DIRECT). CalculiX runs SPOOLES with OMP_NUM_THREADS=2 and its default "
             "convergence criteria; asperity its defaults. *Wall* is the whole run without meshing (gmsh "
             "meshes once, beforehand) and includes writing results (asperity: VTU and CSV every increment; "
             "CalculiX: .frd with U and S, .dat)" + repeats + "; *memory* is the peak resident set size; *its* are Newton "
             "iterations over the run (CalculiX: from the .sta file, converged attempts); *ratio* is CalculiX's "
             "wall time over asperity's. *u* is the displacement under the load (the case's probe point), "
             f"which must agree to {TOLERANCE:g} relative. Load average (1 min) before the runs {load[0]:.2f}"
             + (" (the machine was busy: the times are not representative)"
                if load[0] > 0.5 * (os.cpu_count() or 1) else "") + f", after them {load[1]:.2f}.",
             "",
             "| case | unknowns | increments | CalculiX wall [s] | CalculiX its | CalculiX memory [MB] | asperity wall [s] | asperity range [s] | asperity its (cut-backs) | asperity memory [MB] | ratio | u CalculiX [mm] | u asperity [mm] | rel. difference |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        a, c = r.get("asperity", {}), r.get("calculix")
        comp = 0 if r["component"] == "r" else 1

        def num(d, key, f="{:.2f}"):
            return f.format(d[key]) if d and d.get(key) is not None else "–"
        uc = f"{c['u'][comp]:.6e}" if c and "u" in c else ("–" if c is None else "failed")
        ua = f"{a['u'][comp]:.6e}" if "u" in a else "failed"
        rel = f"{r['rel_diff']:.1e}" + ("" if r.get("agree") else " (DIFFER)") if "rel_diff" in r else "–"
        a_its = f"{a.get('iterations', '?')} ({a.get('cutbacks', '?')})" if a.get("ok") else "failed"
        c_its = (f"{c['iterations']}" if c and c.get("ok") else ("failed" if c else "–"))
        ratio = f"{r['speedup']:.2f}" if r.get("speedup") else "–"
        walls = a.get("walls_s") or []
        spread = f"{walls[0]:.2f}–{walls[-1]:.2f}" if len(walls) > 1 else "–"
        lines.append(f"| {r['title']} (`{r['case']}`, u_{r['component']}) | {a.get('unknowns', '?')} | "
                     f"{c['increments'] if c else a.get('increments', '?')} | {num(c, 'wall_s')} | {c_its} | "
                     f"{num(c, 'rss_mb', '{:.0f}')} | {num(a, 'wall_s')} | {spread} | {a_its} | {num(a, 'rss_mb', '{:.0f}')} | "
                     f"{ratio} | {uc} | {ua} | {rel} |")
    phases = [(r, r["asperity"].get("phases")) for r in results if r.get("asperity", {}).get("phases")]
    if phases:
        keys = []
        for _, ph in phases:
            keys += [k for k in ph if k not in keys]
        lines += ["", "asperity's own time by phase [s], from its closing summary (gmsh ran beforehand; *wall* as above):", "",
                  "| case | " + " | ".join(keys) + " | wall |", "|---|" + "---|" * (len(keys) + 1)]
        for r, ph in phases:
            lines.append(f"| `{r['case']}` | " + " | ".join(f"{ph[k]:.3f}" if k in ph else "–" for k in keys)
                         + f" | {r['asperity']['wall_s']:.2f} |")
    lines += ["", BLOCK_END]
    return "\n".join(lines)


def write_block(path: Path, block: str) -> None:
    text = path.read_text() if path.is_file() else "# Benchmarks\n"
    begin = text.find(BLOCK_BEGIN.split(" (")[0])
    end = text.find(BLOCK_END)
    if begin >= 0 and end > begin:
        text = text[:begin] + block + text[end + len(BLOCK_END):]
    else:
        text = text.rstrip("\n") + "\n\n" + block + "\n"
    tmp = path.with_suffix(".md.tmp")
    tmp.write_text(text)
    tmp.replace(path)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="small meshes (a few thousand unknowns): checks the agreement in minutes")
    p.add_argument("--case", action="append", metavar="NAME", help="run only these cases (repeatable): " + ", ".join(c.name for c in CASES))
    p.add_argument("--size", type=float, help="override the mesh size factor of every selected case")
    p.add_argument("--write", action="store_true", help="write/replace the table block in BENCHMARKS.md")
    p.add_argument("--benchmarks", default=str(ROOT / "BENCHMARKS.md"), help="the file --write edits (default: BENCHMARKS.md)")
    p.add_argument("--bin", help="asperity binary (default target/release/asperity)")
    p.add_argument("--out", help="work folder (default build/bench_calculix/<quick|full>)")
    p.add_argument("--timeout", type=float, default=3600.0, help="seconds allowed per program run (default 3600)")
    p.add_argument("--no-calculix", action="store_true", help="run asperity only")
    p.add_argument("--repeat", type=int, default=5, metavar="N",
                   help="run asperity N times per case and compare its median wall time (default 5; "
                        "CalculiX runs once: its runs take minutes)")
    args = p.parse_args()
    if not 1 <= args.repeat <= 100:
        p.error(f"--repeat {args.repeat}: give 1 to 100 runs")

    selected = CASES
    if args.case:
        known = {c.name: c for c in CASES}
        unknown = [n for n in args.case if n not in known]
        if unknown:
            p.error(f"unknown case(s) {unknown}; known: {', '.join(known)}")
        selected = [known[n] for n in args.case]
    mode = "quick" if args.quick else "full"
    work = (Path(args.out) if args.out else ROOT / "build" / "bench_calculix" / mode).resolve()
    binary = find_binary(args.bin)
    apt_install("gmsh", "gmsh")
    if not args.no_calculix:
        apt_install("calculix-ccx", "ccx")
    version = ccx_version() if not args.no_calculix else "-"
    print(f"asperity: {binary}\nCalculiX: ccx {version} (OMP_NUM_THREADS=2)\nwork folder: {work}\n"
          f"load average: {' '.join(f'{v:.2f}' for v in os.getloadavg())} on {os.cpu_count()} cores", flush=True)

    load_before = os.getloadavg()[0]
    if load_before > 0.5 * (os.cpu_count() or 1):
        print(f"warning: load average {load_before:.2f} on {os.cpu_count()} cores: timings will not be representative",
              flush=True)
    results = []
    failed = False
    for case in selected:
        if args.no_calculix:
            case = Case(**{**case.__dict__, "calculix": False})
        size = args.size or (case.size_quick if args.quick else case.size_full)
        r = run_case(case, size, work / case.name, binary, args.timeout, args.repeat)
        results.append(r)
        if not r["asperity"].get("ok") or (r.get("calculix") and not r["calculix"].get("ok")) \
                or ("agree" in r and not r["agree"]):
            failed = True
    (work / "results.json").write_text(json.dumps(results, indent=1, default=float))
    block = table(results, mode, version, binary, (load_before, os.getloadavg()[0]))
    print("\n" + block)
    if args.write:
        write_block(Path(args.benchmarks), block)
        print(f"\nwritten to {args.benchmarks}")
    compared = sum("agree" in r for r in results)
    verdict = ("SOME CASES FAILED OR DIFFER" if failed else
               f"ALL {compared} COMPARED CASES AGREE" if compared else "asperity only: nothing compared")
    print(f"\n{verdict} (tolerance {TOLERANCE:g} on the displacement under the load)")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
