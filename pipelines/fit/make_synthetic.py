"""Writes the synthetic joint test of the worked example of docs/guide/fitting.md (`asperity fit`).

The curves follow the closed forms of the rough-joint law (Buczkowski & Kleiber 1994,
Eqs. 1-5), written out here independently of asperity's implementation:
- normal loading p = (c / c_N)^(1/m), unloading from (c_max, p_max) along
  c - c_perm = c_Nu p^(m_u) with c_perm = c_max - c_Nu p_max^(m_u);
- monotonic shear at constant pressure p: stick p_T = k_T u with k_T = (p^2 + p0^2)^(S/2) / R,
  then slip with p_T = mu_F(us) p, mu_F = mu_m [1 - (1 - beta) exp(-n us)], us = u - p_T / k_T.
Measured values get 1 % Gaussian noise plus 0.005 MPa (seeded), the errors the fit file states.

    .venv/bin/python pipelines/fit/make_synthetic.py   # rewrites examples/fit/*.csv
"""
import pathlib

import numpy as np

TRUE = dict(c_n=2e-3, m=0.5, unloading_c_n=4e-4, unloading_m=0.8, R=2e-3, S=0.5,
            mu_m=0.3, beta=0.6, n=50.0, starting_pressure=0.1)
DATA_DIR = pathlib.Path(__file__).resolve().parent.parent.parent / "examples" / "fit"  # the worked example's data
RNG = np.random.default_rng(20260415)


def noisy(y):
    return y + RNG.normal(0.0, 1.0, len(y)) * (0.01 * np.abs(y) + 0.005)


def normal_curve():
    t = TRUE
    up = np.linspace(0.2e-3, 8e-3, 40)
    down = np.linspace(7.8e-3, 4.5e-3, 20)
    c_max = up[-1]
    p_max = (c_max / t["c_n"]) ** (1 / t["m"])
    c_perm = c_max - t["unloading_c_n"] * p_max ** t["unloading_m"]
    p_up = (up / t["c_n"]) ** (1 / t["m"])
    p_down = (np.maximum(down - c_perm, 0) / t["unloading_c_n"]) ** (1 / t["unloading_m"])
    return np.concatenate([up, down]), np.concatenate([p_up, p_down])


def shear_curve(p):
    t = TRUE
    kt = (p * p + t["starting_pressure"] ** 2) ** (t["S"] / 2) / t["R"]
    u = np.concatenate([np.linspace(0.2e-3, 4e-3, 20), np.linspace(5e-3, 0.08, 25)])
    pt = []
    for ui in u:
        stick = kt * ui
        if stick <= t["mu_m"] * t["beta"] * p:
            pt.append(stick)
            continue
        lo, hi = 0.0, stick  # slip: solve p_T = mu_F(u - p_T/k_T) p by bisection
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            us = ui - mid / kt
            mu = t["mu_m"] * (1 - (1 - t["beta"]) * np.exp(-t["n"] * us))
            lo, hi = (mid, hi) if mid < mu * p else (lo, mid)
        pt.append(0.5 * (lo + hi))
    return u, np.array(pt)


def write(name, header, rows):
    with open(DATA_DIR / name, "w") as f:
        f.write(header)
        for r in rows:
            f.write(",".join(f"{v:.9g}" for v in r) + "\n")


if __name__ == "__main__":
    c, p = normal_curve()
    write("normal.csv",
          "# synthetic normal loading/unloading of a flat joint (make_synthetic.py)\n"
          "# units: time = s, closure = um, pressure = MPa\ntime,closure,pressure\n",
          zip(np.arange(len(c)), c * 1e3, noisy(p)))
    for level in (10.0, 30.0):
        u, pt = shear_curve(level)
        write(f"shear_{int(level)}MPa.csv",
              f"# synthetic tangential loading at a constant pressure of {level} MPa (make_synthetic.py)\n"
              "# units: time = s, displacement = mm, shear = MPa\ntime,displacement,shear\n",
              zip(np.arange(len(u)), u, noisy(pt)))
