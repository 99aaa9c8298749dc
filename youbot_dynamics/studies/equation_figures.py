"""Figures of the equation studies (document 000 sections 3-5; the Pantelides /
ModiaBase study; benchmarks.md section 6): the bipartite incidence matrices with their
matchings (ours and the document's assign list), the BLT-permuted matrices
(studies/structure.py), the low-pass filter's bipartite graph, and the equation pipeline's
simulations (studies/pipeline.py) with the document's parameters against closed forms and
hand-written references: ModelingToolkit's first-order lag (both runs), its second-order
system and Cartesian pendulum, the ModiaLang damped pendulum with its L = 0.5 merge and
its statistics log beside ours, and the Modia3D Pendulum1 / Pendulum3 examples.
"""
from __future__ import annotations

from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from youbot_dynamics.integrate.integrators import integrate
from youbot_dynamics.studies import modia3d_pendulums
from youbot_dynamics.studies.equations import (LAG_SECOND_RUN, MODIA_MERGE, cartesian_pendulum,
                                               first_order_lag, lowpass_filter, modia_pendulum,
                                               second_order_system)
from youbot_dynamics.studies.modia_log import DOCUMENT_LOG, statistics_rows
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
                   block_sizes: tuple[int, ...] = (),
                   ringed: set[tuple[int, int]] = frozenset(),
                   marked_label: str = "matched (ours)") -> None:
    """An incidence matrix as filled squares (rows equations, columns variables): incident
    cells blue, marked cells (the matching) red, ringed cells (another matching, the
    document's) circled in black; the diagonal blocks (algebraic loops) outlined; a legend
    says which is which."""
    from matplotlib.patches import Rectangle
    n_rows, n_columns = matrix.shape
    scale = 0.26 if n_columns > 20 else 0.5
    figure, axis = panels(size=(max(4.0, scale * n_columns + 2), max(3.0, scale * n_rows + 1.5)))
    axis.grid(False)
    rows, columns = np.nonzero(matrix)
    colors = ["tab:red" if (i, j) in marked else "tab:blue" for i, j in zip(rows, columns)]
    size_ = 60 if n_columns > 20 else 160
    axis.scatter(columns, rows, marker="s", s=size_, c=colors)
    axis.scatter([], [], marker="s", s=size_, c="tab:blue", label="incident (variable in equation)")
    if marked:
        axis.scatter([], [], marker="s", s=size_, c="tab:red", label=marked_label)
    if ringed:
        ring_rows, ring_columns = zip(*sorted(ringed))
        axis.scatter(ring_columns, ring_rows, marker="o", s=size_ * 2.2, facecolors="none",
                     edgecolors="black", linewidths=1.2, label="matched (document's assign)")
    start = 0
    for size in block_sizes:
        axis.add_patch(Rectangle((start - 0.5, start - 0.5), size, size,
                                             fill=False, edgecolor="black", linewidth=1.0))
        start += size
    if block_sizes:
        axis.plot([], [], color="black", linewidth=1.0, label="BLT block (outlined)")
    axis.set_xlabel("variables")
    axis.set_ylabel("equations")
    axis.legend(fontsize=6, loc="upper center", bbox_to_anchor=(0.5, -0.25 if n_columns <= 20
                                                                 else -0.12), ncol=2)
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
    document = set()
    if "assign" in report:
        matching = {(i - 1, j) for j, i in enumerate(report["assign"]) if i}
        document = {(i - 1, j) for j, i in enumerate(report["document_assign"]) if i}
    else:
        matching = {(equations.index(e), index[v])
                    for v, e in report["initial_matching"].items()}
    incidence_plot(out / f"structure_{example}_incidence.png", matrix_of(report["incidence"]),
                   equations, variables, f"{heading(title)}: incidence matrix, matching in red",
                   matching, ringed=document)
    blt = report["blt"]
    permuted = matrix_of(blt["incidence"])
    incidence_plot(out / f"structure_{example}_blt.png", permuted, blt["rows"],
                   blt["columns"], f"{heading(title)}: BLT-permuted incidence matrix",
                   {(k, k) for k in range(min(permuted.shape))}, tuple(blt["block_sizes"]),
                   marked_label="matched (ours, on the diagonal)")
    unmatched = report.get("unmatched_equations", [])
    drawn = {
        f"structure_{example}_incidence.png": (
            f"{len(equations)} equations, {len(variables)} variables, {len(matching)} "
            "matched" + (f"; unmatched: {', '.join(unmatched)}" if unmatched else
                         "; a perfect matching"),
            document_difference(example, report, "incidence")),
        f"structure_{example}_blt.png": (
            f"blocks of sizes {blt['block_sizes']}: " + " ".join(
                "[" + ", ".join(map(str, block)) + "]" for block in report["blocks"]),
            document_difference(example, report, "blt"))}
    if example == "lowpass":
        lowpass_graph(out / "structure_lowpass_graph.png", report)
        drawn["structure_lowpass_graph.png"] = (
            f"assign = {report['assign']}",
            "Document 000's graph G = [[1, 2, 4], [1, 7], [3, 4], [3, 7], [6, 7], [2]] drawn; "
            + ("our matching is the document's assign list." if report["assign"] ==
               report["document_assign"] else f"the document's assign is "
               f"{report['document_assign']}, ours the other perfect matching of the loop."))
    return drawn


#: Document 000's Pantelides eqmap of the Cartesian pendulum (benchmarks.md section 6).
PENDULUM_DOCUMENT_EQMAP = {"f5": "f6", "f6": "f7", "f1": "f8", "f2": "f9"}


def document_difference(example: str, report: dict, view: str) -> str:
    """How one structure figure compares with the document's lists (000 for the low-pass
    filter and the pendulum, 001 for the squeezer)."""
    if example == "lowpass":
        if view == "incidence":
            return (f"Document assign = {report['document_assign']} (ringed): a perfect "
                    f"matching too ({report['document_assign_is_perfect_matching']}); ours "
                    f"{report['assign']} (red). The loop f1-f4 is one 8-cycle with exactly "
                    "two perfect matchings; Pantelides' AUGMENTPATH gives ours scanning each "
                    "equation's variables first to last and the document's last to first.")
        same = report["blocks"] == report["document_assign_blocks"]
        return (f"Document blocks [6], [2, 4, 3, 1], [5] (an algebraic loop of four); ours "
                f"{report['blocks']}, the same sets" + (" (either matching)" if same else "")
                + ".")
    if example == "pendulum":
        if view == "incidence":
            return ("Document: f5 holds no highest derivative, the matching fails there; ours "
                    f"leaves {', '.join(report['unmatched_equations']) or 'none'} unmatched.")
        same = report["eqmap"] == PENDULUM_DOCUMENT_EQMAP
        return (f"Document eqmap {PENDULUM_DOCUMENT_EQMAP}, structural index 3; ours "
                + ("the same" if same else str(report["eqmap"]))
                + f", index {report['structural_index']}. The document draws no BLT of the "
                "reduced system.")
    if view == "incidence":
        return ("Document 001: index 3, the six constraints (f15-f20) hold no highest "
                f"derivative; ours leaves {', '.join(report['unmatched_equations'])} unmatched.")
    return ("Document 001: the constraints differentiated twice; ours: "
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
    """The figures of ModelingToolkit's examples in document 000: the first-order lag's two
    runs and the second-order system."""
    drawn = {}
    lag = first_order_lag()
    merge, t_end = LAG_SECOND_RUN
    figure, axis = panels(size=(7.0, 3.4))
    errors = []
    for model, label in ((lag, "tau = 1 s, x(0) = 0, [0, 5] s (defaults)"),
                         (replace(lag | merge, t_end=t_end), "tau = 5 s, x(0) = 2, [0, 10] s")):
        t, x = run_model(model).values("x")
        tau, x0 = model.parameters["tau"], model.variables["x"]
        exact = 1.0 + (x0 - 1.0) * np.exp(-t / tau)
        errors.append(float(np.max(np.abs(x - exact))))
        axis.plot(t, x, linewidth=1.0, label=f"ours: {label}")
        axis.plot(t, exact, "k:", linewidth=0.8)
    axis.plot([], [], "k:", linewidth=0.8, label="closed form 1 + (x(0) - 1) exp(-t / tau)")
    axis.set_xlabel("t (s)")
    axis.set_ylabel("x (1)")
    axis.legend(fontsize=7)
    save(figure, out / "pipeline_lag.png", "First-order lag: document 000's two runs")
    drawn["pipeline_lag.png"] = (
        f"max |x - closed form|: {errors[0]:.2g} (first run), {errors[1]:.2g} (second)",
        "Document: ODEProblem(fol, [], (0, 5)) with defaults x 0, tau 1, then [:x => 2], "
        "(0, 10), [:tau => 5]; its plot is an image; ours meets the closed form.")
    system = second_order_system()
    run = run_model(system, tol=1e-10, outputs=5001)
    t, x = run.values("x")
    _, y = run.values("y")
    _, z = run.values("z")
    figure, axes = panels(1, 2, size=(10.0, 3.6), sharex=False)
    for values, name in ((x, "x"), (y, "y"), (z, "z")):
        axes[0].plot(t, values, linewidth=0.6, label=name)
    axes[0].set_xlabel("t (s)")
    axes[0].set_ylabel("x, y, z (1)")
    axes[0].legend(fontsize=7)
    axes[1].plot(x, y, linewidth=0.4)
    axes[1].set_xlabel("x (1)")
    axes[1].set_ylabel("y (1)")
    axes[1].set_title("plot(sol, vars = (x, y)) as the document", fontsize=8)
    save(figure, out / "mtk_second_order.png",
         "ModelingToolkit second-order system after ode_order_lowering (sigma 10, rho 10, "
         "beta 8/3)")
    drawn["mtk_second_order.png"] = (
        f"states {', '.join(run.segments[0].states)}; at t = {t[-1]:g} s x = {x[-1]:.4g}, "
        f"y = {y[-1]:.4g}, z = {z[-1]:.4g}",
        "Document: ode_order_lowering gives four states (x, D(x), y, z) and Tsit5 draws "
        "(x, y) (an image); ours lowers to the same four.")
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
    axis.set_ylabel("vC (V); i (A) x 100")
    axis.legend(fontsize=7)
    save(figure, out / "pipeline_lowpass.png", "Low-pass filter simulated by the pipeline")
    drawn["pipeline_lowpass.png"] = (
        f"max |vC - closed form| {np.max(np.abs(voltage - exact)):.2g} V; the algebraic loop "
        "of four equations torn and solved",
        "Document 000 shows the structure only; the simulation is ours, checked against the "
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
    axis.set_ylabel("x, y (m)")
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
        + (f" (first: {'; '.join(switches[:2])}" + ("; ...)" if len(switches) > 2 else ")")
           if switches else "")
        + f"; started at x = {pendulum.variables['x']:g} m, y = {pendulum.variables['y']:g} m, "
        f"g = {pendulum.parameters['g']:g} m/s^2 as the document",
        "Document 000's pipeline (ModelingToolkit's dae_index_lowering, structural_simplify) "
        "gives the "
        "same motion; ours selects x, u or y, v as states where the pivot says.")
    drawn["pipeline_pendulum_difference.png"] = (
        f"max distance {np.max(gap):.2g} m over {t[-1]:g} s",
        "Not in the document: the generated ODE agrees with the hand-written pendulum to the "
        "integrators' tolerances.")
    return drawn


def draw_modia_pendulum(result: object, out: Path, full: bool) -> dict[str, tuple[str, str]]:
    """The ModiaLang damped pendulum's figures, with the document's L = 0.5 merge, its
    statistics log beside ours, and the Modia3D pendulums."""
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
        "The document plots phi for L = 0.8 and after the merge L = 0.5 (a faster, more damped "
        "swing: the damping d / (m L^2) grows as L shrinks); its plots are images.")
    drawn["modia_pendulum_position.png"] = (
        "the path spirals in on r = (0, -L) for each L",
        "Not a document figure: r is the model's output equation, drawn for both merges.")
    drawn["modia_pendulum_statistics.png"] = statistics_figure(out)
    drawn["modia3d_pendulums.png"] = modia3d_figure(out)
    return drawn


#: The statistics compared in modia_pendulum_statistics.png.
STATISTICS = ("nAcceptedSteps", "nRejectedSteps", "nf (integrator)")


def statistics_figure(out: Path) -> tuple[str, str]:
    """Document 000's Tsit5 log beside our runs of the L = 0.5 m pendulum, as bars."""
    rows = statistics_rows()
    figure, axis = panels(size=(7.5, 3.6))
    width = 0.8 / len(rows)
    for k, row in enumerate(rows):
        positions = np.arange(len(STATISTICS)) + (k - (len(rows) - 1) / 2) * width
        values = [row[key] for key in STATISTICS]
        axis.bar(positions, values, width, label=row["run"])
        for x, value in zip(positions, values):
            axis.text(x, value, str(value), ha="center", va="bottom", fontsize=6)
    axis.set_xticks(range(len(STATISTICS)), ["accepted steps", "rejected steps",
                                             "f-evaluations by the integrator"])
    axis.set_ylabel("count")
    axis.legend(fontsize=7)
    save(figure, out / "modia_pendulum_statistics.png",
         "ModiaLang pendulum, L = 0.5 m, tol 1e-6, 501 results: document's log and ours")
    ours = rows[1]
    return (f"RK45 at rtol 1e-6, atol 1e-7: {ours['nAcceptedSteps']} accepted, "
            f"{ours['nRejectedSteps']} rejected, {ours['nf (integrator)']} f-evaluations, "
            f"{ours['nResults']} results",
            f"Document (Tsit5): {DOCUMENT_LOG['nAcceptedSteps']} accepted, "
            f"{DOCUMENT_LOG['nRejectedSteps']} rejected, {DOCUMENT_LOG['nf (integrator)']} "
            f"from the integrator, {DOCUMENT_LOG['nGetDerivatives']} in all. RK45 is the "
            "nearest scipy pair (7 stages, FSAL, 5(4)); the coefficients, error estimate and "
            "step control differ, and Modia evaluates once more per stored result.")


def modia3d_figure(out: Path) -> tuple[str, str]:
    """Pendulum1 (r = 0.5 m, and 0.3 m) and Pendulum3 over 3 s, with Pendulum1's
    closed-form period marked."""
    figure, axis = panels(size=(7.5, 3.6))
    periods = []
    for pendulum in (modia3d_pendulums.pendulum1(0.5), modia3d_pendulums.pendulum1(0.3),
                     modia3d_pendulums.pendulum3()):
        solution = modia3d_pendulums.simulate(pendulum)
        axis.plot(solution.t, solution.x[:, 0], linewidth=0.9, label=f"ours: {pendulum.label}")
        if pendulum.damping == 0.0:
            periods.append((pendulum.radius, modia3d_pendulums.first_return_time(solution),
                            modia3d_pendulums.released_horizontal_period(pendulum.radius)))
    for radius, _, exact in periods:
        axis.axvline(exact, color="grey", linewidth=0.6, linestyle=":")
    axis.plot([], [], color="grey", linewidth=0.6, linestyle=":",
              label="4 sqrt(r / g) K(1/2): closed-form period")
    axis.set_xlabel("t (s)")
    axis.set_ylabel("rev.phi (rad)")
    axis.legend(fontsize=6)
    save(figure, out / "modia3d_pendulums.png", "Modia3D Pendulum1 and Pendulum3: rev.phi(t)")
    return ("Pendulum1 period " + ", ".join(f"{found:.6f} s (closed form {exact:.6f} s, r = "
                                            f"{radius:g} m)" for radius, found, exact in periods),
            "Document: the models and plot commands only (images); Pendulum1's merge is cut "
            "off in its text (r = 0.3 m run second, from its commented line).")


STRUCTURE_SETS = tuple(FigureSet(f"structure-{example}", specs(
    *((f"structure_{example}_{view}.png",
       f"{heading(title)}: " + ("bipartite incidence matrix with the matching"
                       if view == "incidence" else "BLT-permuted incidence matrix, blocks "
                       "outlined"),
       ("Document's " + ("incidence / matching (assign list)" if view == "incidence"
                         else "BLT blocks") + f" of the {title}."))
      for view in ("incidence", "blt")),
    *((("structure_lowpass_graph.png", "Low-pass filter: the bipartite graph with the "
        "matching", "Document 000's bipartite graph G and its maximum matching."),)
      if example == "lowpass" else ())), partial(draw_structure, example))
    for example, title in STRUCTURE_TITLES.items())

PIPELINE_SETS = (
    FigureSet("pipeline-lag", specs(
        ("pipeline_lag.png", "First-order lag: x(t), document 000's two runs (tau 1 s from "
         "0; tau 5 s from 2)", "ModelingToolkit's first-order lag with defaults and overrides."),
        ("mtk_second_order.png", "ModelingToolkit's second-order system after order "
         "lowering: x, y, z and (x, y)", "Document 000's ode_order_lowering example.")),
        draw_lag),
    FigureSet("pipeline-pendulum", specs(
        ("pipeline_pendulum.png", "Cartesian pendulum: x, y from the generated ODE and the "
         "hand-written one", "Document 000's Cartesian pendulum DAE, simulated after index "
         "reduction."),
        ("pipeline_pendulum_difference.png", "Cartesian pendulum: distance between "
         "generated and hand-written solutions", "No document figure.")),
        draw_cartesian_pendulum),
    FigureSet("pipeline-lowpass", specs(
        ("pipeline_lowpass.png", "Low-pass filter: vC(t) and i(t) from the generated ODE",
         "Document 000's low-pass filter (structure only).")), draw_lowpass),
    FigureSet("pipeline-modia-pendulum", specs(
        ("modia_pendulum_phi.png", "ModiaLang damped pendulum: phi(t) for L = 0.8 and the "
         "merge L = 0.5", "Document 000's damped pendulum with the | Map(L = 0.5) merge."),
        ("modia_pendulum_position.png", "ModiaLang damped pendulum: the path r for both L",
         "The model's output r = (L cos phi, -L sin phi)."),
        ("modia_pendulum_statistics.png", "ModiaLang pendulum, L = 0.5 m: the document's "
         "Tsit5 statistics log beside our RK45 and DOP853 runs", "Document 000's log: 152 "
         "accepted, 0 rejected, 913 integrator evaluations, 1416 in all, 501 results."),
        ("modia3d_pendulums.png", "Modia3D Pendulum1 and Pendulum3: rev.phi over 3 s",
         "Document 000's Modia3D examples (models and plot commands).")),
        draw_modia_pendulum),
)
