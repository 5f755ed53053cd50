#!/usr/bin/env python3
"""REPORT.md of a cyclic fretting run (`make fretting`): the case as run, the hysteresis loops,
the dissipation per cycle as the contact wears in, the wear-depth profiles, the worn volume
and largest depth at the end, the energy balance and the run time.

Usage: report.py OUT

Draws the figures with plot_hysteresis.py's functions and writes OUT/REPORT.md beside the
run's files (as the other examples write theirs). Every number in the report is read from the
run's files (run.json, summary.json, hysteresis_*.csv, cycles.csv, wear_*.csv); nothing about
the results is written into this script. Exits with status 2 when a file it needs is missing
or malformed.
"""
from __future__ import annotations

import argparse
import sys
from datetime import datetime
from pathlib import Path
from urllib.parse import quote

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from asperity_tools import rust_exp, table, write_report  # noqa: E402
from fretting_data import (ENERGY_TERMS, WEAR_COLUMNS, OutputError, contact_files, contact_name,  # noqa: E402
                           contact_rows, cycles_per_jump, cyclic_steps, read_case, read_cycles, read_json,
                           read_table, simulated_cycles, wear_profiles)
from plot_hysteresis import plot_all  # noqa: E402

ENERGY_FIELDS = ["external_work", *ENERGY_TERMS]


def _inline(value) -> str:
    """A case-file value as it reads in TOML (tables inline)."""
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_inline(v)}" for k, v in value.items()) + " }"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, list):
        return "[" + ", ".join(_inline(v) for v in value) + "]"
    return str(value)


def description(case_text: str) -> str:
    """The case file's opening comment block (what the case is, sources of its values)."""
    lines = []
    for line in case_text.splitlines():
        if not line.startswith("#"):
            break
        lines.append(line[1:].strip())
    return "\n".join(lines).strip()


def case_section(case: dict, case_file: str, case_text: str) -> str:
    """The case as run: its description, geometry, bodies, loads, interface, wear and steps."""
    mesh = case["mesh"]
    source = f"`{mesh['geo']}` meshed by gmsh at size factor {mesh.get('size', 1.0)}" if "geo" in mesh \
        else f"the mesh `{mesh['file']}`"
    params = ", ".join(f"{k} = {v}" for k, v in mesh.get("parameters", {}).items())
    wear = any("wear" in c for c in case.get("contact", []))
    lines = [f"Case file `{case_file}` (the text `run.json` records), {case['analysis']['type']} analysis; "
             f"geometry: {source}" + (f" with {params}" if params else "") + ".", ""]
    lines += [f"- body `{b['group']}`: {_inline(b['material'])}" for b in case.get("body", [])]
    lines += [f"- support `{s.get('name', s['group'])}` on `{s['group']}`: "
              + ", ".join(f"{k} = {v}" for k, v in s.items() if k not in ("name", "group")) for s in case.get("support", [])]
    lines += [f"- load `{ld.get('name', ld['group'])}` on `{ld['group']}`: "
              + ", ".join(f"{k} = {_inline(v)}" for k, v in ld.items() if k not in ("name", "group")) for ld in case.get("load", [])]
    for c in case.get("contact", []):
        lines.append(f"- contact `{contact_name(c)}` between `{c.get('side_a', c.get('body_a'))}` and "
                     f"`{c.get('side_b', c.get('body_b'))}`: law {_inline(c['law'])}"
                     + (f"; wear {_inline(c['wear'])}" if "wear" in c else "; no wear"))
    lines += [f"- amplitude `{a['name']}`: time {a['time']}, value {a['value']}" for a in case.get("amplitude", [])]
    rows = []
    for i, s in enumerate(case.get("step", []), start=1):
        cyclic = "cycles" in s
        rows.append([i, s.get("name", f"step-{i}"), s.get("increments", 1),
                     s["cycles"] if cyclic else "—",
                     cycles_per_jump(s, wear) if cyclic else "—",
                     simulated_cycles(s, wear) if cyclic else "—",
                     _inline(s.get("loads", {})) + (f", supports {_inline(s['supports'])}" if "supports" in s else "")])
    steps = table(["step", "name", "increments (per cycle)", "cycles", "cycles per jump ΔN", "simulated cycles", "loads"],
                  rows) if rows else "(no `[[step]]`: a `[steps]` schedule)"
    about = description(case_text)
    about = f"The case file's description:\n\n> " + about.replace("\n", "\n> ") + "\n\n" if about else ""
    return about + "\n".join(lines) + "\n\nSteps:\n\n" + steps


def jump_sentence(rows: dict[str, np.ndarray], contact: str) -> str:
    """How close the wear jumps of a contact came to their stability limit, and the jump that
    limit would allow (the share grows about linearly with the cycles a jump adds)."""
    share = rows["jump_limit_share"]
    if not share.any():
        return ""
    i = int(np.argmax(share))
    jumped = rows["cycles"][i] - rows["cycles"][i - 1] if i > 0 else 1.0
    text = (f"\n\nContact `{contact}`: the wear jumps added at most {100 * share[i]:.3g} % of the stability limit "
            f"(`jump_limit`) at a point (cycle ending at N = {rows['cycles'][i]:.0f})")
    if share[i] < 0.5 and jumped > 1:
        allowed = 1 + (jumped - 1) / share[i]
        text += (f"; the limit would allow jumps of about {allowed:.3g} cycles instead of {jumped:.0f} — check a "
                 f"larger `cycles_per_jump` against a run with half of it")
    return text + "."


def dissipation_section(cycles: dict[str, np.ndarray], contact: str) -> str:
    """The per-cycle table of one contact and what it shows: the first against the last
    simulated cycle, and how many times the dissipation fell from one cycle to the next."""
    rows = contact_rows(cycles, contact)
    d = rows["dissipation"]
    if not len(d):
        return f"`{contact}`: no row in cycles.csv."
    body = table(["step", "simulated cycle", "cycles N", "dissipation per cycle [N·mm]", "relative to the first",
                  "re-seating after the jump [N·mm]", "worn volume [mm³]", "max wear depth [µm]"],
                 [[int(k), int(c), f"{n:.0f}", float(e), float(e / d[0]) if d[0] else "—", float(r), float(v),
                   float(1e3 * h)]
                  for k, c, n, e, r, v, h in zip(rows["analysis_step"], rows["cycle"], rows["cycles"], d,
                                                 rows["settling_dissipation"], rows["worn_volume"],
                                                 rows["max_wear_depth"])])
    if len(d) < 2:
        return body
    body += jump_sentence(rows, contact)
    change = (d[-1] - d[0]) / d[0] if d[0] else float("nan")
    falls = int(np.sum(np.diff(d) < 0))
    trend = "fell" if d[-1] < d[0] else "rose" if d[-1] > d[0] else "stayed"
    return (body + f"\n\nContact `{contact}`: the dissipation per cycle {trend} from {d[0]:.4g} N·mm in the first "
            f"simulated cycle to {d[-1]:.4g} N·mm in the last ({100 * change:+.1f} %); it fell from one simulated "
            f"cycle to the next {falls} times out of {len(d) - 1}.")


def wear_section(out: Path, cycles: dict[str, np.ndarray] | None, contacts: list[str], wearing: set[str]) -> str:
    """Largest depth and worn volume at the end of the run, from cycles.csv and the last wear
    profile of each contact."""
    parts = []
    for contact, path in contact_files(out, "wear").items():
        profiles = wear_profiles(read_table(path, WEAR_COLUMNS))
        if not profiles:
            continue
        n, p = profiles[-1]
        i = int(np.argmax(p["wear_depth"]))
        first_n, first = profiles[0]
        text = (f"Contact `{contact}` after N = {n:.0f} cycles ({len(profiles)} profiles, one per jump): largest wear "
                f"depth {1e3 * p['wear_depth'][i]:.4g} µm at s = {p['s'][i]:.4g} mm (x = {p['x'][i]:.4g}, "
                f"y = {p['y'][i]:.4g} mm), of which side A {1e3 * p['wear_a'][i]:.4g} µm and side B "
                f"{1e3 * p['wear_b'][i]:.4g} µm; after the first jump (N = {first_n:.0f}) it was "
                f"{1e3 * first['wear_depth'].max():.4g} µm.")
        if cycles is not None and len(contact_rows(cycles, contact)["cycles"]):
            last = contact_rows(cycles, contact)
            text += (f" cycles.csv at N = {last['cycles'][-1]:.0f}: worn volume {last['worn_volume'][-1]:.4g} mm³, "
                     f"largest depth {1e3 * last['max_wear_depth'][-1]:.4g} µm.")
        parts.append(text + f"\n\n![wear profiles of {contact}]({quote(f'wear_{contact}.png')})")
    for c in contacts:
        if not (out / f"wear_{c}.csv").is_file():
            parts.append(f"**`wear_{c}.csv` is missing although contact `{c}` has wear.**" if c in wearing
                         else f"Contact `{c}` has no wear.")
    return "\n\n".join(parts)


def energy_section(summary: dict, cyclic: set[int]) -> str:
    """The energy balance of summary.json: totals, per step, and per simulated cycle of the
    `cyclic` steps."""
    energy = summary.get("energy")
    if not energy:
        return "summary.json has no `energy` record."
    fields = [*ENERGY_FIELDS, "imbalance"]
    records = [energy.get("total", {}), *energy.get("steps", []), *energy.get("cycles", [])]
    lacking = sorted({f for r in records for f in fields if not isinstance(r.get(f), (int, float))})
    if lacking:
        return f"**summary.json's `energy` records lack (or have no number for) {', '.join(lacking)}.**"

    def relative(e: dict) -> str:
        return rust_exp(e["imbalance"] / abs(e["external_work"])) if e["external_work"] else "—"

    total = energy["total"]
    body = table(["term", "total [N·mm]"], [[f, float(total[f])] for f in ENERGY_FIELDS]
                 + [["imbalance", rust_exp(total["imbalance"])], ["imbalance relative to the external work", relative(total)]])
    steps = energy.get("steps", [])
    if steps:
        body += "\n\nPer step:\n\n" + table(["step", *ENERGY_FIELDS, "imbalance", "relative"],
                                            [[s["name"], *(float(s[f]) for f in ENERGY_FIELDS), rust_exp(s["imbalance"]),
                                              relative(s)] for s in steps])
    per_cycle = [c for c in energy.get("cycles", []) if c.get("analysis_step") in cyclic]
    if per_cycle:
        ratios = [abs(c["imbalance"]) / abs(c["external_work"]) for c in per_cycle if c["external_work"]]
        friction = np.array([c["friction_dissipation"] for c in per_cycle])
        body += (f"\n\nPer simulated cycle of the cyclic steps ({len(per_cycle)} records; the work of one simulated "
                 f"cycle): friction "
                 f"dissipation from {friction[0]:.4g} to {friction[-1]:.4g} N·mm, wear work from "
                 f"{per_cycle[0]['wear_work']:.4g} to {per_cycle[-1]['wear_work']:.4g} N·mm; largest |imbalance| "
                 f"{rust_exp(max(abs(c['imbalance']) for c in per_cycle))} N·mm"
                 + (f", at most {rust_exp(max(ratios))} of the cycle's external work." if ratios else "."))
    return (body + "\n\nThe imbalance is external work − (elastic + interface energy + plastic, frictional, wear and "
            "numerical dissipation): the work of the out-of-balance forces the Newton iterations leave, a "
            "convergence check (README, `summary.json`).")


def _seconds(start: str | None, end: str | None) -> float | None:
    if not start or not end:
        return None
    return (datetime.fromisoformat(end.replace("Z", "+00:00"))
            - datetime.fromisoformat(start.replace("Z", "+00:00"))).total_seconds()


def run_time_section(summary: dict, info: dict) -> str:
    totals, seconds = summary.get("totals", {}), summary.get("seconds", {})
    wall = _seconds(info.get("start"), info.get("end"))
    phases = ", ".join(f"{p} {seconds[p]:.3f}" for p in ("mesh", "model", "symbolic", "assembly", "factorisation",
                                                         "solve", "output") if seconds.get(p) is not None)
    model = summary.get("model") or {}
    size = ", ".join(f"{v} {k.replace('_', ' ')}" for k, v in model.items() if v is not None)
    lines = [f"- status `{summary.get('status')}`; {len(summary.get('steps', []))} output frames, "
             f"{totals.get('increments')} increments ({totals.get('cutbacks')} cut-backs), "
             f"{totals.get('iterations')} Newton iterations; model: {size or 'not built'}",
             f"- solver time (summary.json): {seconds.get('total', float('nan')):.2f} s in all; phases [s]: {phases}"]
    if wall is not None:
        lines.append(f"- wall time of the run (run.json, {info['start']} to {info['end']}): {wall:.1f} s on "
                     f"`{info.get('host')}` with {info.get('threads')} threads")
    return "\n".join(lines)


OWN_GEOMETRY = """Everything about the shape is in the case file's `[mesh]` and the group names; nothing in the
scripts refers to the taper. To study your own joint:

1. Point `[mesh]` at your gmsh script (`geo = "my_joint.geo"`, with `size` and `parameters` for its
   `DefineConstant`s) or at an MSH 4.1 file (`file = "my_joint.msh"`), with quadratic elements and
   physical groups for the bodies, the loaded and supported curves and both faces of the joint
   (README, "Meshes and the naming convention").
2. Rename the groups in `[[body]]`, `[[support]]`, `[[load]]` and `[[contact]]` (`side_a`, `side_b`)
   to yours; keep the load's `name` (the steps refer to it) or rename it there too.
3. Set the materials, the interface law, the wear coefficient(s) and the service amplitude, `cycles`
   and `cycles_per_jump` of your joint.
4. `make fretting FRETTING_CASE=path/to/my_case.toml` (results in `out/fretting`, or set
   `FRETTING_OUT`), or `asperity run my_case.toml --out OUT` then `pipelines/fretting/report.py OUT`."""


def write(out: Path) -> Path:
    info = read_json(out / "run.json")
    summary = read_json(out / "summary.json")
    case = read_case(out)
    figures, notes = plot_all(out)
    contacts = list(contact_files(out, "hysteresis"))
    wearing = {contact_name(c) for c in case.get("contact", []) if "wear" in c}
    cycles = read_cycles(out, set(cyclic_steps(case)))
    loops = "\n\n".join(f"![{caption}]({quote(path.name)})" for caption, path in figures
                          if path.name.startswith("hysteresis_"))
    point_loops = "\n\n".join(f"![{caption}]({quote(path.name)})" for caption, path in figures
                                if path.name.startswith("point_loops_"))
    if point_loops:
        loops += ("\n\nThe points the case traces (`hysteresis_points`): shear stress p_T against the "
                  "tangential relative displacement u_T of each, one loop per simulated cycle "
                  "(`point_loops_<contact>.csv`).\n\n" + point_loops)
    steps = ", ".join(f"{i} (`{s.get('name', f'step-{i}')}`)" for i, s in cyclic_steps(case).items()) or "none"
    if cycles is not None:
        dissipation = ("\n\n".join(dissipation_section(cycles, c) for c in contacts)
                       + "\n\n![dissipation and worn volume](cycles.png)")
    else:
        dissipation = ("**`cycles.csv` is missing although the case has cyclic steps.**" if cyclic_steps(case)
                       else "The case has no cyclic step, so the run wrote no `cycles.csv`.")
    sections = [
        ("The case", case_section(case, info.get("case_file", "?"), info.get("case", ""))),
        ("Hysteresis loops", f"""Tangential force ∫p_T dA of each contact against its mean relative slip (the area-weighted
mean of u_T over the closed points), one loop per simulated cycle of the cyclic steps ({steps}),
coloured by the cycles reached; in grey the frames before them. Right: each loop minus the
straight line through its turning points, which shows its opening.

{loops}"""),
        ("Dissipation per cycle as the contact wears in", dissipation),
        ("Wear", wear_section(out, cycles, contacts, wearing)),
        ("Energy balance", energy_section(summary, set(cyclic_steps(case)))),
        ("Run time", run_time_section(summary, info)),
        ("Your own geometry", OWN_GEOMETRY),
    ]
    if notes:
        sections.append(("Notes", "\n".join(f"- {n}" for n in notes)))
    path = out / "REPORT.md"
    write_report(path, f"Fretting run: {Path(info.get('case_file', 'case')).name}", sections)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="output folder of the run")
    out = parser.parse_args().out
    try:
        path = write(out)
    except OutputError as error:
        print(f"report.py: {error}", file=sys.stderr)
        sys.exit(2)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
