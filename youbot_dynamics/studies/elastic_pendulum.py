"""The elastic (spring) pendulum, the seed's first study (shared/benchmarks.md section 3).

A unit point mass on a spring of unit rest length and stiffness k, unit gravity along -y.
State x = (x, y, vx, vy) in the plane (m, m/s with all units 1):
    x' = vx, y' = vy, vx' = -x lambda, vy' = -y lambda - 1, lambda = k (r - 1) / r.
Energy E = (vx^2 + vy^2) / 2 + y + k (r - 1)^2 / 2 is conserved.

:func:`elastic_pendulum_study` reproduces the seed's tables with our integrators and puts
the seed's figures beside ours.
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

STATE_NAMES = ("x", "y", "vx", "vy")
#: The seed's initial state: spring stretched to r = 1.2 along x, at rest.
SEED_STATE0 = (1.2, 0.0, 0.0, 0.0)
SEED_T_END = 20.0
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
    their own by difference quotients (as the seed's Assimulo runs did). ``bounds`` bounds
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


@dataclass
class StudyRow:
    """One line of a study table: our measurement and, where the seed gives it, the seed's."""

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
    seed: str

    def as_dict(self) -> dict:
        """The row as plain data."""
        return dict(self.__dict__)


def stability_verdict(k: float, n_steps: int, integrator: str = "euler"
                      ) -> tuple[str, float | None, Solution | None]:
    """Run N fixed steps on the seed's problem; "unstable" if it diverges (non-finite or
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
              error: float | None, seed: str, verdict: str | None = None) -> StudyRow:
    """A StudyRow from a run (solution None: the run diverged)."""
    stats = None if solution is None else solution.stats
    return StudyRow(table, integrator, k, setting, verdict, error,
                    None if stats is None else stats.steps,
                    None if stats is None else stats.rhs_evals,
                    None if stats is None else stats.jac_evals,
                    None if stats is None else stats.wall_time, seed)


#: The seed's figures (benchmarks.md section 3).
SEED_EULER = {(1, 1000): "stable, inaccurate", (1, 10000): "accurate", (20, 1000): "unstable",
              (20, 10000): "accurate"}
#: The CVODE rows are run with CVODE's own difference-quotient Jacobian, as the seed's
#: Assimulo runs were (no Jacobian given): BDF k = 10 then takes the seed's 536 steps
#: exactly (545 with the analytic Jacobian).
SEED_CVODE = {("cvode_bdf", 10): "536 steps, 580 f-evals, 9 J-evals",
              ("cvode_adams", 10): "381 steps, 455 f-evals",
              ("cvode_bdf", 50): "1100 steps, 1177 f-evals",
              ("cvode_adams", 50): "737 steps, 880 f-evals",
              ("rk45", 10): "Dopri45: 201 steps, 1208 f-evals",
              ("lsoda", 10): "LSODAR: 362 steps, 747 f-evals"}


def elastic_pendulum_study(energy_k: float = 10.0,
                           fixed_steps: Sequence[int] = (1000, 10000),
                           tolerances: Sequence[float] = (1e-4, 1e-6, 1e-8)) -> list[StudyRow]:
    """The seed's tables with our integrators, seed figures beside ours:

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
