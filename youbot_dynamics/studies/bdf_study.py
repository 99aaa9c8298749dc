"""Document 001's fixed-step study of the elastic pendulum (sections 1.6-1.9; Tables 1-4:
explicit Euler, BDF2, BDF3, BDF4 over stiffness k and step count N on [0, 20] s from
x0 = 1.2 at rest), with the document's verdicts beside ours, and CVODE's order-capped runs.

Our criterion, stated:

- unstable: the run diverges (a non-finite state, |x| beyond STABLE_BOUND, or Newton's
  iteration failing) or its energy GROWS by more than ENERGY_GROWTH (the potential-energy
  scale m g L = 1). Energy lost by a damping method is no instability.
- accurate: stable, and the position (x, y) stays within POSITION_TOLERANCE (1 % of the
  pendulum's length) of a high-accuracy reference (DOP853 at rtol = atol =
  REFERENCE_TOL) at the outputs every 0.1 s.

Why a verdict comes out as it does: the spring's eigenvalue is close to i sqrt(k), so each
cell puts z = i h sqrt(k) into the method's characteristic polynomial
(:func:`spring_mode_prediction`): the principal root's modulus |zeta| decides stability
(|zeta| > 1 grows by |zeta|^N over the run however slowly), its phase against h sqrt(k)
the phase lag, and the two together predict the position error of the spring's 0.2 m
oscillation. Document 001 judged its cells by eye on [0, 20] s, where a growth of 18 %
(BDF4, k = 200, N = 1000) or a phase lag of 0.4 periods among 142 (BDF2, k = 2000,
N = 10000) does not show.

Beside it, the energy verdict of ``study pendulum-tables`` (unstable at max|E - E0| >= 1,
accurate below 0.01): the two disagree where a method damps the spring (BDF2 at k = 2000
loses all 40 units of spring energy, "unstable" by energy, bounded and stable in fact) and
where a small energy error hides a phase error.
"""
from __future__ import annotations

import functools
import math
from dataclasses import asdict, dataclass
from functools import partial
from typing import Sequence

import numpy as np

from youbot_dynamics.integrate.integrators import DivergenceError, Solution
from youbot_dynamics.io.text_tables import markdown_table
from youbot_dynamics.studies.bdf import (alpha_angle, bdf_fixed_step, coefficients,
                                         locus_radius_on_ray, measured_boundary_radius)
from youbot_dynamics.studies.elastic_pendulum import (ACCURATE_ENERGY_ERROR, SEED_STATE0,
                                                      SEED_T_END, STABLE_BOUND, STABLE_ENERGY_ERROR,
                                                      elastic_pendulum_energy,
                                                      elastic_pendulum_jacobian,
                                                      elastic_pendulum_rhs,
                                                      simulate_elastic_pendulum)

#: Energy growth (units of m g L) beyond which a run counts as unstable.
ENERGY_GROWTH = 1.0
#: Position error (m; the pendulum is 1 long) below which a run counts as accurate.
POSITION_TOLERANCE = 1e-2
#: Tolerance of the DOP853 reference (its outputs agree with rtol 1e-10's to 3e-9 m at
#: k = 2000, measured).
REFERENCE_TOL = 1e-12
#: Output times of the comparison: every 0.1 s; of the reference run: every 0.01 s.
OUTPUTS, DENSE_OUTPUTS = 201, 2001
METHODS = ("euler", "bdf2", "bdf3", "bdf4")
#: Document 001's Tables 1-4 as printed: method -> (k, N) -> (stable?, accurate?).
DOCUMENT_TABLES = {
    "euler": {(1, 1000): ("yes", "no"), (1, 10000): ("yes", "yes"),
              (20, 1000): ("no", "no"), (20, 10000): ("yes", "yes")},
    "bdf2": {(100, 1000): ("yes", "no"), (100, 10000): ("yes", "yes"),
             (2000, 1000): ("yes", "no"), (2000, 10000): ("yes", "yes")},
    "bdf3": {(115, 1000): ("yes", "no"), (115, 10000): ("yes", "yes"),
             (500, 1000): ("no", "no"), (500, 10000): ("yes", "yes")},
    "bdf4": {(200, 1000): ("yes", "yes"), (200, 10000): ("yes", "yes"),
             (400, 1000): ("no", "no"), (400, 10000): ("yes", "yes")},
}
#: The document's (stable?, accurate?) as one of our verdicts.
VERDICT_OF_ANSWERS = {("yes", "yes"): "accurate", ("yes", "no"): "stable, inaccurate",
                      ("no", "no"): "unstable"}
#: The document's verdicts: method -> (k, N) -> verdict.
DOCUMENT_VERDICTS = {method: {cell: VERDICT_OF_ANSWERS[answers]
                              for cell, answers in table.items()}
                     for method, table in DOCUMENT_TABLES.items()}
#: The grids of Tables 1-4 (the document's stiffnesses k and step counts N), and further
#: stiffnesses run as a second, labelled set (``study bdf`` without --short).
GRIDS = {method: (tuple(sorted({k for k, _ in table})), (1000, 10000))
         for method, table in DOCUMENT_TABLES.items()}
EXTRA_GRIDS = {"bdf2": (1,), "bdf3": (1, 100, 2000), "bdf4": (1, 100, 2000)}
#: The spring's amplitude (m) from x0 = 1.2: the stretch at the start.
SPRING_AMPLITUDE = 0.2
#: Document 001's CVODE BDF step counts at rtol = atol = 1e-6: (k, max order) -> steps.
DOCUMENT_CVODE_ORDER = {(10, 1): 38_501, (50, 1): 76_856, (10, 5): 536, (50, 5): 1100}


@dataclass
class FixedStepRow:
    """One cell of Tables 1-4: the document's verdict (empty for cells it does not give),
    ours, the energy verdict, the figures, and the spring mode's linear prediction."""

    method: str
    k: float
    n_steps: int
    h_omega: float                # h sqrt(k): the spring's |h lambda| on the imaginary axis
    document: str
    verdict: str
    energy_verdict: str
    energy_growth: float | None   # max (E - E0)
    energy_error: float | None    # max |E - E0|
    position_error: float | None  # max |(x, y) - reference| (m)
    diverged_at: float | None     # s
    newton_iterations: int | None
    wall_time: float | None
    root_modulus: float = float("nan")       # |zeta| of the principal root at z = i h sqrt(k)
    predicted_growth: float = float("nan")   # |zeta|^N: the spring amplitude's factor
    predicted_phase_lag: float = float("nan")  # N (arg zeta - h sqrt(k)) (rad)
    predicted_position_error: float = float("nan")  # m, of the spring's oscillation

    def as_dict(self) -> dict:
        """The row as plain data."""
        return asdict(self)


@functools.cache
def reference_solution(k: float, tol: float = REFERENCE_TOL) -> Solution:
    """The DOP853 reference run at rtol = atol = tol, outputs every 0.01 s (DENSE_OUTPUTS
    over [0, 20] s); cached per process (the tables and the figures share it)."""
    solution, _ = simulate_elastic_pendulum(k, SEED_STATE0, SEED_T_END, "dop853", rtol=tol,
                                            atol=tol, n_out=DENSE_OUTPUTS)
    return solution


def reference_positions(k: float, tol: float = REFERENCE_TOL) -> np.ndarray:
    """(x, y) of the DOP853 reference at the OUTPUTS times (OUTPUTS, 2)."""
    stride = (DENSE_OUTPUTS - 1) // (OUTPUTS - 1)
    return reference_solution(float(k), tol).x[::stride, :2]


def energy_verdict(energy_error: float | None) -> str:
    """study pendulum-tables' verdict from max |E - E0| alone (None: diverged)."""
    if energy_error is None or energy_error >= STABLE_ENERGY_ERROR:
        return "unstable"
    return "accurate" if energy_error < ACCURATE_ENERGY_ERROR else "stable, inaccurate"


def fixed_step_states(method: str, k: float, n_steps: int, t_end: float = SEED_T_END,
                      n_out: int = OUTPUTS) -> tuple[np.ndarray, int | None, float]:
    """The states at n_out equally spaced times of a fixed-step run of n_steps steps over
    [0, t_end] s (DivergenceError if it diverges; n_steps a multiple of n_out - 1), its
    Newton iterations (None for Euler) and its wall time (s)."""
    if method == "euler":
        solution, _ = simulate_elastic_pendulum(k, SEED_STATE0, t_end, "euler",
                                                dt=t_end / n_steps, n_out=n_out,
                                                bounds=STABLE_BOUND)
        return solution.x, None, solution.stats.wall_time
    solution = bdf_fixed_step(partial(elastic_pendulum_rhs, k=k), SEED_STATE0, t_end,
                              n_steps, int(method[-1]),
                              jac=partial(elastic_pendulum_jacobian, k=k), bound=STABLE_BOUND)
    stride = n_steps // (n_out - 1)
    return (solution.x[::stride], solution.stats.nonlinear_iterations,
            solution.stats.wall_time)


def principal_root(method: str, z: complex) -> complex:
    """The root of the method's characteristic polynomial at z = h lambda that follows
    e^z (explicit Euler: 1 + z)."""
    if method == "euler":
        return 1.0 + z
    a, b = coefficients(int(method[-1]))
    polynomial = a.astype(complex)
    polynomial[0] -= z * b
    roots = np.roots(polynomial)
    return complex(roots[np.argmin(np.abs(roots - np.exp(z)))])


def spring_mode_prediction(method: str, k: float, n_steps: int,
                           t_end: float = SEED_T_END) -> dict[str, float]:
    """The linear prediction for the spring's oscillation (eigenvalue i sqrt(k), amplitude
    SPRING_AMPLITUDE) after n_steps steps of h = t_end / n_steps: |zeta|, the amplitude
    factor |zeta|^N, the phase lag N (arg zeta - h sqrt(k)) (rad) and the position error
    A |1 - |zeta|^N e^{i lag}| (m)."""
    h_omega = t_end / n_steps * float(np.sqrt(k))
    zeta = principal_root(method, 1j * h_omega)
    growth = abs(zeta) ** n_steps
    lag = n_steps * (float(np.angle(zeta)) - h_omega)
    return {"root_modulus": abs(zeta), "predicted_growth": growth,
            "predicted_phase_lag": lag,
            "predicted_position_error": SPRING_AMPLITUDE * abs(1.0 - growth * np.exp(1j * lag))}


def fixed_step_row(method: str, k: float, n_steps: int, reference: np.ndarray) -> FixedStepRow:
    """Run one cell and judge it by our criterion and by energy."""
    document = DOCUMENT_VERDICTS.get(method, {}).get((k, n_steps), "")
    h_omega = SEED_T_END / n_steps * float(np.sqrt(k))
    prediction = spring_mode_prediction(method, k, n_steps)
    try:
        states, iterations, wall = fixed_step_states(method, k, n_steps)
    except DivergenceError as error:
        return FixedStepRow(method, k, n_steps, h_omega, document, "unstable", "unstable",
                            None, None, None, error.time, None, None, **prediction)
    energy = elastic_pendulum_energy(states, k)
    growth = float(np.max(energy - energy[0]))
    error = float(np.max(np.abs(energy - energy[0])))
    position = float(np.max(np.linalg.norm(states[:, :2] - reference, axis=1)))
    verdict = ("unstable" if growth > ENERGY_GROWTH else
               "accurate" if position < POSITION_TOLERANCE else "stable, inaccurate")
    return FixedStepRow(method, k, n_steps, h_omega, document, verdict, energy_verdict(error),
                        growth, error, position, None, iterations, wall, **prediction)


def fixed_step_tables(methods: Sequence[str] = METHODS, extra: bool = False,
                      reference_tol: float = REFERENCE_TOL) -> list[FixedStepRow]:
    """Tables 1-4: the document's 16 cells (``extra``: and the EXTRA_GRIDS stiffnesses,
    after them, with an empty document verdict)."""
    cells = [(method, k, n) for method in methods for k in GRIDS[method][0]
             for n in GRIDS[method][1]]
    if extra:
        cells += [(method, k, n) for method in methods for k in EXTRA_GRIDS.get(method, ())
                  for n in GRIDS[method][1]]
    references = {k: reference_positions(k, reference_tol) for k in {c[1] for c in cells}}
    return [fixed_step_row(method, k, n, references[k]) for method, k, n in cells]


def cvode_order_rows(stiffnesses: Sequence[float] = (10, 50),
                     orders: Sequence[int] = (1, 5)) -> list[dict]:
    """CVODE BDF at rtol = atol = 1e-6 with its order capped, CVODE's own difference-
    quotient Jacobian (as document 001's Assimulo runs), beside the document's step
    counts (``document_steps``)."""
    rows = []
    for k in stiffnesses:
        for order in orders:
            solution, error = simulate_elastic_pendulum(k, SEED_STATE0, SEED_T_END,
                                                        "cvode_bdf", rtol=1e-6, atol=1e-6,
                                                        max_order=order,
                                                        jacobian="difference")
            stats = solution.stats
            document = DOCUMENT_CVODE_ORDER.get((k, order))
            rows.append({"k": k, "max_order": order, "steps": stats.steps,
                         "rhs_evals": stats.rhs_evals, "jac_evals": stats.jac_evals,
                         "document_steps": document,
                         "difference": (None if document is None
                                        else stats.steps / document - 1.0),
                         "energy_error": error, "wall_time": stats.wall_time})
    return rows


def measured_orders(orders: Sequence[int] = (1, 2, 3, 4), k: float = 10.0,
                    t_end: float = 2.0, steps: Sequence[int] = (400, 800)) -> list[dict]:
    """Order of convergence measured on the elastic pendulum: the final-state max-error
    against a DOP853 reference at 1e-13 (over [0, t_end] s, k as given) at each step
    count, and the slope log(e(N1) / e(N2)) / log(N2 / N1) between the last two."""
    reference, _ = simulate_elastic_pendulum(k, SEED_STATE0, t_end, "dop853", rtol=1e-13,
                                             atol=1e-13, n_out=2)
    rows = []
    for order in orders:
        errors = [float(np.max(np.abs(bdf_fixed_step(
            partial(elastic_pendulum_rhs, k=k), SEED_STATE0, t_end, n, order,
            jac=partial(elastic_pendulum_jacobian, k=k)).x[-1] - reference.x[-1])))
            for n in steps]
        rows.append({"order": order, "steps": list(steps), "errors": errors,
                     "measured_order": float(np.log(errors[-2] / errors[-1])
                                             / np.log(steps[-1] / steps[-2]))})
    return rows


def stability_points(rows: Sequence[FixedStepRow]) -> dict[str, complex]:
    """z = h i sqrt(k) of the BDF cells (the spring's eigenvalue near r = 1), labelled."""
    return {f"{row.method} k={row.k:g} N={row.n_steps}": 1j * row.h_omega
            for row in rows if row.method != "euler"}


#: Document 001's loose-tolerance runs (Figs 19-23): CVODE BDF with one tolerance at 0.1
#: and the other at Assimulo's default 1e-6: figure -> (k, rtol, atol).
LOOSE_TOLERANCE_RUNS = {"Fig. 19": (10.0, 0.1, 1e-6), "Fig. 20": (10.0, 1e-6, 0.1),
                        "Fig. 21": (50.0, 1e-6, 1e-6), "Fig. 22": (50.0, 1e-6, 0.1),
                        "Fig. 23": (50.0, 0.1, 1e-6)}
#: The BDF orders whose stability regions are drawn (document 001's Fig. 14: 1-6).
STABILITY_ORDERS = (1, 2, 3, 4, 5, 6)


@dataclass(frozen=True)
class BdfConfig:
    """The study's size (``short``: only the document's 16 cells, no further stiffnesses,
    no CVODE order 1 at k = 50) and where the stability bisections run (``workers``: processes of a
    local Dask cluster, 0 serial; ``scheduler``: a cluster's address; ``progress``: a bar)."""

    short: bool = False
    workers: int | None = None
    scheduler: str | None = None
    progress: bool = True


@dataclass
class BdfStudy:
    """Tables 1-4, the stability figures, the measured orders and the CVODE order caps."""

    config: BdfConfig
    rows: list[FixedStepRow]
    stability: list[dict]
    orders: list[dict]
    cvode: list[dict]


def run(config: BdfConfig) -> BdfStudy:
    """Run the study."""
    from youbot_dynamics.accuracy.sweeps import map_cases
    rows = fixed_step_tables(extra=not config.short)
    measured = map_cases(measured_boundary_radius, [(order, 0.0, 1e-3, 20.0, 20) for order in
                                                    STABILITY_ORDERS], workers=config.workers,
                         scheduler=config.scheduler, desc="stability boundaries",
                         progress=config.progress)
    stability = [{"order": order, "alpha_deg": math.degrees(alpha_angle(order)),
                  "real_axis_boundary": locus_radius_on_ray(order, 0.0),
                  "measured_by_solver": radius}
                 for order, radius in zip(STABILITY_ORDERS, measured)]
    return BdfStudy(config, rows, stability, measured_orders(),
                    cvode_order_rows((10,) if config.short else (10, 50)))


def as_json(study: BdfStudy) -> dict:
    """The tables' rows, the stability figures, the measured orders and the CVODE rows."""
    return {"tables": [row.as_dict() for row in study.rows], "stability": study.stability,
            "measured_orders": study.orders, "cvode_max_order": study.cvode}


#: Columns of Tables 1-4 and their titles.
FIXED_STEP_COLUMNS = ("k", "n_steps", "h_omega", "document", "verdict", "energy_verdict",
                      "energy_growth", "energy_error", "position_error", "diverged_at",
                      "newton_iterations", "root_modulus", "predicted_growth",
                      "predicted_position_error")
METHOD_TITLES = {"euler": "Table 1: explicit Euler", "bdf2": "Table 2: BDF2",
                 "bdf3": "Table 3: BDF3", "bdf4": "Table 4: BDF4"}


def text(study: BdfStudy) -> str:
    """The criteria, Tables 1-4, the stability table, the measured orders and the CVODE
    order caps (Markdown tables)."""
    lines = [f"Elastic pendulum on [0, {SEED_T_END:g}] from x0 = 1.2 at rest, N fixed steps. "
             f"Our verdict: unstable if the run diverges or its energy grows by more than "
             f"{ENERGY_GROWTH:g}; accurate if (x, y) stays within {POSITION_TOLERANCE:g} m of "
             f"DOP853 at rtol = atol = {REFERENCE_TOL:g} (outputs every 0.1 s). energy_verdict "
             f"is study pendulum-tables' (unstable at max|E-E0| >= {STABLE_ENERGY_ERROR:g}, "
             f"accurate below {ACCURATE_ENERGY_ERROR:g}). h_omega = h sqrt(k); root_modulus "
             f"|zeta| of the principal root at z = i h sqrt(k) (> 1: the spring grows), "
             f"predicted_growth |zeta|^N and predicted_position_error (m) of the spring's "
             f"{SPRING_AMPLITUDE:g} m oscillation by linear theory. Rows with no document "
             f"verdict are our further stiffnesses."]
    for method in METHODS:
        lines += [f"\n{METHOD_TITLES[method]}\n", markdown_table(
            FIXED_STEP_COLUMNS, ([getattr(row, c) if getattr(row, c) != "" else "-"
                                  for c in FIXED_STEP_COLUMNS]
                                 for row in study.rows if row.method == method), digits=3)]
    lines += ["\nStability: A(alpha) angle and the real-axis boundary h lambda of each BDF, "
              "from the root locus and measured by bisection on the solver's own growth on "
              "x' = lambda x\n",
              markdown_table(tuple(study.stability[0]), ([r[c] for c in r]
                                                         for r in study.stability), digits=6),
              "\nMeasured orders (elastic pendulum k = 10 on [0, 2], final-state error "
              "against DOP853 at 1e-13)\n",
              markdown_table(("order", "error N=400", "error N=800", "measured_order"),
                             ([r["order"], *r["errors"], r["measured_order"]]
                              for r in study.orders), digits=4),
              "\nCVODE BDF at rtol = atol = 1e-6, order capped (its difference-quotient "
              "Jacobian, as document 001's runs)\n",
              markdown_table(tuple(study.cvode[0]), ([r[c] for c in r] for r in study.cvode),
                             digits=4)]
    return "\n".join(lines)
