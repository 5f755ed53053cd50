"""Shared helpers of the example pipelines: run case files in parallel, read the results,
write reports. Used by pipelines/<example>.py scripts; see README "Examples".

A pipeline script typically:
    cases = [variant(template, out_dir / "a.toml", {"mu_m = 0.2": "mu_m = 0.1"}), ...]
    run_cases([(case, out_dir / "a"), ...])   # mesh size: variant(..., size=...)
    history = read_history(out_dir / "a"); contact = read_contact(out_dir / "a", "joint")
    write_report(out_dir / "REPORT.md", "Title", [("Section", "markdown text"), ...])
"""
from __future__ import annotations

import csv
import os
import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
BINARY = ROOT / "target" / "release" / "asperity"


def variant(template: Path, path: Path, replacements: dict[str, str] | None = None, size: float | None = None) -> Path:
    """Writes a copy of the case `template` to `path` with textual `replacements` applied
    (each key must occur in the template, so a renamed parameter cannot be missed silently)
    and, if given, the mesh size factor replaced. Relative paths inside the case are made
    absolute so the copy works from any folder."""
    text = template.read_text()
    for old, new in (replacements or {}).items():
        if old not in text:
            raise ValueError(f"{template}: '{old}' not found for a variant")
        text = text.replace(old, new)
    if size is not None:
        text, count = re.subn(r"(?m)^size\s*=.*$", f"size = {size}", text)
        if count != 1:
            raise ValueError(f"{template}: expected one 'size =' line in [mesh]")
    base = template.resolve().parent

    def absolute(match: re.Match) -> str:
        key, value = match.group(1), match.group(2)
        return f'{key} = "{(base / value).resolve()}"'

    text = re.sub(r'(?m)^(geo|file)\s*=\s*"([^"/][^"]*)"', absolute, text)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def run_cases(runs: list[tuple[Path, Path]], jobs: int | None = None, fail_fast: bool = True) -> list[str]:
    """Runs `asperity run CASE --out DIR` for every (case, out) pair, as many at a time as
    there are cores, and returns each run's summary. Stops the pipeline with the run's error
    message if one fails, or, with `fail_fast=False`, returns "FAILED: <message>" for it."""
    if not BINARY.exists():
        sys.exit(f"{BINARY} not found: build it with `cargo build --release` (the Makefile does)")
    jobs = jobs or os.cpu_count() or 1

    def one(run: tuple[Path, Path]) -> str:
        case, out = run
        done = subprocess.run([str(BINARY), "run", str(case), "--out", str(out)], capture_output=True, text=True)
        if done.returncode != 0:
            message = done.stderr.strip() or done.stdout.strip()
            if not fail_fast:
                return f"FAILED: {message}"
            raise RuntimeError(f"{case}: {message}")
        (out / "summary.txt").write_text(done.stdout)
        return done.stdout

    with ThreadPoolExecutor(max_workers=jobs) as pool:
        try:
            return list(pool.map(one, runs))
        except RuntimeError as error:
            sys.exit(f"run failed: {error}")


def read_csv(path: Path) -> dict[str, np.ndarray]:
    """A CSV written by asperity as columns of floats."""
    with open(path) as f:
        rows = list(csv.reader(f))
    header, data = rows[0], np.array([[float(v) for v in r] for r in rows[1:]]).reshape(-1, len(rows[0]))
    return {name: data[:, i] for i, name in enumerate(header)}


def read_history(out: Path) -> dict[str, np.ndarray]:
    """history.csv of a run."""
    return read_csv(out / "history.csv")


def read_contact(out: Path, pair: str, step: int | None = None) -> dict[str, np.ndarray]:
    """The contact table of `pair` at `step` (default: the last step)."""
    files = sorted(out.glob(f"contact_{pair}_*.csv"))
    if not files:
        raise FileNotFoundError(f"{out}: no contact_{pair}_*.csv")
    if step is not None:
        files = [out / f"contact_{pair}_{step:04d}.csv"]
    return read_csv(files[-1])


def summary_line(summary: str, prefix: str) -> str:
    """The line of a run summary that starts with `prefix` (e.g. 'steps:')."""
    return next((l for l in summary.splitlines() if l.startswith(prefix)), "")


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
