"""The elastic pendulum's figures (seed 001, Lund course project 1: sections 1.1-1.9,
Tables 1-7; benchmarks.md section 3): the fixed-step runs of Tables 1-4 against a DOP853
reference, the CVODE / Dopri45 / LSODA runs of Tables 5-7, the order caps, the rtol = 0.1
"choppy" traces, the BDF stability regions and measured orders.

Every trajectory figure draws x(t) and y(t) (m) of the run over the reference's (DOP853 at
rtol = atol = 1e-12, dashed). Verdicts are study bdf's (studies/bdf_study.py): unstable
when the run diverges or its energy grows by more than 1; accurate when (x, y) stays
within 1 cm of the reference at the outputs every 0.1 s.
"""
from __future__ import annotations

import re
from pathlib import Path
from typing import Sequence

import numpy as np

from youbot_dynamics.integrate.integrators import DivergenceError
from youbot_dynamics.studies.bdf import alpha_angle, amplification, root_locus
from youbot_dynamics.studies.bdf_study import (CHOPPY_K, CHOPPY_TOL, DENSE_OUTPUTS,
                                               REFERENCE_TOL, SEED_CVODE_ORDER, SEED_VERDICTS,
                                               fixed_step_row, fixed_step_states,
                                               measured_orders, reference_positions,
                                               reference_solution, stability_points)
from youbot_dynamics.studies.elastic_pendulum import (SEED_CVODE, SEED_STATE0, SEED_T_END,
                                                      elastic_pendulum_energy,
                                                      simulate_elastic_pendulum)
from youbot_dynamics.studies.figures import FigureSet, heading, panels, pyplot, save, specs

#: Fixed-step cells with a seed verdict: (method, k, N) -> file.
FIXED_STEP_FILES = {("euler", 1, 1000): "pendulum_euler_k1_n1000.png",
                    ("euler", 1, 10000): "pendulum_euler_k1_n10000.png",
                    ("euler", 20, 1000): "pendulum_euler_k20_n1000.png",
                    ("euler", 20, 10000): "pendulum_euler_k20_n10000.png",
                    ("bdf2", 100, 1000): "bdf2_k100_n1000.png",
                    ("bdf2", 2000, 1000): "bdf2_k2000_n1000.png",
                    ("bdf3", 500, 1000): "bdf3_k500_n1000.png",
                    ("bdf4", 400, 1000): "bdf4_k400_n1000.png"}
#: Adaptive runs at rtol = atol = 1e-6 with the seed's figures (Tables 5-7, the keys of
#: elastic_pendulum.SEED_CVODE): (integrator, k) -> file.
ADAPTIVE_FILES = {("cvode_bdf", 10): "pendulum_cvode_bdf_k10.png",
                  ("cvode_adams", 10): "pendulum_cvode_adams_k10.png",
                  ("cvode_bdf", 50): "pendulum_cvode_bdf_k50.png",
                  ("cvode_adams", 50): "pendulum_cvode_adams_k50.png",
                  ("rk45", 10): "pendulum_dopri45_k10.png",
                  ("lsoda", 10): "pendulum_lsoda_k10.png"}
#: Integrators and tolerances (short form, full form) of the energy work-precision figure.
PRECISION_INTEGRATORS = ("cvode_bdf", "cvode_adams", "rk45", "dop853", "lsoda")
PRECISION_TOLERANCES = {False: (1e-4, 1e-7), True: (1e-4, 1e-6, 1e-8, 1e-10)}


def plot_stability_regions(path: str, orders=(1, 2, 3, 4),
                           points: dict[str, complex] | None = None) -> None:
    """PNG of the root loci (stability boundaries) of the given orders, the unstable side
    shaded: the whole regions, and a close-up of the imaginary axis near 0 with optional
    labelled points z = h lambda."""
    plt = pyplot()

    figure, axes = plt.subplots(1, 2, figsize=(11, 5.5))
    theta = np.linspace(0.0, 2.0 * np.pi, 4001)
    for axis in axes:
        for order in orders:
            z = root_locus(order, theta)
            line, = axis.plot(z.real, z.imag, label=f"BDF{order} "
                              f"(A({np.degrees(alpha_angle(order)):.2f} deg))")
            axis.fill(z.real, z.imag, color=line.get_color(), alpha=0.08)
        axis.axhline(0.0, color="grey", linewidth=0.5)
        axis.axvline(0.0, color="grey", linewidth=0.5)
        axis.set_xlabel("Re h lambda")
        axis.set_ylabel("Im h lambda")
        axis.grid(True, alpha=0.3)
    for label, z in (points or {}).items():
        axes[1].plot(z.real, z.imag, "k.", markersize=6)
        axes[1].annotate(label, (z.real, z.imag), fontsize=7, xytext=(4, -2),
                         textcoords="offset points")
    axes[0].set_aspect("equal")
    axes[0].legend(fontsize=8, loc="lower right")
    axes[0].set_title("BDF1-4: unstable inside each closed curve (shaded)")
    axes[1].set_xlim(-0.8, 0.6)
    axes[1].set_ylim(-0.1, 2.0)
    axes[1].set_title("near the imaginary axis: the spring's h i sqrt(k)", fontsize=10)
    save(figure, path)


def plot_choppy_traces(path: str,
                       integrators: Sequence[str] = ("cvode_bdf", "cvode_adams")) -> dict:
    """PNG of x(t) and y(t) from CVODE (BDF and Adams, or the ``integrators`` given) at
    rtol = atol = CHOPPY_TOL (k = CHOPPY_K, CVODE's difference-quotient Jacobian) against
    the DOP853 reference, outputs by CVODE's interpolation every 0.01 s over [0, 20] s.
    Returns each run's steps and max position error (m)."""
    plt = pyplot()

    reference = reference_solution(CHOPPY_K)
    figure, axes = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
    figures = {}
    for integrator in integrators:
        solution, _ = simulate_elastic_pendulum(CHOPPY_K, SEED_STATE0, SEED_T_END,
                                                integrator, rtol=CHOPPY_TOL, atol=CHOPPY_TOL,
                                                n_out=DENSE_OUTPUTS, jacobian="difference")
        error = float(np.max(np.linalg.norm(solution.x[:, :2] - reference.x[:, :2], axis=1)))
        figures[integrator] = {"steps": solution.stats.steps, "position_error": error}
        for axis, column in zip(axes, (0, 1)):
            axis.plot(solution.t, solution.x[:, column], linewidth=0.9,
                      label=f"{integrator} ({solution.stats.steps} steps)")
    for axis, column, label in zip(axes, (0, 1), ("x (m)", "y (m)")):
        axis.plot(reference.t, reference.x[:, column], "k--", linewidth=0.6,
                  label=f"DOP853 {REFERENCE_TOL:g}")
        axis.set_ylabel(label)
        axis.grid(True, alpha=0.3)
        axis.legend(fontsize=8, loc="upper right")
    axes[0].set_title(f"Elastic pendulum k = {CHOPPY_K:g}, CVODE at rtol = atol = "
                      f"{CHOPPY_TOL:g}", fontsize=10)
    axes[1].set_xlabel("t (s)")
    save(figure, path)
    return figures


def method_label(method: str) -> str:
    """'explicit Euler' or 'BDF2'..."""
    return "explicit Euler" if method == "euler" else method.upper()


def fixed_step_spec(method: str, k: int, n: int, file: str):
    """(file, caption, seed) of one fixed-step cell."""
    table = {"euler": 1, "bdf2": 2, "bdf3": 3, "bdf4": 4}[method]
    return (file, f"{heading(method_label(method))}, k = {k}, N = {n} steps on [0, 20] s: "
                  "x(t), y(t) against the DOP853 reference",
            f"Table {table}: {SEED_VERDICTS[method][(k, n)]}.")


def adaptive_spec(integrator: str, k: int, file: str):
    """(file, caption, seed) of one adaptive run at tol 1e-6."""
    seed = SEED_CVODE[(integrator, k)]
    name = {"rk45": "Dormand-Prince 4(5) (Dopri45)", "lsoda": "LSODA (scipy)"}.get(
        integrator, integrator.replace("cvode_", "CVODE ").replace("bdf", "BDF")
        .replace("adams", "Adams"))
    return (file, f"{name}, k = {k}, rtol = atol = 1e-6: x(t), y(t) against the reference",
            f"Tables 5-7: {seed}.")


def seed_counts(text: str) -> dict[str, int]:
    """{'steps': 536, 'f-evals': 580, ...} from the seed's words."""
    return {key: int(value) for value, key in re.findall(r"(\d+) (steps|f-evals|J-evals)", text)}


def fixed_step_trajectory(method: str, k: float, n_steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Times and states at every step of a fixed-step run on the seed's problem; a run
    that diverges is run again up to two steps before it diverged (the part to draw)."""
    h = SEED_T_END / n_steps
    n = n_steps
    for _ in range(4):
        try:
            states, _, _ = fixed_step_states(method, k, n, n * h, n + 1)
            return h * np.arange(n + 1), states
        except DivergenceError as error:
            n = max(1, int(error.time / h) - 2)
    raise RuntimeError(f"{method} k={k} N={n_steps}: no finite stretch to draw")


def trajectory_plot(path: Path, t, x, reference, title: str, diverged_at: float | None = None,
                    style: str = "-") -> None:
    """x(t), y(t) of a run (solid) over the reference (dashed); the divergence time marked."""
    figure, axis = panels(size=(7.5, 3.6))
    axis.plot(reference.t, reference.x[:, 0], "k--", linewidth=0.6, label="x reference")
    axis.plot(reference.t, reference.x[:, 1], "--", color="grey", linewidth=0.6,
              label="y reference")
    axis.plot(t, x[:, 0], style, color="tab:blue", linewidth=0.8, label="x")
    axis.plot(t, x[:, 1], style, color="tab:orange", linewidth=0.8, label="y")
    if diverged_at is not None:
        axis.axvline(diverged_at, color="red", linewidth=0.8, label="diverged")
        axis.set_ylim(-3.0, 3.0)
    axis.set_xlabel("t (s)")
    axis.set_ylabel("position (m)")
    axis.legend(fontsize=7, loc="upper right", ncol=5)
    save(figure, path, title)


def verdict_text(row) -> str:
    """Our verdict of a fixed-step cell with its figures."""
    if row.diverged_at is not None:
        return f"unstable: diverged at t = {row.diverged_at:.3g} s (h sqrt(k) = {row.h_omega:.3g})"
    return (f"{row.verdict}: position error up to {row.position_error:.3g} m against DOP853, "
            f"energy grows by at most {row.energy_growth:.3g} (h sqrt(k) = {row.h_omega:.3g}); "
            f"study pendulum-tables' energy verdict: {row.energy_verdict}")


def agreement(seed: str, ours: str) -> str:
    """'agrees' or how the verdicts differ."""
    if seed == ours:
        return f"Same verdict ({ours})."
    return f"Seed {seed!r}, ours {ours!r}."


def draw_fixed_step(out: Path, method: str, k: int, n: int) -> tuple[tuple[str, str], object]:
    """One fixed-step cell's figure; (our verdict, the difference from the seed's) and
    the cell's FixedStepRow."""
    reference = reference_solution(float(k))
    row = fixed_step_row(method, k, n, reference_positions(k))
    t, x = fixed_step_trajectory(method, k, n)
    every = max(1, len(t) // 4000)
    trajectory_plot(out / FIXED_STEP_FILES[(method, k, n)], t[::every], x[::every], reference,
                    f"{heading(method_label(method))}, k = {k}, N = {n}: {row.verdict}",
                    row.diverged_at)
    difference = agreement(row.seed, row.verdict)
    if row.energy_verdict != row.verdict:
        difference += (f" By energy alone (study pendulum-tables) it would be {row.energy_verdict!r}: "
                       "the position criterion is the one stated above the tables.")
    return (verdict_text(row), difference), row


def draw_adaptive(out: Path, integrator: str, k: int) -> tuple[tuple[str, str], object]:
    """One adaptive run at tol 1e-6 (difference-quotient Jacobian, as the seed's), its
    figure, and (ours, difference) against the seed's counts; also the solution."""
    solution, energy_error = simulate_elastic_pendulum(k, SEED_STATE0, SEED_T_END, integrator,
                                                       rtol=1e-6, atol=1e-6, n_out=DENSE_OUTPUTS,
                                                       jacobian="difference")
    reference = reference_solution(float(k))
    error = float(np.max(np.linalg.norm(solution.x[:, :2] - reference.x[:, :2], axis=1)))
    stats = solution.stats
    trajectory_plot(out / ADAPTIVE_FILES[(integrator, k)], solution.t, solution.x, reference,
                    f"{integrator}, k = {k}, tol 1e-6: {stats.steps} steps, "
                    f"{stats.rhs_evals} f-evals")
    seed = seed_counts(SEED_CVODE[(integrator, k)])
    ours = (f"{stats.steps} steps, {stats.rhs_evals} f-evals"
            + (f", {stats.jac_evals} J-evals" if stats.jac_evals else "")
            + f"; position error up to {error:.3g} m, energy error {energy_error:.3g}")
    difference = "; ".join(
        f"{key} {value} ours {mine} ({mine / value - 1.0:+.1%})"
        for key, value, mine in ((key, value, {"steps": stats.steps, "f-evals": stats.rhs_evals,
                                               "J-evals": stats.jac_evals}[key])
                                 for key, value in seed.items()) if mine is not None)
    if integrator == "lsoda":
        difference = ("The seed ran LSODAR (LSODA with root finding); ours is scipy's LSODA. "
                      "Seed " + difference)
    elif integrator == "rk45":
        difference = "Ours is scipy's RK45 (Dormand-Prince 4(5)). Seed " + difference
    else:
        difference = "Seed " + difference
    return (ours, difference), solution


def draw_pendulum(result: object, out: Path, full: bool) -> dict[str, tuple[str, str]]:
    """The figures of PENDULUM_SET."""
    drawn = {FIXED_STEP_FILES[cell]: draw_fixed_step(out, *cell)[0]
             for cell in FIXED_STEP_FILES if cell[0] == "euler"}
    solutions = {}
    for (integrator, k), file in ADAPTIVE_FILES.items():
        drawn[file], solutions[(integrator, k)] = draw_adaptive(out, integrator, k)

    figure, axis = panels(size=(7.5, 3.6))
    spread = {}
    for (integrator, k), solution in solutions.items():
        if k != 10:
            continue
        energy = elastic_pendulum_energy(solution.x, k)
        axis.plot(solution.t, energy - energy[0], linewidth=0.8, label=integrator)
        spread[integrator] = float(np.max(np.abs(energy - energy[0])))
    axis.set_xlabel("t (s)")
    axis.set_ylabel("E(t) - E(0)")
    axis.legend(fontsize=7)
    save(figure, out / "pendulum_energy_k10.png",
         "Elastic pendulum k = 10, rtol = atol = 1e-6: energy error over time")
    worst = max(spread, key=spread.get)
    drawn["pendulum_energy_k10.png"] = (
        "max |E - E0|: " + ", ".join(f"{name} {value:.2g}" for name, value in spread.items()),
        f"The seed gives no energy figure; the largest drift is {worst}'s.")

    tolerances = PRECISION_TOLERANCES[full]
    figure, axis = panels(size=(7.5, 4.2))
    best = {}
    for integrator in PRECISION_INTEGRATORS:
        evals, errors = [], []
        for tol in tolerances:
            solution, error = simulate_elastic_pendulum(10.0, SEED_STATE0, SEED_T_END,
                                                        integrator, rtol=tol, atol=tol,
                                                        jacobian="difference")
            evals.append(solution.stats.rhs_evals)
            errors.append(error)
        axis.loglog(evals, errors, "o-", label=integrator, markersize=4)
        best[integrator] = (evals[-1], errors[-1])
    axis.set_xlabel("right-hand-side evaluations")
    axis.set_ylabel("max |E - E0|")
    axis.legend(fontsize=7)
    save(figure, out / "pendulum_work_precision_k10.png",
         "Elastic pendulum k = 10: energy error against work, tol "
         + ", ".join(f"{tol:g}" for tol in tolerances))
    drawn["pendulum_work_precision_k10.png"] = (
        f"at tol {tolerances[-1]:g}: " + ", ".join(
            f"{name} {evals} f-evals for {error:.2g}" for name, (evals, error) in best.items()),
        "The seed tabulates steps and f-evals at one tolerance (Table 6); ours draws the "
        "whole curve, so the cheapest method at each accuracy can be read off.")
    return drawn


def draw_bdf(result: object, out: Path, full: bool) -> dict[str, tuple[str, str]]:
    """The figures of BDF_SET."""
    drawn, rows = {}, []
    for cell in (cell for cell in FIXED_STEP_FILES if cell[0] != "euler"):
        drawn[FIXED_STEP_FILES[cell]], row = draw_fixed_step(out, *cell)
        rows.append(row)
    plot_stability_regions(str(out / "bdf_stability.png"), points=stability_points(rows))
    angles = {order: np.degrees(alpha_angle(order)) for order in (1, 2, 3, 4)}
    growths = [(row, amplification(int(row.method[-1]), 1j * row.h_omega)) for row in rows]
    drawn["bdf_stability.png"] = (
        "A(alpha): " + ", ".join(f"BDF{order} {angle:.2f} deg" for order, angle in angles.items())
        + "; the seed's cells drawn at z = i h sqrt(k) (the spring's eigenvalue)",
        "Published A(alpha) angles: BDF3 86.03 deg, BDF4 73.35 deg (Hairer-Wanner II, "
        "section V.2); BDF1 and BDF2 are A-stable. Largest root |zeta| at the seed's "
        "cells: " + "; ".join(f"{row.method} k = {row.k:g}: {growth:.4f}"
                               for row, growth in growths)
        + " (> 1: unstable, as the seed found for BDF3 k = 500 and BDF4 k = 400).")

    steps = (100, 200, 400, 800, 1600) if full else (200, 400, 800)
    orders = measured_orders(steps=steps)
    figure, axis = panels(size=(6.5, 4.2))
    for row in orders:
        axis.loglog(row["steps"], row["errors"], "o-", markersize=4,
                    label=f"BDF{row['order']}: slope {row['measured_order']:.2f}")
    axis.set_xlabel("steps N on [0, 2] s")
    axis.set_ylabel("final-state max error")
    axis.legend(fontsize=7)
    save(figure, out / "bdf_orders.png",
         "Fixed-step BDF1-4 on the elastic pendulum (k = 10): error against steps")
    drawn["bdf_orders.png"] = (
        "measured orders " + ", ".join(f"{row['measured_order']:.2f}" for row in orders),
        "The seed gives no convergence figure; orders 1-4 are the methods' by construction, "
        "and ours measure within "
        f"{max(abs(row['measured_order'] - row['order']) for row in orders):.2f} of them.")

    for integrator, file in (("cvode_bdf", "bdf_choppy_cvode_bdf.png"),
                             ("cvode_adams", "bdf_choppy_cvode_adams.png")):
        figures = plot_choppy_traces(str(out / file), integrators=(integrator,))[integrator]
        drawn[file] = (f"{figures['steps']} steps; position off the reference by up to "
                       f"{figures['position_error']:.2f} m",
                       "As the seed's: at rtol = atol = 0.1 the run follows the first "
                       "swing, then loses the spring's oscillation and the phase (k = "
                       f"{CHOPPY_K:g}); the seed's traces are not in benchmarks.md, so the "
                       "comparison is by eye.")

    reference = reference_solution(10.0)
    figure, axis = panels(size=(7.5, 3.8))
    counts = {}
    for order in ((1, 2, 3, 4, 5) if full else (1, 5)):
        solution, _ = simulate_elastic_pendulum(10.0, SEED_STATE0, SEED_T_END, "cvode_bdf",
                                                rtol=1e-6, atol=1e-6, n_out=DENSE_OUTPUTS,
                                                max_order=order, jacobian="difference")
        error = np.linalg.norm(solution.x[:, :2] - reference.x[:, :2], axis=1)
        counts[order] = solution.stats.steps
        axis.semilogy(solution.t, error + 1e-16, linewidth=0.8,
                      label=f"max order {order}: {solution.stats.steps} steps")
    axis.set_xlabel("t (s)")
    axis.set_ylabel("|(x, y) - reference| (m)")
    axis.legend(fontsize=7)
    save(figure, out / "bdf_cvode_max_order_k10.png",
         "CVODE BDF with its order capped, k = 10, rtol = atol = 1e-6")
    seed1, seed5 = SEED_CVODE_ORDER[(10, 1)], SEED_CVODE_ORDER[(10, 5)]
    drawn["bdf_cvode_max_order_k10.png"] = (
        "steps: " + ", ".join(f"order {order} {steps}" for order, steps in counts.items()),
        f"Seed: order 1 {seed1} steps, ours {counts[1]} ({counts[1] / seed1 - 1:+.1%}); "
        f"order 5 {seed5}, ours {counts[5]} ({counts[5] / seed5 - 1:+.1%}).")
    return drawn


PENDULUM_SET = FigureSet("pendulum-tables", specs(
    *(fixed_step_spec(*cell, file) for cell, file in FIXED_STEP_FILES.items()
      if cell[0] == "euler"),
    *(adaptive_spec(*key, file) for key, file in ADAPTIVE_FILES.items()),
    ("pendulum_energy_k10.png", "Energy error E(t) - E(0) of the tol 1e-6 runs at k = 10",
     "No figure: Tables 5-7 give steps and evaluations only."),
    ("pendulum_work_precision_k10.png",
     "Work-precision: energy error against f-evals over tolerances, k = 10",
     "Table 6 at tol 1e-6 (steps, f-evals of CVODE BDF / Adams, Dopri45, LSODAR)."),
), draw_pendulum)

BDF_SET = FigureSet("bdf", specs(
    *(fixed_step_spec(*cell, file) for cell, file in FIXED_STEP_FILES.items()
      if cell[0] != "euler"),
    ("bdf_stability.png", "Stability regions of BDF1-4 (root loci), and the seed's cells "
     "near the imaginary axis", "The stability-region plot of section 1.9."),
    ("bdf_orders.png", "Measured order of fixed-step BDF1-4 (error against N, log-log)",
     "Not in the seed: the methods' nominal orders 1-4."),
    ("bdf_choppy_cvode_bdf.png", "CVODE BDF at rtol = atol = 0.1, k = 10: the 'choppy' "
     "trace", "The choppy rtol 0.1 trace of CVODE BDF."),
    ("bdf_choppy_cvode_adams.png", "CVODE Adams at rtol = atol = 0.1, k = 10: the 'choppy' "
     "trace", "The choppy rtol 0.1 trace of CVODE Adams."),
    ("bdf_cvode_max_order_k10.png", "CVODE BDF capped at order 1 and 5 (full: 1-5): "
     "position error and steps", "38 501 steps at order 1 against 536 at order 5 (k = 10)."),
), draw_bdf)
