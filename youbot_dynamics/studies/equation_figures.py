"""Figures of the equation studies (seed 000 items 4-5; the Pantelides / ModiaBase study;
benchmarks.md section 6): the bipartite incidence matrices with their matchings, the
BLT-permuted matrices (studies/structure.py), the low-pass filter's bipartite graph, and
the equation pipeline's simulations (studies/pipeline.py) against closed forms and the
hand-written pendulum, with the ModiaLang damped pendulum and its L = 0.5 merge.
"""
from __future__ import annotations

from functools import partial
from pathlib import Path

import numpy as np

from youbot_dynamics.integrate.integrators import integrate
from youbot_dynamics.studies.equations import (MODIA_MERGE, cartesian_pendulum, first_order_lag,
                                               lowpass_filter, modia_pendulum)
from youbot_dynamics.studies.figures import FigureSet, heading, panels, save, specs
from youbot_dynamics.studies.state_selection import simulate_with_reselection
from youbot_dynamics.studies.structure import LOWPASS_INCIDENCE, LOWPASS_KNOWN, structure_report

STRUCTURE_TITLES = {"lowpass": "low-pass filter", "pendulum": "Cartesian pendulum",
                    "squeezer": "Andrew's squeezer (index 3)"}


def matrix_of(rows: list[str]) -> np.ndarray:
    """The 'x' / '.' text rows of an incidence matrix as 0/1."""
    return np.array([[cell == "x" for cell in row] for row in rows], dtype=float)


def incidence_plot(path: Path, matrix: np.ndarray, row_names, column_names, title: str,
                   marked: set[tuple[int, int]] = frozenset(),
                   block_sizes: tuple[int, ...] = ()) -> None:
    """An incidence matrix as filled squares (rows equations, columns variables); marked
    cells (the matching) in red; the diagonal blocks outlined."""
    from matplotlib.patches import Rectangle
    n_rows, n_columns = matrix.shape
    scale = 0.26 if n_columns > 20 else 0.5
    figure, axis = panels(size=(max(4.0, scale * n_columns + 2), max(3.0, scale * n_rows + 1.5)))
    axis.grid(False)
    rows, columns = np.nonzero(matrix)
    colors = ["tab:red" if (i, j) in marked else "tab:blue" for i, j in zip(rows, columns)]
    axis.scatter(columns, rows, marker="s", s=(60 if n_columns > 20 else 160), c=colors)
    start = 0
    for size in block_sizes:
        axis.add_patch(Rectangle((start - 0.5, start - 0.5), size, size,
                                             fill=False, edgecolor="black", linewidth=1.0))
        start += size
    axis.set_xticks(range(n_columns), column_names, rotation=90,
                    fontsize=6 if n_columns > 20 else 8)
    axis.set_yticks(range(n_rows), row_names, fontsize=6 if n_rows > 20 else 8)
    axis.set_xlim(-0.5, n_columns - 0.5)
    axis.set_ylim(n_rows - 0.5, -0.5)
    save(figure, path, title)


def draw_structure(example: str, result: dict | None, out: Path,
                   full: bool) -> dict[str, tuple[str, str]]:
    """The figures of one structure set: the example's incidence matrix with its
    matching and its BLT-permuted matrix (and the low-pass filter's bipartite graph);
    ``result``: the example's structure report, if already made."""
    title = STRUCTURE_TITLES[example]
    report = structure_report(example) if result is None else result
    variables, equations = report["variables"], report["equations"]
    index = {name: j for j, name in enumerate(variables)}
    if "assign" in report:
        matching = {(i - 1, j) for j, i in enumerate(report["assign"]) if i}
    else:
        matching = {(equations.index(e), index[v])
                    for v, e in report["initial_matching"].items()}
    incidence_plot(out / f"structure_{example}_incidence.png", matrix_of(report["incidence"]),
                   equations, variables, f"{heading(title)}: incidence matrix, matching in red",
                   matching)
    blt = report["blt"]
    permuted = matrix_of(blt["incidence"])
    incidence_plot(out / f"structure_{example}_blt.png", permuted, blt["rows"],
                   blt["columns"], f"{heading(title)}: BLT-permuted incidence matrix",
                   {(k, k) for k in range(min(permuted.shape))}, tuple(blt["block_sizes"]))
    unmatched = report.get("unmatched_equations", [])
    drawn = {
        f"structure_{example}_incidence.png": (
            f"{len(equations)} equations, {len(variables)} variables, {len(matching)} "
            "matched" + (f"; unmatched: {', '.join(unmatched)}" if unmatched else
                         "; a perfect matching"),
            seed_difference(example, report, "incidence")),
        f"structure_{example}_blt.png": (
            f"blocks of sizes {blt['block_sizes']}: " + " ".join(
                "[" + ", ".join(map(str, block)) + "]" for block in report["blocks"]),
            seed_difference(example, report, "blt"))}
    if example == "lowpass":
        lowpass_graph(out / "structure_lowpass_graph.png", report)
        drawn["structure_lowpass_graph.png"] = (
            f"assign = {report['assign']}",
            "The seed's graph G = [[1, 2, 4], [1, 7], [3, 4], [3, 7], [6, 7], [2]] drawn; "
            + ("our matching is the seed's assign list." if report["assign"] ==
               LOWPASS_SEED_ASSIGN else f"the seed's assign is {LOWPASS_SEED_ASSIGN}, ours "
               "another maximum matching."))
    return drawn


#: The seed's matching and blocks of the low-pass filter, and the pendulum's lists
#: (benchmarks.md section 6).
LOWPASS_SEED_ASSIGN = [2, 6, 3, 1, 0, 5, 4]
LOWPASS_SEED_BLOCKS = [[6], [1, 2, 3, 4], [5]]
PENDULUM_SEED_EQMAP = {"f5": "f6", "f6": "f7", "f1": "f8", "f2": "f9"}


def seed_difference(example: str, report: dict, view: str) -> str:
    """How one structure figure compares with the seed's lists."""
    if example == "lowpass":
        if view == "incidence":
            same = report["assign"] == LOWPASS_SEED_ASSIGN
            return (f"Seed assign = {LOWPASS_SEED_ASSIGN}; ours "
                    + ("the same." if same else f"{report['assign']}."))
        same = report["blocks"] == LOWPASS_SEED_BLOCKS
        return (f"Seed blocks {LOWPASS_SEED_BLOCKS} (an algebraic loop of four); ours "
                + ("the same." if same else f"{report['blocks']}."))
    if example == "pendulum":
        if view == "incidence":
            return ("Seed: f5 holds no highest derivative, the matching fails there; ours "
                    f"leaves {', '.join(report['unmatched_equations']) or 'none'} unmatched.")
        same = report["eqmap"] == PENDULUM_SEED_EQMAP
        return (f"Seed eqmap {PENDULUM_SEED_EQMAP}, structural index 3; ours "
                + ("the same" if same else str(report["eqmap"]))
                + f", index {report['structural_index']}. The seed draws no BLT of the "
                "reduced system.")
    if view == "incidence":
        return ("Seed: index 3, the six constraints (f15-f20) hold no highest derivative; "
                f"ours leaves {', '.join(report['unmatched_equations'])} unmatched.")
    return (f"Seed: the constraints differentiated twice; ours: "
            + ", ".join(f"{name} x{count}" for name, count in report["differentiations"].items())
            + f"; structural index {report['structural_index']}.")


def lowpass_graph(path: Path, report: dict) -> None:
    """The low-pass filter's bipartite graph: equations left, variables right, the
    matching's edges in red, the known variable grey."""
    figure, axis = panels(size=(5.0, 4.5))
    axis.grid(False)
    axis.axis("off")
    matched = {(i, j + 1) for j, i in enumerate(report["assign"]) if i}
    n_variables = len(report["variables"])
    for i, variables in enumerate(LOWPASS_INCIDENCE, start=1):
        for j in variables:
            red = (i, j) in matched
            axis.plot([0, 1], [-i, -j], color="tab:red" if red else "grey",
                      linewidth=2.0 if red else 0.7, zorder=1)
    axis.scatter([0] * len(LOWPASS_INCIDENCE), [-i for i in range(1, 7)], s=300,
                 color="tab:blue", zorder=2)
    axis.scatter([1] * n_variables, [-j for j in range(1, n_variables + 1)], s=300,
                 color=["lightgrey" if j in LOWPASS_KNOWN else "tab:orange"
                        for j in range(1, n_variables + 1)], zorder=2)
    for i in range(1, len(LOWPASS_INCIDENCE) + 1):
        axis.annotate(f"f{i}", (0, -i), ha="center", va="center", fontsize=7, color="white")
    for j in range(1, n_variables + 1):
        axis.annotate(str(j), (1, -j), ha="center", va="center", fontsize=8)
    save(figure, path, "Low-pass filter: bipartite graph (equations, variables), matching red")


def run_model(model, tol: float = 1e-10, outputs: int = 401):
    """The pipeline's simulation of an equation model (state selection as the command)."""
    with np.errstate(all="ignore"):
        return simulate_with_reselection(model, "dop853", tol, outputs)


def hand_written_pendulum(model, t: np.ndarray) -> np.ndarray:
    """(x, y) of the Cartesian pendulum model from theta'' = -(g / l) sin theta, written
    by hand (theta from hanging straight down), DOP853 at 1e-12."""
    length = float(np.sqrt(model.parameters["L"]))
    gravity = model.parameters["g"]
    theta0 = float(np.arctan2(model.variables["x"], -model.variables["y"]))
    solution = integrate(lambda _, s: np.array([s[1], -gravity / length * np.sin(s[0])]),
                         [theta0, 0.0], t, "dop853", rtol=1e-12, atol=1e-12)
    theta = solution.x[:, 0]
    return np.c_[length * np.sin(theta), -length * np.cos(theta)]


def draw_lag(result: object, out: Path, full: bool) -> dict[str, tuple[str, str]]:
    """The figure of the first-order lag."""
    drawn = {}
    lag = first_order_lag()
    figure, axis = panels(size=(7.0, 3.4))
    errors = []
    for model, label in ((lag, "defaults (tau = 3 s)"), (lag | {"tau": 1.0}, "tau => 1 s")):
        t, x = run_model(model).values("x")
        tau = model.parameters["tau"]
        errors.append(float(np.max(np.abs(x - (1.0 - np.exp(-t / tau))))))
        axis.plot(t, x, linewidth=1.0, label=f"x, {label}")
        axis.plot(t, 1.0 - np.exp(-t / tau), "k:", linewidth=0.8)
    axis.set_xlabel("t (s)")
    axis.set_ylabel("x")
    axis.legend(fontsize=7, title="dotted: 1 - exp(-t / tau)", title_fontsize=7)
    save(figure, out / "pipeline_lag.png", "First-order lag: defaults and an override")
    drawn["pipeline_lag.png"] = (
        f"max |x - (1 - exp(-t / tau))|: {errors[0]:.2g} (defaults), {errors[1]:.2g} (tau => 1)",
        "As ModelingToolkit's tutorial: the override is honoured (the faster curve); RHS "
        "is eliminated as an alias of x'.")
    return drawn


def draw_lowpass(result: object, out: Path, full: bool) -> dict[str, tuple[str, str]]:
    """The figure of the low-pass filter's simulation."""
    drawn = {}
    filter_model = lowpass_filter()
    filter_run = run_model(filter_model)
    t, voltage = filter_run.values("vC")
    _, current = filter_run.values("i")
    p = filter_model.parameters
    time_constant = (p["R1"] + p["R2"]) * p["C"]
    exact = p["U0"] * (1.0 - np.exp(-t / time_constant))
    figure, axis = panels(size=(7.0, 3.4))
    axis.plot(t, voltage, linewidth=1.0, label="vC (V)")
    axis.plot(t, exact, "k:", linewidth=0.8, label="U0 (1 - exp(-t / (R1 + R2) C))")
    axis.plot(t, current * 100.0, linewidth=1.0, label="i (A) x 100")
    axis.set_xlabel("t (s)")
    axis.legend(fontsize=7)
    save(figure, out / "pipeline_lowpass.png", "Low-pass filter simulated by the pipeline")
    drawn["pipeline_lowpass.png"] = (
        f"max |vC - closed form| {np.max(np.abs(voltage - exact)):.2g} V; the algebraic loop "
        "of four equations torn and solved",
        "The seed shows the structure only; the simulation is ours, checked against the "
        "closed form.")
    return drawn


def draw_cartesian_pendulum(result: object, out: Path, full: bool) -> dict[str, tuple[str, str]]:
    """The Cartesian pendulum's figures: generated against hand-written."""
    drawn = {}
    pendulum = cartesian_pendulum()
    run = run_model(pendulum, tol=1e-10, outputs=501)
    t, x = run.values("x")
    _, y = run.values("y")
    reference = hand_written_pendulum(pendulum, t)
    figure, axis = panels(size=(7.0, 3.4))
    axis.plot(t, x, linewidth=1.0, label="x, generated ODE")
    axis.plot(t, y, linewidth=1.0, label="y, generated ODE")
    axis.plot(t, reference[:, 0], "k:", linewidth=0.8, label="hand-written (angle form)")
    axis.plot(t, reference[:, 1], "k:", linewidth=0.8)
    axis.set_xlabel("t (s)")
    axis.set_ylabel("m")
    axis.legend(fontsize=7)
    save(figure, out / "pipeline_pendulum.png",
         "Cartesian pendulum: the pipeline's ODE against the hand-written one")
    gap = np.hypot(x - reference[:, 0], y - reference[:, 1])
    figure, axis = panels(size=(7.0, 3.0))
    axis.semilogy(t, gap + 1e-17, linewidth=0.8)
    axis.set_xlabel("t (s)")
    axis.set_ylabel("|(x, y) - hand-written| (m)")
    save(figure, out / "pipeline_pendulum_difference.png",
         "Cartesian pendulum: generated ODE (tol 1e-10) against hand-written (1e-12)")
    switches = run.switches()
    drawn["pipeline_pendulum.png"] = (
        f"states {', '.join(run.segments[0].states)}; {len(run.segments)} state selection(s)"
        + (f" ({'; '.join(switches)})" if switches else ""),
        "The seed's pipeline (ModelingToolkit's structural_simplify / ModiaBase) gives the "
        "same motion; ours selects x, u or y, v as states where the pivot says.")
    drawn["pipeline_pendulum_difference.png"] = (
        f"max distance {np.max(gap):.2g} m over {t[-1]:g} s",
        "Not in the seed: the generated ODE agrees with the hand-written pendulum to the "
        "integrators' tolerances.")
    return drawn


def draw_modia_pendulum(result: object, out: Path, full: bool) -> dict[str, tuple[str, str]]:
    """The ModiaLang damped pendulum's figures, with the seed's L = 0.5 merge."""
    drawn = {}
    modia = modia_pendulum()
    runs = {"L = 0.8 (defaults)": run_model(modia, tol=1e-8),
            "| Map(L = 0.5)": run_model(modia | MODIA_MERGE, tol=1e-8)}
    figure, axis = panels(size=(7.0, 3.4))
    for label, each in runs.items():
        t, phi = each.values("phi")
        axis.plot(t, phi, linewidth=1.0, label=label)
    axis.set_xlabel("t (s)")
    axis.set_ylabel("phi (rad)")
    axis.legend(fontsize=7)
    save(figure, out / "modia_pendulum_phi.png", "ModiaLang damped pendulum: phi(t)")
    figure, axis = panels(size=(5.0, 4.2), sharex=False)
    for label, each in runs.items():
        _, rx = each.values("rx")
        _, ry = each.values("ry")
        axis.plot(rx, ry, linewidth=0.8, label=label)
    axis.set_aspect("equal")
    axis.set_xlabel("rx (m)")
    axis.set_ylabel("ry (m)")
    axis.legend(fontsize=7)
    save(figure, out / "modia_pendulum_position.png",
         "ModiaLang damped pendulum: r = (L cos phi, -L sin phi)")
    ends = {label: float(each.values("phi")[1][-1]) for label, each in runs.items()}
    drawn["modia_pendulum_phi.png"] = (
        "phi at t = 10 s: " + ", ".join(f"{label} {value:.4g} rad"
                                        for label, value in ends.items()),
        "The seed plots phi for L = 0.8 and after the merge L = 0.5 (a faster, more damped "
        "swing: the damping d / (m L^2) grows as L shrinks); its log is not in "
        "benchmarks.md.")
    drawn["modia_pendulum_position.png"] = (
        "the path spirals in on r = (0, -L) for each L",
        "Not a seed figure: r is the model's output equation, drawn for both merges.")
    return drawn


STRUCTURE_SETS = tuple(FigureSet(f"structure-{example}", specs(
    *((f"structure_{example}_{view}.png",
       f"{heading(title)}: " + ("bipartite incidence matrix with the matching"
                       if view == "incidence" else "BLT-permuted incidence matrix, blocks "
                       "outlined"),
       ("The seed's " + ("incidence / matching (assign list)" if view == "incidence"
                         else "BLT blocks") + f" of the {title}."))
      for view in ("incidence", "blt")),
    *((("structure_lowpass_graph.png", "Low-pass filter: the bipartite graph with the "
        "matching", "The seed's bipartite graph G and its maximum matching."),)
      if example == "lowpass" else ())), partial(draw_structure, example))
    for example, title in STRUCTURE_TITLES.items())

PIPELINE_SETS = (
    FigureSet("pipeline-lag", specs(
        ("pipeline_lag.png", "First-order lag: x(t) with the defaults and with tau => 1 s",
         "ModelingToolkit's first-order lag with defaults and overrides.")), draw_lag),
    FigureSet("pipeline-pendulum", specs(
        ("pipeline_pendulum.png", "Cartesian pendulum: x, y from the generated ODE and the "
         "hand-written one", "The seed's Cartesian pendulum DAE, simulated after index "
         "reduction."),
        ("pipeline_pendulum_difference.png", "Cartesian pendulum: distance between "
         "generated and hand-written solutions", "No seed figure.")),
        draw_cartesian_pendulum),
    FigureSet("pipeline-lowpass", specs(
        ("pipeline_lowpass.png", "Low-pass filter: vC(t) and i(t) from the generated ODE",
         "The seed's low-pass filter (structure only).")), draw_lowpass),
    FigureSet("pipeline-modia-pendulum", specs(
        ("modia_pendulum_phi.png", "ModiaLang damped pendulum: phi(t) for L = 0.8 and the "
         "merge L = 0.5", "The seed's damped pendulum with the | Map(L = 0.5) merge."),
        ("modia_pendulum_position.png", "ModiaLang damped pendulum: the path r for both L",
         "The model's output r = (L cos phi, -L sin phi).")), draw_modia_pendulum),
)
