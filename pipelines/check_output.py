#!/usr/bin/env python3
"""Checks a finished run the way a user's ParaView/pyvista session would see it.

Usage: check_output.py OUT_DIR

Fails (exit 1) when an expected array is missing, a value is not finite, the .pvd series does
not list every converged step of history.csv, or - for the thick-cylinder example - the bore
displacement differs from Lamé's closed form by more than 1e-4 (the mesh has 8 quadratic
elements through the wall; the solver tests measure 4e-6 at that density, so 1e-4 leaves
room only for a real defect such as wrong loads or a wrong axisymmetric weighting); for the
shrink fit, the contact pressure differs from delta / (C + 1/k_N) by more than 1e-3 (6
elements through each wall; measured 6e-6 in the solver tests) or the interface arrays are
incomplete; or when pyvista does not show the bodies and contact pairs by name.
"""
import csv
import json
import math
import sys
from pathlib import Path

import numpy as np
import pyvista as pv
from asperity_tools import frame_parts, frames, read_frame, read_vtu, run_main

POINT_ARRAYS = {"displacement": 3, "stress": 6, "von_mises": 1, "equivalent_plastic_strain": 1}
CELL_ARRAYS = {"body": 1, "plastic": 1}
INTERFACE_ARRAYS = [
    "contact_normal_stress", "contact_pressure", "contact_shear_stress", "normal_gap",
    "tangential_slip", "plastic_slip", "friction_coefficient", "contact_status",
    "normal_stiffness", "tangential_stiffness",
]


def check_grid(path: Path) -> pv.UnstructuredGrid:
    grid = read_vtu(path)
    for name, ncomp in POINT_ARRAYS.items():
        if name not in grid.point_data:
            sys.exit(f"{path}: point array '{name}' missing (have {list(grid.point_data)})")
        arr = np.asarray(grid.point_data[name])
        if (arr.ndim == 1 and ncomp != 1) or (arr.ndim == 2 and arr.shape[1] != ncomp):
            sys.exit(f"{path}: '{name}' has shape {arr.shape}, expected {ncomp} components")
        if not np.all(np.isfinite(arr)):
            sys.exit(f"{path}: '{name}' has non-finite values")
    for name in CELL_ARRAYS:
        if name not in grid.cell_data:
            sys.exit(f"{path}: cell array '{name}' missing")
    types = set(np.unique(grid.celltypes))
    if not types <= {22, 23}:
        sys.exit(f"{path}: unexpected cell types {types} (expected quadratic 22/23)")
    return grid


def check_interface(path: Path) -> pv.UnstructuredGrid:
    grid = read_vtu(path)
    for name in INTERFACE_ARRAYS:
        if name not in grid.point_data:
            sys.exit(f"{path}: interface array '{name}' missing (have {list(grid.point_data)})")
        if not np.all(np.isfinite(grid.point_data[name])):
            sys.exit(f"{path}: '{name}' has non-finite values")
    if set(np.unique(grid.celltypes)) != {21}:
        sys.exit(f"{path}: interface cells must be quadratic edges (21)")
    status = np.asarray(grid.point_data["contact_status"])
    if not set(np.unique(status)) <= {0, 1, 2}:
        sys.exit(f"{path}: contact_status outside 0/1/2")
    return grid


def check_shrink_fit(out: Path, history: list) -> None:
    """Contact pressure against p = delta / (C + 1/k_N) (plane strain, solid shaft)."""
    b, c, e, nu, delta, k_n = 10.0, 20.0, 210000.0, 0.3, 0.01, 1e4
    e1, nu1 = e / (1 - nu**2), nu / (1 - nu)
    compliance = b * ((1 - nu1) / e1 + ((c * c + b * b) / (c * c - b * b) + nu1) / e1)
    exact = delta / (compliance + 1 / k_n)
    grid = read_frame(frames(out)[-1][1])["interface"]
    p = np.asarray(grid.point_data["contact_pressure"])
    err = np.max(np.abs(p - exact)) / exact
    print(f"contact pressure {p.min():.5f}..{p.max():.5f} MPa, closed form {exact:.5f} MPa, relative error {err:.2e}")
    if not err < 1e-3:
        sys.exit("contact pressure differs from the closed form")
    fn = float(history[-1]["fit_normal_force"])
    if not abs(fn + 2 * np.pi * b * 10.0 * exact) < 1e-3 * 2 * np.pi * b * 10.0 * exact:
        sys.exit(f"normal resultant {fn} is not -2 pi b L p")
    if not list(out.glob("contact_fit_*.csv")):
        sys.exit("contact CSV missing")


def check_blocks(out: Path) -> None:
    """`pyvista.read("results.pvd")` shows the parts by name: each frame's multiblock has the
    block `bodies` with a dataset per body and `contacts` with one per pair, named as the
    files' `body_names` and `pair_names`, each holding only its own cells and together the
    model's cells as summary.json counts them (each cell once)."""
    frame = pv.read(out / "results.pvd")[0]
    model = json.loads((out / "summary.json").read_text())["model"]
    blocks = [("bodies", "body", "elements")]
    if "contacts" in frame.keys():
        blocks.append(("contacts", "pair", "interface_elements"))
    for block, index, count in blocks:
        parts = frame[block]
        names = [str(n) for n in parts[0].field_data[f"{index}_names"]]
        if list(parts.keys()) != names:
            sys.exit(f"results.pvd: {block} blocks {parts.keys()}, expected {names}")
        for k, name in enumerate(names):
            if np.any(np.asarray(parts[name].cell_data[index]) != k):
                sys.exit(f"results.pvd: block '{name}' holds cells of other {block}")
        cells = sum(parts[name].n_cells for name in names)
        if cells != model[count]:
            sys.exit(f"results.pvd: the {block} blocks hold {cells} cells, the model {model[count]}")
    contacts = list(frame["contacts"].keys()) if "contacts" in frame.keys() else []
    print(f"results.pvd: blocks by name: bodies {list(frame['bodies'].keys())}, contacts {contacts}")


def main() -> None:
    out = Path(sys.argv[1])
    series = frames(out)
    with open(out / "history.csv") as f:
        # Step 0 (the unloaded state) has no files.
        history = [row for row in csv.DictReader(f) if int(row["step"]) > 0]
    if len(series) != len(history):
        sys.exit(f"results.pvd lists {len(series)} steps, history.csv {len(history)}")
    for _, vtm in series:
        parts = frame_parts(vtm)
        for _, path in parts["bodies"]:
            check_grid(path)
        for _, path in parts.get("contacts", []):
            check_interface(path)
    check_blocks(out)
    last = read_frame(series[-1][1])["bodies"]
    if "thick_cylinder" in str(out):
        a, b, p, e, nu = 10.0, 20.0, 100.0, 200000.0, 0.3
        exact = p * a * a * (1 + nu) * ((1 - 2 * nu) * a + b * b / a) / (e * (b * b - a * a))
        bore = np.isclose(last.points[:, 0], a)
        u = last.point_data["displacement"][bore, 0]
        err = np.max(np.abs(u - exact)) / exact
        print(f"bore displacement {u.mean():.6e} mm, Lame {exact:.6e} mm, relative error {err:.2e}")
        if not err < 1e-4:
            sys.exit("bore displacement differs from Lame's solution")
        fy = float(history[-1]["reaction_bottom_y"])
        if not math.isfinite(fy):
            sys.exit("non-finite reaction")
    if "shrink_fit" in str(out):
        check_shrink_fit(out, history)
    print(f"{out}: {len(series)} steps, arrays {sorted(last.array_names)}: ok")


if __name__ == "__main__":
    run_main(main)
