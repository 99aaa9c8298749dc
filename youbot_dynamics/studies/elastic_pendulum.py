"""The elastic (spring) pendulum, document 001's first study (its section 1).

A unit point mass on a spring of unit rest length and stiffness k, unit gravity along -y.
State x = (x, y, vx, vy) in the plane (m, m/s with all units 1):
    x' = vx, y' = vy, vx' = -x lambda, vy' = -y lambda - 1, lambda = k (r - 1) / r.
Energy E = (vx^2 + vy^2) / 2 + y + k (r - 1)^2 / 2 is conserved.

:func:`elastic_pendulum_study` reproduces the document's tables with our integrators and
puts the document's figures beside ours. :func:`taylor_reference` is an independent
reference: mpmath's Taylor-series integrator at 30 digits.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import partial
from typing import Callable, Sequence

import numpy as np

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import DivergenceError, Solution, integrate
from youbot_dynamics.integrate.registry import FIXED_STEP, INTEGRATORS
from youbot_dynamics.io.text_tables import cell, markdown_table

STATE_NAMES = ("x", "y", "vx", "vy")
#: Document 001's initial state of sections 1.7-1.11: spring stretched to r = 1.2 along x,
#: at rest; its time span (s).
SEED_STATE0 = (1.2, 0.0, 0.0, 0.0)
SEED_T_END = 20.0
#: Its free swings (Figs 1-9): k -> initial state. Figs 1-6 start at x = 1 unstretched
#: (section 1.4: "all zeros except for the x which is set to 1"), Figs 7-9 at x = 1.2.
FREE_SWINGS = {0.75: (1.0, 0.0, 0.0, 0.0), 100.0: (1.0, 0.0, 0.0, 0.0), 10.0: SEED_STATE0}
#: "Stable": the run stays finite, inside |state| <= STABLE_BOUND, with the maximum energy
#: error below STABLE_ENERGY_ERROR (the pendulum's potential-energy scale m g L = 1).
#: "Accurate": maximum energy error below ACCURATE_ENERGY_ERROR.
STABLE_BOUND = 1e3
STABLE_ENERGY_ERROR = 1.0
ACCURATE_ENERGY_ERROR = 1e-2
#: A run whose energy drifts by more than ENERGY_GROWTH_LIMIT (1 + |E0|) has diverged.
ENERGY_GROWTH_LIMIT = 100.0
#: Where the implicit integrators' Jacobian comes from: ours, or their difference quotients.
JACOBIANS = ("analytic", "difference")


def spring_force_factor(x: float, y: float, k: float) -> float:
    """lambda = k (r - 1) / r: spring force per unit length of the position vector."""
    r = math.hypot(x, y)
    return k * (r - 1.0) / r


def elastic_pendulum_rhs(t: float, state: np.ndarray, k: float) -> np.ndarray:
    """d/dt (x, y, vx, vy) for spring stiffness k."""
    x, y, vx, vy = state
    lam = spring_force_factor(x, y, k)
    return np.array([vx, vy, -x * lam, -y * lam - 1.0])


def elastic_pendulum_jacobian(t: float, state: np.ndarray, k: float) -> np.ndarray:
    """d rhs / d state (4 x 4), using d lambda / d(x, y) = k (x, y) / r^3."""
    x, y = state[0], state[1]
    r = math.hypot(x, y)
    lam = k * (r - 1.0) / r
    c = k / r**3
    return np.array([[0.0, 0.0, 1.0, 0.0],
                     [0.0, 0.0, 0.0, 1.0],
                     [-lam - c * x * x, -c * x * y, 0.0, 0.0],
                     [-c * x * y, -lam - c * y * y, 0.0, 0.0]])


def elastic_pendulum_energy(states: np.ndarray, k: float) -> np.ndarray:
    """E = (vx^2 + vy^2)/2 + y + k (r - 1)^2/2 for one state (4,) or many (n, 4)."""
    s = np.asarray(states, dtype=float)
    r = np.hypot(s[..., 0], s[..., 1])
    return 0.5 * (s[..., 2] ** 2 + s[..., 3] ** 2) + s[..., 1] + 0.5 * k * (r - 1.0) ** 2


def energy_growth_monitor(k: float, energy0: float) -> Callable[[float, np.ndarray], str | None]:
    """A monitor (see integrate) reporting divergence once |E - E0| exceeds
    ENERGY_GROWTH_LIMIT (1 + |E0|): energy growth no conservative run can show."""
    limit = ENERGY_GROWTH_LIMIT * (1.0 + abs(energy0))

    def monitor(t: float, state: np.ndarray) -> str | None:
        drift = abs(float(elastic_pendulum_energy(state, k)) - energy0)
        return f"energy drift {drift:.3g} beyond {limit:.3g}" if drift > limit else None
    return monitor


def simulate_elastic_pendulum(k: float, state0: Sequence[float], t_end: float,
                              integrator: str, *, dt: float | None = None,
                              rtol: float = 1e-6, atol: float = 1e-6, n_out: int = 201,
                              bounds: float | None = None, max_steps: int | None = None,
                              progress: Callable[[float], None] | None = None,
                              max_order: int | None = None, jacobian: str = "analytic"
                              ) -> tuple[Solution, float]:
    """Simulate from state0 over [0, t_end] (outputs at n_out equally spaced times).

    Returns the solution and the energy error max |E(t) - E(0)| over the outputs. The
    implicit methods get the analytic Jacobian, or with ``jacobian="difference"`` build
    their own by difference quotients (as document 001's Assimulo runs did). ``bounds`` bounds
    |every component|; energy growth beyond :func:`energy_growth_monitor`'s limit is a
    DivergenceError. ``max_steps`` (step budget), ``progress(t)`` and ``max_order``
    (CVODE's order cap) go to :func:`integrate`.
    """
    if jacobian not in JACOBIANS:
        raise UserInputError(f"jacobian must be one of {JACOBIANS}, got {jacobian!r}")
    if not k > 0:
        raise UserInputError(f"spring stiffness k must be positive, got {k!r}")
    if len(state0) != 4:
        raise UserInputError(f"state0 must be x,y,vx,vy (4 numbers), got {state0!r}")
    if math.hypot(state0[0], state0[1]) == 0:
        raise UserInputError("state0 puts the mass at the pivot (r = 0), where the spring "
                             "force is undefined")
    if not t_end > 0:
        raise UserInputError(f"t_end must be positive, got {t_end!r}")
    solution = integrate(partial(elastic_pendulum_rhs, k=k), state0,
                         np.linspace(0.0, t_end, n_out), integrator, dt=dt, rtol=rtol,
                         atol=atol,
                         jac=(partial(elastic_pendulum_jacobian, k=k)
                              if jacobian == "analytic" else None),
                         state_names=STATE_NAMES, n_positions=2,
                         bounds=None if bounds is None else np.full(4, bounds),
                         monitor=energy_growth_monitor(
                             k, float(elastic_pendulum_energy(state0, k))),
                         max_steps=max_steps, progress=progress, max_order=max_order)
    energy = elastic_pendulum_energy(solution.x, k)
    return solution, float(np.max(np.abs(energy - energy[0])))


def taylor_reference(k: float, state0: Sequence[float], times: Sequence[float],
                     digits: int = 30) -> np.ndarray:
    """The state (x, y, vx, vy) at ``times`` (s, ascending from 0) by mpmath's Taylor-series
    integrator (``mpmath.odefun``) at ``digits`` significant digits: an independent
    reference for the float integrators (n, 4)."""
    import mpmath
    with mpmath.workdps(digits):
        stiffness = mpmath.mpf(k)

        def rhs(t, state):
            x, y, vx, vy = state
            r = mpmath.sqrt(x * x + y * y)
            lam = stiffness * (r - 1) / r
            return [vx, vy, -x * lam, -y * lam - 1]
        solution = mpmath.odefun(rhs, 0, [mpmath.mpf(v) for v in state0],
                                 tol=mpmath.mpf(10) ** (-digits + 5))
        return np.array([[float(v) for v in solution(t)] for t in times])


@dataclass
class StudyRow:
    """One line of a study table: our measurement and, where document 001 gives it, its
    value (``document``)."""

    table: str
    integrator: str
    k: float
    setting: str                 # "N=1000" / "dt=0.002" / "tol=1e-06"
    verdict: str | None          # stable / unstable / accurate, for the Euler table
    energy_error: float | None
    steps: int | None
    rhs_evals: int | None
    jac_evals: int | None
    wall_time: float | None
    document: str
    nonlinear_iterations: int | None = None

    def as_dict(self) -> dict:
        """The row as plain data."""
        return dict(self.__dict__)


def stability_verdict(k: float, n_steps: int, integrator: str = "euler"
                      ) -> tuple[str, float | None, Solution | None]:
    """Run N fixed steps on document 001's problem; "unstable" if it diverges (non-finite or
    beyond STABLE_BOUND) or its energy error reaches STABLE_ENERGY_ERROR, "accurate" below
    ACCURATE_ENERGY_ERROR, else "stable, inaccurate"."""
    try:
        solution, error = simulate_elastic_pendulum(k, SEED_STATE0, SEED_T_END, integrator,
                                                    dt=SEED_T_END / n_steps,
                                                    bounds=STABLE_BOUND)
    except DivergenceError:
        return "unstable", None, None
    if error >= STABLE_ENERGY_ERROR:
        return "unstable", error, solution
    return ("accurate" if error < ACCURATE_ENERGY_ERROR else "stable, inaccurate"), error, \
        solution


def study_row(table: str, integrator: str, k: float, setting: str, solution: Solution | None,
              error: float | None, document: str, verdict: str | None = None) -> StudyRow:
    """A StudyRow from a run (solution None: the run diverged)."""
    stats = None if solution is None else solution.stats
    return StudyRow(table, integrator, k, setting, verdict, error,
                    None if stats is None else stats.steps,
                    None if stats is None else stats.rhs_evals,
                    None if stats is None else stats.jac_evals,
                    None if stats is None else stats.wall_time, document,
                    None if stats is None else stats.nonlinear_iterations)


#: Document 001's Table 1 verdicts and Tables 5-6 counts.
SEED_EULER = {(1, 1000): "stable, inaccurate", (1, 10000): "accurate", (20, 1000): "unstable",
              (20, 10000): "accurate"}
#: The CVODE rows are run with CVODE's own difference-quotient Jacobian, as document 001's
#: Assimulo runs were (no Jacobian given): BDF k = 10 then takes the document's 536 steps
#: exactly (545 with the analytic Jacobian).
SEED_CVODE = {("cvode_bdf", 10): "536 steps, 580 f-evals, 9 J-evals, 576 nonlinear",
              ("cvode_adams", 10): "381 steps, 455 f-evals, 7 J-evals, 451 nonlinear",
              ("cvode_bdf", 50): "1100 steps, 1177 f-evals, 19 J-evals, 1173 nonlinear",
              ("cvode_adams", 50): "737 steps, 880 f-evals, 13 J-evals, 876 nonlinear",
              ("rk45", 10): "Dopri45: 201 steps, 1208 f-evals",
              ("lsoda", 10): "LSODAR: 362 steps, 747 f-evals"}


def elastic_pendulum_study(energy_k: float = 10.0,
                           fixed_steps: Sequence[int] = (1000, 10000),
                           tolerances: Sequence[float] = (1e-4, 1e-6, 1e-8)) -> list[StudyRow]:
    """Document 001's tables with our integrators, its figures beside ours:

    1. explicit Euler stable or not for k = 1, 20 with N = 1000, 10000 steps on [0, 20];
    2. CVODE BDF vs Adams (and Dormand-Prince) at rtol = atol = 1e-6, k = 10 and 50;
    3. energy error versus step count / tolerance for every ODE integrator at k=energy_k.
    """
    rows = []
    for k, n in SEED_EULER:
        verdict, error, solution = stability_verdict(k, n)
        rows.append(study_row("euler_stability", "euler", k, f"N={n}", solution, error,
                              SEED_EULER[(k, n)], verdict))
    for integrator, k in SEED_CVODE:
        solution, error = simulate_elastic_pendulum(k, SEED_STATE0, SEED_T_END, integrator,
                                                    rtol=1e-6, atol=1e-6,
                                                    jacobian="difference")
        rows.append(study_row("cvode_statistics", integrator, k, "tol=1e-06", solution, error,
                              SEED_CVODE[(integrator, k)]))
    for integrator in INTEGRATORS:
        if integrator == "ida":
            continue
        settings = ([("dt", SEED_T_END / n) for n in fixed_steps] if integrator in FIXED_STEP
                    else [("tol", tol) for tol in tolerances])
        for name, value in settings:
            options = {"dt": value} if name == "dt" else {"rtol": value, "atol": value}
            try:
                solution, error = simulate_elastic_pendulum(
                    energy_k, SEED_STATE0, SEED_T_END, integrator, bounds=STABLE_BOUND,
                    **options)
            except DivergenceError:
                solution, error = None, None
            rows.append(study_row("energy_error", integrator, energy_k, f"{name}={value:g}",
                                  solution, error, ""))
    return rows


#: The default integrator of ``study pendulum``, and the one --tol picks when none is
#: named: its global error on ``--k 1000 --state0 1.1,0,0,0 --duration 10`` measured 8.6e-11
#: at tol 1e-12 where cvode_bdf's was 1.7e-8 (both local-error controlled; the run spans 50
#: periods).
DEFAULT_INTEGRATOR, ACCURATE_INTEGRATOR = "cvode_bdf", "dop853"
#: Output times of ``study pendulum`` (equally spaced over [0, duration]).
OUTPUTS = 201
#: rtol and atol when no tolerance is given.
DEFAULT_RTOL = DEFAULT_ATOL = 1e-6


@dataclass(frozen=True)
class PendulumConfig:
    """One run: stiffness k, the initial (x, y, vx, vy), the simulated ``duration`` (s),
    the integrator, a fixed step ``dt`` (s), rtol and atol (a number or one per
    component), a step budget, CVODE's order cap and where the Jacobian comes from."""

    k: float = 10.0
    state0: tuple[float, ...] = SEED_STATE0
    duration: float = SEED_T_END
    integrator: str = DEFAULT_INTEGRATOR
    dt: float | None = None
    rtol: float = DEFAULT_RTOL
    atol: object = DEFAULT_ATOL
    max_steps: int | None = None
    max_order: int | None = None
    jacobian: str = "analytic"


@dataclass
class PendulumRun:
    """The run's solution and its energy error max |E - E0|."""

    config: PendulumConfig
    solution: Solution
    energy_error: float

    @property
    def final_state(self) -> dict[str, float]:
        """x, y (m), vx, vy (m/s) at the end."""
        return dict(zip(STATE_NAMES, map(float, self.solution.x[-1])))


def run(config: PendulumConfig, progress: Callable[[float], None] | None = None) -> PendulumRun:
    """Simulate (``progress(t)`` after each step, if given); IntegrationError if the
    integrator fails."""
    solution, energy_error = simulate_elastic_pendulum(
        config.k, config.state0, config.duration, config.integrator, dt=config.dt,
        rtol=config.rtol, atol=config.atol, n_out=OUTPUTS, max_steps=config.max_steps,
        progress=progress, max_order=config.max_order, jacobian=config.jacobian)
    return PendulumRun(config, solution, energy_error)


def as_json(result: PendulumRun) -> dict:
    """k, the end time (s), the final state, the energy error and the statistics."""
    return {"k": result.config.k, "t_end": float(result.solution.t[-1]),
            "final_state": result.final_state, "energy_error": result.energy_error,
            "stats": result.solution.stats.as_dict()}


def text(result: PendulumRun) -> str:
    """The final state, the energy error and the statistics."""
    config, solution = result.config, result.solution
    return "\n".join([
        f"elastic pendulum k={config.k:g}, {config.integrator}, t={solution.t[-1]:g} s",
        "final state: " + ", ".join(f"{name}={value:.9g}"
                                    for name, value in result.final_state.items()),
        f"energy error max|E-E0|: {result.energy_error:.3e}",
        f"statistics: {solution.stats.summary()}"])


#: The tables of ``study pendulum-tables`` (StudyRow.table -> title).
TABLE_TITLES = {
    "euler_stability": f"Explicit Euler on [0, {SEED_T_END:g}] from x0 = 1.2 (stable: finite, "
                       f"|state| <= {STABLE_BOUND:g} and max|E-E0| < {STABLE_ENERGY_ERROR:g}; "
                       f"accurate: max|E-E0| < {ACCURATE_ENERGY_ERROR:g})",
    "cvode_statistics": "Statistics at rtol = atol = 1e-6 from x0 = 1.2 on [0, 20] (CVODE "
                        "and LSODA with their own difference-quotient Jacobians, as the "
                        "document 001's runs; scipy's LSODA beside its LSODAR)",
    "energy_error": "Energy error max|E-E0| versus step size / tolerance",
}
TABLE_COLUMNS = ("integrator", "k", "setting", "verdict", "energy_error", "steps", "rhs_evals",
                 "jac_evals", "nonlinear_iterations", "wall_time", "document")
TEXT_COLUMNS = ("integrator", "setting", "verdict", "document")


def tables_text(rows: Sequence[StudyRow]) -> str:
    """The study's tables (Markdown) with each verdict that differs from the document's
    noted."""
    lines = []
    for table, title in TABLE_TITLES.items():
        lines += [f"\n{title}\n", markdown_table(TABLE_COLUMNS, (
            [(getattr(row, c) or "-") if c in TEXT_COLUMNS else getattr(row, c)
             for c in TABLE_COLUMNS] for row in rows if row.table == table), digits=3)]
        lines += [f"- k={row.k:g} {row.setting}: document 001 says {row.document!r}, our energy "
                  f"criterion {row.verdict!r} (max|E-E0| {cell(row.energy_error)}); "
                  f"study bdf judges position against a reference instead"
                  for row in rows if row.table == table and row.verdict and row.document
                  and row.verdict != row.document]
    return "\n".join(lines)
