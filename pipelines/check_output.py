#!/usr/bin/env python3
"""Checks a finished run the way a user's ParaView/pyvista session would see it.

Usage: check_output.py OUT_DIR

Fails (exit 1) when an expected array is missing, a value is not finite, the .pvd series does
not list every converged step of history.csv, or - for the thick-cylinder example - the bore
displacement differs from Lamé's closed form by more than 1e-4 (the mesh has 8 quadratic
elements through the wall; the solver tests measure 4e-6 at that density, so 1e-4 leaves
room only for a real defect such as wrong loads or a wrong axisymmetric weighting).
"""
import csv
import math
import sys
from pathlib import Path

import numpy as np
import pyvista as pv

POINT_ARRAYS = {"displacement": 3, "stress": 6, "von_mises": 1}
CELL_ARRAYS = {"body": 1}


def check_grid(path: Path) -> pv.UnstructuredGrid:
    grid = pv.read(path)
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


def main() -> None:
    out = Path(sys.argv[1])
    reader = pv.get_reader(out / "results.pvd")
    with open(out / "history.csv") as f:
        history = list(csv.DictReader(f))
    if len(reader.time_values) != len(history):
        sys.exit(f"results.pvd lists {len(reader.time_values)} steps, history.csv {len(history)}")
    grids = [check_grid(p) for p in sorted(out.glob("bodies_*.vtu"))]
    last = grids[-1]
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
    print(f"{out}: {len(grids)} steps, arrays {sorted(last.array_names)}: ok")


if __name__ == "__main__":
    main()
