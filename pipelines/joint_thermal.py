#!/usr/bin/env python3
"""Heat through a machine-tool slideway joint (issue 26): a carriage with a heat source
pressed on a guide; how the contact pressure sets the temperature jump across the joint, and
how the carriage's thermal strain changes the pressure.

Usage: joint_thermal.py [--out out/joint_thermal] [--size S] [--quick]

Runs pipelines/joint_thermal/case.toml (plane strain; steps press, heat, press harder) three
ways, in parallel:
  coupled       as written: h = h0 (|p|/1 MPa)^n and thermal strain, the two iterated
                (staggered) within every increment;
  no_expansion  the same without thermal strain (α = 0): the pressure no longer depends on
                the temperature;
  constant_h    the thermal strain, but a constant conductance, h0 (p_0/1 MPa)^n at the
                pressure p_0 of the press step: the temperatures no longer depend on the
                pressure;
and writes into OUT: one run folder per case, joint_profiles.png (pressure, conductance and
temperature jump along the joint at the end of the heating and at the end),
heat_flows.png, temperature.png (the coupled run's temperature on the deformed shape) and
REPORT.md. Checks (each in the report with its numbers; exit status 1 if one fails):
- heat balance at every frame of every run: the source's heat leaves through the base and
  the film to 1e-9 of it (steady state: round-off), and the carriage's own balance: what
  crosses the joint is the source less the film (1e-9);
- the joint's heat flow in history.csv equals the contact CSV's joint_heat_flux integrated
  along the joint with the pair's Newton–Cotes weights (1e-9);
- constant_h: the conduction is one-dimensional (uniform source, film and conductance,
  adiabatic sides), so the temperature of every node of both bodies and the jump equal the
  closed form T(y) (linear in the guide, the jump q/h, quadratic in the carriage with the
  film on top), which the quadratic elements reproduce exactly: 1e-6 of the largest
  temperature;
- coupled and no_expansion: the conductance at every node is h0 (p/1 MPa)^n of its pressure
  (1e-9; 0 where open), and the mean jump at the end of the heating and at the end lies
  between the one-dimensional jumps for h(p_max) and h(p_min) of that frame (the jump is
  q/h pointwise, so its mean cannot leave the range the pressures span);
- no_expansion: heating leaves the pressure as it was (1e-9 of it): without thermal strain
  the conduction does not act on the mechanics;
- vertical equilibrium of the joint against the pressure on the carriage (5e-4, the
  solver's residual tolerance);
- the staggered coupling settles in every increment (log.txt: `thermal-mechanical coupling:
  N exchange(s)`, N at most 50);
- the energy balance: imbalance below 1e-6 of the external work.

--quick runs a coarse mesh (size 2) for `make test`.
"""
from __future__ import annotations

import argparse
import re
import tomllib
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from asperity_tools import (ROOT, Checks, body_points, read_contact, read_history, read_step, run_cases,  # noqa: E402
                            solver_statistics, table, variant, write_report)
from plot_fields import field_picture  # noqa: E402

HERE = Path(__file__).resolve().parent
CASE = HERE / "joint_thermal" / "case.toml"
RUNS = {"coupled": "pressure-dependent conductance and thermal strain",
        "no_expansion": "pressure-dependent conductance, no thermal strain (α = 0)",
        "constant_h": "thermal strain, constant conductance h0 (p_0/1 MPa)^n"}
ROUND_OFF = 1e-9  # relative: a balance the discrete equations hold exactly
MAX_EXCHANGES = 50  # src/solver/coupling.rs


class Joint:
    """The case's data the checks need, read from the case file."""

    def __init__(self, case: dict) -> None:
        contact = case["contact"][0]
        self.pair = contact["name"]
        conductance = contact["conductance"]
        self.h0, self.n = ((conductance, 0.0) if isinstance(conductance, float)
                           else (conductance["h0"], conductance["exponent"]))
        self.side_a, self.side_b = contact["side_a"], contact["side_b"]
        load = case["load"][0]
        self.load, self.pressure = load["name"], load["pressure"]
        self.bodies = {b["group"]: b for b in case["body"]}
        supports = {s["name"]: s for s in case["thermal_support"]}
        self.base = next(s for s in supports.values() if "temperature" in s)
        self.film = next(s for s in supports.values() if "film" in s)
        self.source = case["heat_source"][0]

    def h(self, p: np.ndarray) -> np.ndarray:
        return self.h0 * np.abs(p) ** self.n


class Slab:
    """One-dimensional conduction through the guide (height hg, y from −hg to 0, base at
    T_base) and the carriage (height hc, uniform source s, film h_f to T_amb on its top),
    joined by the conductance h: the reference of the constant-conductance run."""

    def __init__(self, hg: float, hc: float, k_g: float, k_c: float, h_f: float) -> None:
        self.hg, self.hc, self.k_g, self.k_c, self.h_f = hg, hc, k_g, k_c, h_f

    def joint_flux(self, s: float, h: float, t_base: float = 0.0, t_amb: float = 0.0) -> float:
        """Heat flux from the carriage into the guide: the carriage's balance
        s hc = q + h_f (T(hc) − T_amb) with T(hc) from the temperatures below."""
        hg, hc, kg, kc, hf = self.hg, self.hc, self.k_g, self.k_c, self.h_f
        return ((s * hc * (1 + hf * hc / (2 * kc)) - hf * (t_base - t_amb))
                / (1 + hf * (hg / kg + 1 / h + hc / kc)))

    def temperature(self, y: np.ndarray, in_carriage: np.ndarray, s: float, h: float,
                    t_base: float = 0.0, t_amb: float = 0.0) -> np.ndarray:
        q = self.joint_flux(s, h, t_base, t_amb)
        guide = t_base + q * (y + self.hg) / self.k_g
        top_of_guide = t_base + q * self.hg / self.k_g
        carriage = top_of_guide + q / h + q * y / self.k_c - s * y**2 / (2 * self.k_c)
        return np.where(in_carriage, carriage, guide)

    def jump(self, s: float, h: float) -> float:
        """T_carriage − T_guide at the joint."""
        return self.joint_flux(s, h) / h


def along(contact: dict[str, np.ndarray]) -> np.ndarray:
    """The Newton–Cotes weights (L/6, 4L/6, L/6 per quadratic element) of the joint's nodes,
    in the contact CSV's order along side B."""
    s = contact["arc_length"]
    weights = np.zeros_like(s)
    for i in range(0, len(s) - 2, 2):
        length = s[i + 2] - s[i]
        weights[i:i + 3] += np.array([1.0, 4.0, 1.0]) * length / 6
    return weights


def exchanges(out: Path) -> list[int]:
    """Exchanges of the staggered coupling per increment, from log.txt."""
    text = (out / "log.txt").read_text()
    return [int(n) for n in re.findall(r"thermal-mechanical coupling: (\d+) exchange", text)]


def slab_of(out: Path, joint: Joint) -> Slab:
    """The bodies' heights from the mesh (the run's bodies grid) and the case's data."""
    grid = read_step(out, 1)["bodies"]
    y = np.asarray(grid.points[:, 1])
    guide, carriage = y[body_points(grid, "guide")], y[body_points(grid, "carriage")]
    return Slab(guide.max() - guide.min(), carriage.max() - carriage.min(), joint.bodies["guide"]["conductivity"],
                joint.bodies["carriage"]["conductivity"], joint.film["film"]["h"])


def source_density(history: dict[str, np.ndarray], k: int, joint: Joint, slab: Slab, width: float) -> float:
    """The source's power per volume s (W/mm³) at frame k: its heat (history.csv) over the
    carriage's section."""
    return history[f"heat_source_{joint.source['name']}"][k] / (width * slab.hc)


def heat_checks(name: str, out: Path, joint: Joint, checks: Checks) -> dict[str, np.ndarray]:
    history = read_history(out)
    source = history[f"heat_source_{joint.source['name']}"]
    base, air = history[f"heat_flow_{joint.base['name']}"], history[f"heat_flow_{joint.film['name']}"]
    through = history[f"heat_flow_{joint.pair}"]
    scale = np.abs(source).max()
    balance = np.abs(source + base + air).max() / scale
    carriage = np.abs(through + source + air).max() / scale
    checks(balance <= ROUND_OFF and carriage <= ROUND_OFF,
           f"`{name}`: heat balance at every frame: source + base + film = {balance:.1e} of the source "
           f"({source.max():.4g} W/mm at most); carriage: source + film + joint = {carriage:.1e}")
    csv_flow = np.array([np.sum(along(c) * c["joint_heat_flux"])
                         for c in (read_contact(out, joint.pair, int(s)) for s in history["step"])])
    error = np.abs(csv_flow - through).max() / scale
    checks(error <= ROUND_OFF, f"`{name}`: heat flow of the joint in history.csv against its contact CSV's "
           f"joint_heat_flux integrated along the joint: {error:.1e} of the source")
    force = np.abs(history[f"{joint.pair}_force_on_b_y"]) / np.abs(history[f"factor_load_{joint.load}"] * joint.pressure)
    width = float(read_contact(out, joint.pair)["arc_length"].max())
    equilibrium = np.abs(force / width - 1).max()
    checks(equilibrium <= 5e-4, f"`{name}`: vertical force of the joint against the pressure on the carriage × "
           f"width {width:g} mm: largest relative difference {equilibrium:.1e}")
    return history


def law_checks(name: str, out: Path, joint: Joint, frames: list[int], slab: Slab, width: float,
               history: dict, checks: Checks) -> None:
    worst = 0.0
    for step in history["step"].astype(int):
        c = read_contact(out, joint.pair, step)
        closed = c["contact_status"] > 0
        expected = np.where(closed, joint.h(c["contact_pressure"]), 0.0)
        worst = max(worst, float(np.abs(c["joint_conductance"] - expected).max() / expected.max()))
    checks(worst <= ROUND_OFF, f"`{name}`: conductance at every node and frame = h0 (p/1 MPa)^n = "
           f"{joint.h0:g} (p/1 MPa)^{joint.n:g}: largest difference {worst:.1e} of the largest")
    steps = history["step"].astype(int)
    for step in frames:
        c = read_contact(out, joint.pair, step)
        k = int(np.flatnonzero(steps == step)[0])
        s = source_density(history, k, joint, slab, width)
        p = c["contact_pressure"]
        low, high = slab.jump(s, joint.h(p.max())), slab.jump(s, joint.h(p.min()))
        mean = float(np.sum(along(c) * -c["temperature_jump"]) / width)
        checks(low <= mean <= high, f"`{name}`, frame {step}: mean jump T_carriage − T_guide {mean:.4f} K within the "
               f"one-dimensional jumps for h(p_max = {p.max():.3f} MPa) = {low:.4f} K and h(p_min = {p.min():.3f} MPa) = "
               f"{high:.4f} K")


def one_dimensional_check(out: Path, joint: Joint, slab: Slab, h: float, width: float, history: dict,
                          checks: Checks) -> float:
    """constant_h: every node's temperature against the slab's; returns the largest error."""
    worst, largest = 0.0, 0.0
    for k, step in enumerate(history["step"].astype(int)):
        grid = read_step(out, step)["bodies"]
        t = np.asarray(grid.point_data["temperature"])
        carriage = np.zeros(len(t), bool)
        carriage[body_points(grid, "carriage")] = True
        base = joint.base["temperature"] * history[f"factor_thermal_{joint.base['name']}"][k] \
            if f"factor_thermal_{joint.base['name']}" in history else joint.base["temperature"]
        ambient = joint.film["film"].get("ambient", 0.0)
        reference = slab.temperature(np.asarray(grid.points[:, 1]), carriage, source_density(history, k, joint, slab, width), h,
                                     base, ambient)
        worst = max(worst, float(np.abs(t - reference).max()))
        largest = max(largest, float(np.abs(reference).max()))
    error = worst / largest
    checks(error <= 1e-6, f"`constant_h`: temperature of every node of both bodies at every frame against the "
           f"one-dimensional closed form (h = {h:.5g} W/(mm²·K)): largest error {error:.1e} of the largest "
           f"temperature ({largest:.4g} K)")
    return error


def profiles_figure(out: Path, joint: Joint, frames: dict[str, int], slab: Slab, h_const: float,
                    sources: dict[int, float]) -> Path:
    fig, axes = plt.subplots(3, 1, figsize=(7.5, 9), sharex=True)
    styles = {"coupled": "C0", "no_expansion": "C1", "constant_h": "C2"}
    for (label, step), ls in zip(frames.items(), ["-", "--"]):
        for name, colour in styles.items():
            c = read_contact(out / name, joint.pair, step)
            x = c["x"]
            axes[0].plot(x, c["contact_pressure"], ls, color=colour, label=f"{name}, {label}")
            axes[1].plot(x, 1e3 * c["joint_conductance"], ls, color=colour, label=f"{name}, {label}")
            axes[2].plot(x, -c["temperature_jump"], ls, color=colour, label=f"{name}, {label}")
        axes[2].axhline(slab.jump(sources[step], h_const), color="k", ls=ls, lw=0.8,
                        label=f"one-dimensional, constant h, {label}")
    axes[0].set_ylabel("contact pressure [MPa]")
    axes[1].set_ylabel("conductance [10⁻³ W/(mm²·K)]")
    axes[2].set_ylabel("jump T_carriage − T_guide [K]")
    axes[2].set_xlabel("x along the joint [mm]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=6, ncol=2)
    axes[2].legend(fontsize=6, ncol=2)
    fig.suptitle("Along the joint (solid: end of heating; dashed: pressed harder)")
    fig.tight_layout()
    path = out / "joint_profiles.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def heat_flow_figure(out: Path, joint: Joint, history: dict) -> Path:
    fig, ax = plt.subplots(figsize=(7, 4))
    columns = [f"heat_source_{joint.source['name']}", f"heat_flow_{joint.base['name']}",
               f"heat_flow_{joint.film['name']}", f"heat_flow_{joint.pair}"]
    for column in columns:
        ax.plot(history["step"], history[column], "o-", ms=3, label=column)
    ax.set_xlabel("frame")
    ax.set_ylabel("heat flow [W per mm of depth]")
    ax.set_title("coupled run: heat flows (supports: into the bodies; joint: guide → carriage)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    path = out / "heat_flows.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "joint_thermal")
    parser.add_argument("--size", type=float, default=None, help="mesh size factor (default: the case file's)")
    parser.add_argument("--quick", action="store_true", help="coarse mesh for CI (size 2)")
    args = parser.parse_args()
    size = 2.0 if args.quick and args.size is None else args.size
    out = args.out.resolve()
    joint = Joint(tomllib.loads(CASE.read_text()))
    h_const = float(joint.h(joint.pressure))
    changes = {"no_expansion": {f"body[{i}].material.expansion": 0.0 for i in range(len(joint.bodies))},
               "constant_h": {"contact[0].conductance": h_const}}
    cases = {name: variant(CASE, out / "cases" / f"{name}.toml", changes.get(name), size=size) for name in RUNS}
    summaries = dict(zip(cases, run_cases([(case, out / name) for name, case in cases.items()])))

    checks = Checks()
    histories = {name: heat_checks(name, out / name, joint, checks) for name in RUNS}
    history = histories["coupled"]
    steps = history["step"].astype(int)
    heated = int(steps[history["analysis_step"] == 2][-1])
    pressed = int(steps[history["analysis_step"] == 1][-1])
    last = int(steps[-1])
    width = float(read_contact(out / "coupled", joint.pair)["arc_length"].max())
    slab = slab_of(out / "coupled", joint)
    for name in ("coupled", "no_expansion"):
        law_checks(name, out / name, joint, [heated, last], slab, width, histories[name], checks)
    one_dimensional_check(out / "constant_h", joint, slab, h_const, width, histories["constant_h"], checks)
    before = read_contact(out / "no_expansion", joint.pair, pressed)["contact_pressure"]
    after = read_contact(out / "no_expansion", joint.pair, heated)["contact_pressure"]
    unchanged = float(np.abs(after - before).max() / before.max())
    checks(unchanged <= ROUND_OFF, f"`no_expansion`: heating leaves the pressure as it was: largest change "
           f"{unchanged:.1e} of the largest pressure (frames {pressed} and {heated})")
    for name in RUNS:
        counts = exchanges(out / name)
        checks(len(counts) == len(histories[name]["step"]) and max(counts) <= MAX_EXCHANGES,
               f"`{name}`: the staggered coupling settled in every increment ({len(counts)} increments, "
               f"exchanges per increment: {', '.join(map(str, counts))})")
        energy = summaries[name]["energy"]["total"]
        imbalance = abs(energy["imbalance"]) / abs(energy["external_work"])
        checks(imbalance <= 1e-6, f"`{name}`: energy imbalance {imbalance:.1e} of the external work "
               f"({energy['external_work']:.4g} N·mm; thermal work {energy['thermal_work']:.4g} N·mm)")

    sources = {step: source_density(history, int(np.flatnonzero(steps == step)[0]), joint, slab, width)
               for step in (heated, last)}
    profiles = profiles_figure(out, joint, {"end of heating": heated, "pressed harder": last}, slab, h_const, sources)
    flows = heat_flow_figure(out, joint, history)
    temperature = field_picture(out / "coupled", "temperature", "temperature change [K]", "temperature", heated)
    rows = []
    for name in RUNS:
        for step, label in ((pressed, "pressed"), (heated, "end of heating"), (last, "pressed harder")):
            c = read_contact(out / name, joint.pair, step)
            k = int(np.flatnonzero(histories[name]["step"] == step)[0])
            rows.append([name, label, float(c["contact_pressure"].min()), float(c["contact_pressure"].max()),
                         float(-c["temperature_jump"].max()) + 0.0, float(-c["temperature_jump"].min()) + 0.0,
                         float(histories[name][f"heat_flow_{joint.pair}"][k])])
    coupled = read_contact(out / "coupled", joint.pair, heated)["contact_pressure"]
    plain = read_contact(out / "no_expansion", joint.pair, heated)["contact_pressure"]
    effect = float(np.abs(coupled - plain).max())
    setup = f"""`pipelines/joint_thermal/case.toml` on `geo/joint_thermal.geo` (plane strain, per mm of depth): a
carriage {slab.hc:g} mm high and {width:g} mm wide on a guide {slab.hg:g} mm high, cast iron
(conductivity {joint.bodies['carriage']['conductivity']} W/(mm·K), α = {joint.bodies['carriage']['material']['expansion']:g} 1/K),
pressed by {joint.pressure:g} MPa (step `press`), heated by a source of
{joint.source['power']:g} W/mm³ in the carriage (`heat`), then pressed by four times the pressure
(`press harder`). The guide's base is held at the reference temperature, the carriage's top
has a film (h = {joint.film['film']['h']:g} W/(mm²·K)), the other sides are adiabatic; the carriage's
ends are held horizontally. The joint conducts with h = {joint.h0:g} (|p|/1 MPa)^{joint.n:g}; the
`constant_h` run uses h = {h_const:.5g} W/(mm²·K), its value at {joint.pressure:g} MPa.
Runs: {"; ".join(f"`{n}`: {d}" for n, d in RUNS.items())}. Mesh size factor: {size or "as in the case file"}.

The one-dimensional reference (this script): the guide conducts the joint's flux q linearly to
the base, the joint adds q/h, the carriage's temperature is quadratic with its source s and
q = s hc (1 + h_f hc/(2k)) / (1 + h_f (hg/k + 1/h + hc/k)) from the carriage's balance with the
film."""
    k_heated, k_last = (int(np.flatnonzero(steps == s)[0]) for s in (heated, last))
    harder = history[f"factor_load_{joint.load}"][k_last] / history[f"factor_load_{joint.load}"][k_heated]
    x = read_contact(out / "coupled", joint.pair, heated)["x"]
    findings = f"""The pressure sets the jump: pressed {harder:g} times harder, the conductance grows by about
{harder:g}^{joint.n:g} = {harder ** joint.n:.3g} and the jump falls accordingly (table; the `constant_h` run's jump
does not move). The thermal strain sets the pressure: at the end of the heating the coupled run's
pressure differs from the run without thermal strain by up to {effect:.3g} MPa (mean {joint.pressure:g} MPa), from
{coupled.min():.3g} MPa at x = {x[np.argmin(coupled)]:.3g} mm to {coupled.max():.3g} MPa at x = {x[np.argmax(coupled)]:.3g} mm
(without thermal strain {plain.min():.3g} to {plain.max():.3g} MPa), and the jump follows: it is largest where the
pressure is lowest (figure)."""
    write_report(out / "REPORT.md", "Heat through a slideway joint", [
        ("Set-up", setup),
        ("Checks", checks.markdown()),
        ("Pressure, conductance and temperature jump along the joint",
         f"![profiles]({profiles.name})\n\n{findings}\n\n"
         + table(["run", "frame", "p_min [MPa]", "p_max [MPa]", "jump min [K]", "jump max [K]",
                  "heat flow guide → carriage [W/mm]"], rows)),
        ("Heat flows", f"![heat flows]({flows.name})\n\nTemperature of the coupled run at the end of the heating "
                       f"(deformation magnified): ![temperature](coupled/{temperature.name})"),
        ("Solver statistics", table(["run", "steps / iterations", "time [s]"],
                                    [[name, *solver_statistics(summaries[name])] for name in RUNS])),
    ])
    print(f"results: {out} (REPORT.md, joint_profiles.png, heat_flows.png, run folders with results.pvd)")
    print("\n".join(checks.lines))
    checks.exit_on_failure("joint_thermal")


if __name__ == "__main__":
    main()
