"""Shared helpers of the example pipelines: build case variants, run case files in parallel,
read the results (summary.json and the CSV tables), write reports. Used by
pipelines/<example>.py scripts; see examples/README.md.

A pipeline script typically:
    cases = [variant(template, out_dir / "a.toml", {"contact[0].law.mu_m": 0.1}), ...]
    summaries = run_cases([(case, out_dir / "a"), ...])   # mesh size: variant(..., size=...)
    history = read_history(out_dir / "a"); contact = read_contact(out_dir / "a", "joint")
    summaries[0]["totals"]["iterations"]                   # summary.json of the run (docs/guide/outputs.md)
    write_report(out_dir / "REPORT.md", "Title", [("Section", "markdown text"), ...])

Nothing is read from what `asperity` prints: a run's numbers come from its summary.json and
CSV files.
"""
from __future__ import annotations

import csv
import json
import os
import re
import subprocess
import sys
import tempfile
import tomllib
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import tomli_w

ROOT = Path(__file__).resolve().parent.parent
BINARY = ROOT / "target" / "release" / "asperity"
PHASES = ["mesh", "model", "symbolic", "assembly", "factorisation", "solve", "output"]


def _key_path(key: str) -> list[str | int]:
    """`contact[0].law.R` -> ["contact", 0, "law", "R"]; `steps.factors[-1]` -> [..., -1]."""
    parts: list[str | int] = []
    for name in key.split("."):
        name, *indices = name.split("[")
        if name:
            parts.append(name)
        parts += [int(i.rstrip("]")) for i in indices]
    return parts


def _set(case: dict, key: str, value, create: bool, where: Path) -> None:
    """Sets `key` (a path as in `_key_path`) of the parsed case; the key must exist unless
    `create`, so that a renamed parameter cannot be missed silently."""
    *parents, last = _key_path(key)
    node = case
    try:
        for part in parents:
            node = node[part]
        if not create:
            node[last]
    except (KeyError, IndexError, TypeError):
        raise ValueError(f"{where}: no `{key}` for a variant") from None
    node[last] = value


def variant(template: Path, path: Path, changes: dict | None = None, size: float | None = None,
            new: dict | None = None) -> Path:
    """Writes a copy of the case `template` to `path` with the values of `changes` replaced
    (keys are paths into the case: `contact[0].law.R`, `body[1].material.hardening`,
    `steps.factors[-1]`; each must exist in the template), the keys of `new` added, and,
    if given, the mesh size factor replaced. The case is parsed with tomllib and written
    with tomli_w (comments are not kept). Relative mesh paths are made absolute so the copy
    works from any folder."""
    case = tomllib.loads(template.read_text())
    for key, value in (changes or {}).items():
        _set(case, key, value, False, template)
    for key, value in (new or {}).items():
        _set(case, key, value, True, template)
    if size is not None:
        _set(case, "mesh.size", float(size), False, template)
    base = template.resolve().parent
    for key in ("geo", "file"):
        if key in case["mesh"]:
            case["mesh"][key] = str((base / case["mesh"][key]).resolve())
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(tomli_w.dumps(case))
    return path


def read_summary(out: Path) -> dict:
    """summary.json of a run (docs/guide/outputs.md)."""
    return json.loads((out / "summary.json").read_text())


def run_cases(runs: list[tuple[Path, Path]], jobs: int | None = None, fail_fast: bool = True) -> list[dict]:
    """Runs `asperity run CASE --out DIR` for every (case, out) pair, as many at a time as
    there are cores, and returns each run's summary.json. Stops the pipeline with the run's
    error if one fails, or, with `fail_fast=False`, returns its summary (status "failed",
    "error"; a run that stopped before writing one gets {"status": "failed", "error": what
    it reported})."""
    if not BINARY.exists():
        sys.exit(f"{BINARY} not found: build it with `cargo build --release` (the Makefile does)")
    jobs = jobs or os.cpu_count() or 1

    def one(run: tuple[Path, Path]) -> dict:
        case, out = run
        (out / "summary.json").unlink(missing_ok=True)  # never read a previous run's
        # --force: replace a previous run's files (asperity refuses to overwrite them otherwise).
        done = subprocess.run([str(BINARY), "run", str(case), "--out", str(out), "--force"], capture_output=True,
                              text=True)
        try:
            summary = read_summary(out)
        except FileNotFoundError:
            # Stopped before the run began (e.g. an invalid case): only its message is known.
            summary = {"status": "failed", "error": done.stderr.strip() or done.stdout.strip()}
        if done.returncode != 0 and fail_fast:
            raise RuntimeError(f"{case}: {summary.get('error')}")
        return summary

    with ThreadPoolExecutor(max_workers=jobs) as pool:
        try:
            return list(pool.map(one, runs))
        except RuntimeError as error:
            sys.exit(f"run failed: {error}")


def phase_seconds(summary: dict) -> dict[str, float]:
    """Seconds of each phase of a converged run, in milliseconds' precision (as printed)."""
    return {p: round(summary["seconds"][p], 3) for p in PHASES}


def rust_exp(value: float, digits: int = 2) -> str:
    """`value` as Rust's `{:.2e}` writes it (as `asperity` prints residuals): 1.50e-13, 2.00e0."""
    mantissa, exponent = f"{value:.{digits}e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def read_csv(path: Path) -> dict[str, np.ndarray]:
    """A CSV written by asperity as columns of floats."""
    with open(path) as f:
        rows = list(csv.reader(f))
    header, data = rows[0], np.array([[float(v) for v in r] for r in rows[1:]]).reshape(-1, len(rows[0]))
    return {name: data[:, i] for i, name in enumerate(header)}


def read_history(out: Path, start: bool = False) -> dict[str, np.ndarray]:
    """history.csv of a run: one row per converged step. With `start`, also the row of the
    unloaded state (step 0) that asperity writes first, so that curves begin at the origin, and
    the row of the last converged sub-increment of a step that failed (fractional `time`)."""
    history = read_csv(out / "history.csv")
    if start:
        return history
    keep = (history["step"] > 0) & (history["time"] == np.round(history["time"]))
    return {name: values[keep] for name, values in history.items()}


def read_contact(out: Path, pair: str, step: int | None = None) -> dict[str, np.ndarray]:
    """The contact table of `pair` at `step` (default: the last step)."""
    files = sorted(out.glob(f"contact_{pair}_*.csv"))
    if not files:
        raise FileNotFoundError(f"{out}: no contact_{pair}_*.csv")
    if step is not None:
        files = [out / f"contact_{pair}_{step:04d}.csv"]
    return read_csv(files[-1])


def frames(out: Path) -> list[tuple[float, Path]]:
    """(time, `frame_NNNN.vtm`) of every output frame the series `out`/results.pvd lists, in
    order of time."""
    import xml.etree.ElementTree as ET

    entries = {(float(d.get("timestep")), d.get("file"))
               for d in ET.parse(out / "results.pvd").getroot().iter("DataSet")}
    return [(time, out / file) for time, file in sorted(entries)]


def frame_parts(vtm: Path) -> dict[str, list[tuple[str, Path]]]:
    """The blocks of a frame's multiblock file (`bodies`, and `contacts` with contact pairs),
    each a list of (part name, VTU file) in the case's order. Each cell is in one file: a
    model of one body has `bodies_NNNN.vtu`, one of several `bodies_NNNN_K.vtu` per body
    (the same for the pairs, `interface_...`; docs/guide/outputs.md)."""
    import xml.etree.ElementTree as ET

    return {block.get("name"): [(d.get("name"), vtm.parent / d.get("file")) for d in block.iter("DataSet")]
            for block in ET.parse(vtm).getroot().iter("Block")}


def read_vtu(path: Path):
    """The VTU file `path` as a pyvista grid; a file that is cut short or damaged (VTK only
    prints errors for it and gives a partial grid) raises ValueError naming it."""
    import pyvista as pv

    path = Path(path)
    with open(path, "rb") as f:
        head = f.read(4096).decode("utf-8", "replace")
        f.seek(max(0, path.stat().st_size - 64))
        tail = f.read().decode("utf-8", "replace")
    counts = re.search(r'NumberOfPoints="(\d+)"\s+NumberOfCells="(\d+)"', head)
    if counts is None or "</VTKFile>" not in tail:
        raise ValueError(f"{path}: not a complete VTU file (cut short or damaged)")
    grid = pv.read(path)
    if (grid.n_points, grid.n_cells) != (int(counts[1]), int(counts[2])):
        raise ValueError(f"{path}: {grid.n_cells} of its {counts[2]} cells could be read: the file is damaged")
    return grid


def run_main(main) -> None:
    """Runs a script's `main`, a damaged or missing input ending it with a one-line error
    (exit status 1) instead of a traceback."""
    import xml.etree.ElementTree as ET

    try:
        main()
    except (OSError, ValueError, KeyError, IndexError, TypeError, ET.ParseError) as e:
        what = f"{type(e).__name__}: {e}" if isinstance(e, (KeyError, IndexError, TypeError)) else str(e)
        sys.exit(f"error: {Path(sys.argv[0]).name}: {what}")


def read_frame(vtm: Path):
    """A frame's parts as a pyvista MultiBlock with the blocks `bodies` (all bodies in one
    UnstructuredGrid, cell data `body` telling them apart) and, with contact pairs,
    `interface` (all pairs, cell data `pair`); each keeps the field data of its VTU files
    (`TimeValue`, `load_factor`, `body_names`, `pair_names`)."""
    import pyvista as pv

    blocks = pv.MultiBlock()
    for block, key in (("bodies", "bodies"), ("contacts", "interface")):
        grids = [read_vtu(file) for _, file in frame_parts(vtm).get(block, [])]
        if grids:
            blocks[key] = grids[0] if len(grids) == 1 else pv.MultiBlock(grids).combine()
    return blocks


def read_step(out: Path, step: int | None = None):
    """Frame `step` (1-based position in the series results.pvd; default: the last) as
    `read_frame` gives it, whose own field_data `step` is that position."""
    series = frames(out)
    if not series or (step is not None and not 1 <= step <= len(series)):
        raise ValueError(f"{out / 'results.pvd'}: no step {step} (it lists {len(series)})")
    index = len(series) if step is None else step
    blocks = read_frame(series[index - 1][1])
    blocks.field_data["step"] = [index]
    return blocks


def solver_statistics(summary: dict) -> list[str]:
    """A run's counters and phase times (from its summary.json), worded as `asperity run`
    prints them."""
    t, s = summary["totals"], summary["seconds"]
    steps = (f"{t['steps']} converged in {t['increments']} increments ({t['cutbacks']} cut-backs), "
             f"{t['iterations']} Newton iterations ({t['unsymmetric_solves']} unsymmetric solves, "
             f"{t['krylov_iterations']} BiCGSTAB iterations); final relative residual "
             f"{rust_exp(summary['final_residual'])}")
    times = (f"mesh {s['mesh']:.3f}, model {s['model']:.3f}, ordering+symbolic {s['symbolic']:.3f}, "
             f"assembly {s['assembly']:.3f}, factorisation {s['factorisation']:.3f}, solve {s['solve']:.3f}, "
             f"output {s['output']:.3f}")
    if s.get("conduction"):  # only a run with conducting bodies has the conduction's phase
        times += f", conduction {s['conduction']:.3f}"
    return [steps, times]


class Checks:
    """The checks of a report: each is recorded as a line `PASS|FAIL what` (what carries the
    numbers compared and the tolerance); `failures` lists the failed ones, and `markdown` the
    lines as a list for REPORT.md."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.failures: list[str] = []

    def __call__(self, ok: bool, what: str) -> bool:
        ok = bool(ok)
        self.lines.append(f"{'PASS' if ok else '**FAIL**'} {what}")
        if not ok:
            self.failures.append(what)
        return ok

    def markdown(self) -> str:
        return "\n".join(f"- {line}" for line in self.lines)

    def exit_on_failure(self, name: str) -> None:
        """Exits non-zero, naming the failed checks, if one failed."""
        if self.failures:
            sys.exit(f"{name}: checks failed:\n  " + "\n  ".join(self.failures))


def body_points(grid, body: str) -> np.ndarray:
    """The point ids of body `body` (a `[[body]]` group) in a bodies grid of `read_step`
    (its cells' points; a body's points are its own, also where it touches another)."""
    index = list(grid.field_data["body_names"]).index(body)
    cells = np.flatnonzero(np.asarray(grid.cell_data["body"]) == index)
    return np.unique(grid.extract_cells(cells).point_data["vtkOriginalPointIds"])


def save_figure(fig, path: Path, dpi: int = 120) -> None:
    """Saves `fig` as the PNG `path` through a temporary file in its folder renamed onto it,
    as asperity writes its files: a symbolic link of that name is replaced, never written
    through, and no half-written PNG is left behind."""
    path = Path(path)
    fd, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            fig.savefig(f, format="png", dpi=dpi)
        os.chmod(temporary, 0o644)
        os.replace(temporary, path)
    except BaseException:
        os.unlink(temporary)
        raise


def write_report(path: Path, title: str, sections: list[tuple[str, str]]) -> None:
    """REPORT.md with a title and (heading, markdown) sections."""
    parts = [f"# {title}\n"] + [f"## {h}\n\n{body.strip()}\n" for h, body in sections]
    path.write_text("\n".join(parts))


def table(header: list[str], rows: list[list]) -> str:
    """A markdown table; floats are printed with 4 significant digits."""
    def cell(v) -> str:
        return f"{v:.4g}" if isinstance(v, float) else str(v)
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(cell(v) for v in r) + " |" for r in rows]
    return "\n".join(lines)
