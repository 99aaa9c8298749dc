"""Rotations study (document 000, section 1; benchmarks.md section 7): three orientation states of
a torque-free rigid body, compared on the same Euler equations.

The body: principal inertia J = diag(J1, J2, J3) (kg m^2), body angular velocity w (rad/s,
body frame), attitude R (3x3, body axes in the world frame). Euler's equations
J w' = (J w) x w; the attitude kinematics R' = R [w]. Three states for R:

- ``cardan``: Cardan (Tait-Bryan) angles of the intrinsic x-y-z sequence,
  R = Rot(x, a1) Rot(y, a2) Rot(z, a3) (Modia3D's ``rot123``); w = B(a) a', an ODE with
  no constraint, singular where cos a2 = 0 (gimbal lock: first and third axes align).
- ``cardan_adaptive``: Modia3D's remedy. The same angles, but when |a2| exceeds
  ``SWITCH_ANGLE`` (1.5 rad) a state event switches the sequence x-y-z <-> x-z-y
  (R = Rot(x, a1) Rot(z, a2) Rot(y, a3)), re-expressing the same attitude in the other
  sequence, whose middle angle is then near 0 (integrate/events.py simulate_hybrid).
- ``quaternion``: q = (x, y, z, w) (the ROS order of model/lie.py), q' = q (x) (w, 0) / 2,
  four states for three degrees of freedom. The ODE is integrated as it is (no projection
  inside the integrator); the attitude is read from q / |q| (renormalised on output), and
  the drift of |q| from 1 is reported.

The closed form (:func:`axisymmetric_top`) of a body with two equal moments, A about the
transverse axes and C about the symmetry axis e_s: with L the (constant) world angular
momentum and lambda = (A - C) w_s / A, R(t) = exp(t [L] / A) R0 exp(t lambda [e_s]) and
w(t) = R(t)^T L / A + lambda e_s. Every run below is such a top, so every formulation is
judged against it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.events import Mode, Transition, simulate_hybrid
from youbot_dynamics.integrate.integrators import (IntegrationError, IntegratorStats,
                                                   StepBudgetError, integrate)
from youbot_dynamics.io.text_tables import markdown_table
from youbot_dynamics.model.lie import (exp_so3, log_so3, matrix_from_quaternion,
                                       quaternion_from_matrix)
from youbot_dynamics.model.rotations import (AXES, SWITCH_ANGLE, adaptive_angles,
                                             cardan_angle_rates, cardan_angles, cardan_matrix,
                                             euler_equations, quaternion_rate, switched_angles)

FORMULATIONS = ("cardan", "cardan_adaptive", "quaternion")
#: Step budget of one run: the fixed sequence near gimbal lock is stopped here.
MAX_STEPS = 50_000


def cardan_rhs(sequence: str, inertia: np.ndarray) -> Callable[[float, np.ndarray], np.ndarray]:
    """x' for x = (a1, a2, a3, w1, w2, w3): a' = B(a)^-1 w, Euler's equations."""
    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        w = x[3:]
        return np.concatenate((cardan_angle_rates(sequence, x[:3], w), euler_equations(inertia, w)))
    return rhs


def quaternion_rhs(inertia: np.ndarray) -> Callable[[float, np.ndarray], np.ndarray]:
    """x' for x = (qx, qy, qz, qw, w1, w2, w3)."""
    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        w = x[4:]
        return np.concatenate((quaternion_rate(x[:4], w), euler_equations(inertia, w)))
    return rhs


def symmetry_axis(inertia: np.ndarray) -> int:
    """Index of the symmetry axis of an axisymmetric body (the moment that differs)."""
    for s in range(3):
        others = [inertia[m] for m in range(3) if m != s]
        if math.isclose(others[0], others[1], rel_tol=1e-12):
            return s
    raise UserInputError(f"inertia {inertia.tolist()} has no two equal moments: the closed "
                         f"form needs an axisymmetric body")


def axisymmetric_top(inertia: np.ndarray, rotation0: np.ndarray, w0: np.ndarray,
                     t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closed form of the torque-free axisymmetric top: (R(t) (n, 3, 3), w(t) (n, 3))."""
    s = symmetry_axis(inertia)
    transverse = inertia[(s + 1) % 3]
    momentum = rotation0 @ (inertia * w0)
    spin = (transverse - inertia[s]) * w0[s] / transverse
    rotations = np.array([exp_so3(momentum * ti / transverse) @ rotation0
                          @ exp_so3(AXES[s] * spin * ti) for ti in t])
    rates = np.einsum("nji,j->ni", rotations, momentum) / transverse + spin * AXES[s]
    return rotations, rates


@dataclass(frozen=True)
class TopRun:
    """A study case: inertia diag (kg m^2), R0, w0 (rad/s, body), t_end (s), purpose."""

    name: str
    inertia: tuple[float, float, float]
    rotation0: np.ndarray
    w0: tuple[float, float, float]
    t_end: float
    purpose: str


#: The three runs. ``spin``: symmetric about x, spinning about x (the first Cardan axis)
#: with a small wobble. ``tumble``: symmetric about z but turning end over end about body
#: y from R0 = Rot(z, 1e-4), so the body z axis passes within 1e-4 rad of world x and the
#: x-y-z middle angle within 1e-4 rad of pi/2 twice a turn (a1 and a3 swing by pi there
#: at rates near 2e4 rad/s). ``top``: a nutating top (symmetric about z, tilted 0.3 rad)
#: that stays clear of gimbal lock, so all three formulations can be held to the closed
#: form.
RUNS = {
    "spin": TopRun("spin", (2.0, 1.0, 1.0), np.eye(3), (10.0, 0.2, 0.0), 10.0,
                   "spin mostly about one axis: does Cardan take larger steps?"),
    "tumble": TopRun("tumble", (1.0, 1.0, 0.5), exp_so3(np.array([0.0, 0.0, 1e-4])),
                     (0.0, 2.0, 0.01), 10.0,
                     "tumbling through gimbal lock of the x-y-z sequence"),
    "top": TopRun("top", (1.0, 1.0, 2.0), exp_so3(np.array([0.3, 0.0, 0.0])),
                  (0.5, 0.3, 3.0), 10.0, "nutating top against its closed form"),
}


@dataclass
class RotationResult:
    """One formulation on one run: the attitudes and rates at the output times, the
    statistics, and what failed (``failure``: the error message, outputs up to it)."""

    run: str
    formulation: str
    t: np.ndarray
    rotations: np.ndarray
    rates: np.ndarray
    stats: IntegratorStats
    middle_angle: np.ndarray | None = None
    quaternion_norm: np.ndarray | None = None
    switches: int = 0
    failure: str | None = None
    failure_time: float | None = None
    errors: dict = field(default_factory=dict)

    def summary(self) -> dict:
        """The figures of the study table as plain data."""
        drift = (None if self.quaternion_norm is None
                 else float(np.max(np.abs(self.quaternion_norm - 1.0))))
        return {"run": self.run, "formulation": self.formulation,
                "steps": self.stats.steps, "rhs_evals": self.stats.rhs_evals,
                "switches": self.switches,
                "t_reached": float(self.t[-1]) if self.failure is None else self.failure_time,
                "attitude_error": self.errors.get("attitude"),
                "rate_error": self.errors.get("rate"), "norm_drift": drift,
                "wall_time": self.stats.wall_time, "failure": self.failure}


def simulate_cardan(inertia: np.ndarray, rotation0: np.ndarray, w0: np.ndarray,
                    t_eval: np.ndarray, integrator: str, options: dict) -> RotationResult:
    """The fixed x-y-z sequence."""
    x0 = np.concatenate((cardan_angles("xyz", rotation0), w0))
    solution = integrate(cardan_rhs("xyz", inertia), x0, t_eval, integrator, **options)
    rotations = np.array([cardan_matrix("xyz", x[:3]) for x in solution.x])
    return RotationResult("", "cardan", solution.t, rotations, solution.x[:, 3:],
                          solution.stats, middle_angle=solution.x[:, 1])


def sequence_switch(target: str) -> Callable[[float, np.ndarray], tuple[str, np.ndarray]]:
    """Reset map: the same attitude in the ``target`` sequence, rates unchanged."""
    def reset(t: float, x: np.ndarray) -> tuple[str, np.ndarray]:
        return target, np.concatenate((switched_angles(target, x[:3]), x[3:]))
    return reset


def simulate_cardan_adaptive(inertia: np.ndarray, rotation0: np.ndarray, w0: np.ndarray,
                             t_eval: np.ndarray, integrator: str,
                             options: dict) -> RotationResult:
    """Cardan angles switching x-y-z <-> x-z-y when |a2| > SWITCH_ANGLE."""
    def guard(t: float, x: np.ndarray) -> float:
        return abs(x[1]) - SWITCH_ANGLE

    modes = [Mode(name, cardan_rhs(name, inertia),
                  (Transition("switch", guard, sequence_switch(other), 1),))
             for name, other in (("xyz", "xzy"), ("xzy", "xyz"))]
    sequence, angles = adaptive_angles(rotation0)
    solution = simulate_hybrid(modes, sequence, np.concatenate((angles, w0)), t_eval, integrator,
                               **options)
    rotations = np.array([cardan_matrix(mode, x[:3])
                          for mode, x in zip(solution.mode, solution.x)])
    return RotationResult("", "cardan_adaptive", solution.t, rotations, solution.x[:, 3:],
                          solution.stats, middle_angle=solution.x[:, 1],
                          switches=len(solution.switches))


def simulate_quaternion(inertia: np.ndarray, rotation0: np.ndarray, w0: np.ndarray,
                        t_eval: np.ndarray, integrator: str, options: dict) -> RotationResult:
    """Quaternion (x, y, z, w) integrated unprojected, renormalised on output."""
    x0 = np.concatenate((quaternion_from_matrix(rotation0), w0))
    solution = integrate(quaternion_rhs(inertia), x0, t_eval, integrator, **options)
    return RotationResult("", "quaternion", solution.t,
                          matrix_from_quaternion(solution.x[:, :4]), solution.x[:, 4:],
                          solution.stats,
                          quaternion_norm=np.linalg.norm(solution.x[:, :4], axis=1))


SIMULATORS = {"cardan": simulate_cardan, "cardan_adaptive": simulate_cardan_adaptive,
              "quaternion": simulate_quaternion}


def attitude_error(rotations: np.ndarray, references: np.ndarray) -> np.ndarray:
    """|log(R_ref^T R)| (rad) per sample: the angle between computed and true attitude."""
    return np.array([np.linalg.norm(log_so3(ref.T @ r)) for r, ref in zip(rotations, references)])


def simulate_rotation(run: TopRun, formulation: str, *, integrator: str = "rk45",
                      tol: float = 1e-8, n_out: int = 401,
                      max_steps: int = MAX_STEPS) -> RotationResult:
    """Simulate one run with one formulation at rtol = atol = tol, and measure it against
    the closed form. A failed run (IntegrationError, e.g. the step budget spent crawling
    through gimbal lock) is returned with ``failure`` set and no outputs past t = 0."""
    if formulation not in SIMULATORS:
        raise UserInputError(f"unknown orientation formulation {formulation!r}; valid: "
                             + ", ".join(FORMULATIONS))
    inertia, w0 = np.array(run.inertia, dtype=float), np.array(run.w0, dtype=float)
    t_eval = np.linspace(0.0, run.t_end, n_out)
    options = {"rtol": tol, "atol": tol, "max_steps": max_steps}
    try:
        result = SIMULATORS[formulation](inertia, run.rotation0, w0, t_eval, integrator,
                                         options)
    except IntegrationError as error:
        stats = IntegratorStats(integrator)
        stats.steps = error.budget if isinstance(error, StepBudgetError) else None
        stats.rhs_evals = None
        result = RotationResult(run.name, formulation, t_eval[:1], run.rotation0[None],
                                w0[None], stats, failure=str(error),
                                failure_time=getattr(error, "time", None))
    result.run = run.name
    references, reference_rates = axisymmetric_top(inertia, run.rotation0, w0, result.t)
    result.errors = {"attitude": float(np.max(attitude_error(result.rotations, references))),
                     "rate": float(np.max(np.abs(result.rates - reference_rates)))}
    return result


def rotations_study(integrator: str = "rk45", tol: float = 1e-8, n_out: int = 401,
                    runs: tuple[str, ...] = tuple(RUNS)) -> list[RotationResult]:
    """Every formulation on every named run."""
    return [simulate_rotation(RUNS[name], formulation, integrator=integrator, tol=tol,
                              n_out=n_out)
            for name in runs for formulation in FORMULATIONS]


#: Wobbles (rad/s, about body y) of the spin sweep: the spin run with ever less wobble.
SPIN_WOBBLES = (0.0, 1e-3, 1e-2, 0.2, 1.0)


def spin_wobble_sweep(integrator: str = "rk45", tol: float = 1e-8,
                      wobbles: tuple[float, ...] = SPIN_WOBBLES) -> list[dict]:
    """Document 000's claim that Cardan angles take larger steps when the body turns mostly
    about one axis, measured: the ``spin`` run with each wobble, fixed Cardan against the
    quaternion (steps, evaluations, attitude error)."""
    spin = RUNS["spin"]
    rows = []
    for wobble in wobbles:
        run = TopRun("spin", spin.inertia, spin.rotation0, (spin.w0[0], wobble, 0.0),
                     spin.t_end, spin.purpose)
        row = {"wobble": wobble}
        for formulation in ("cardan", "quaternion"):
            result = simulate_rotation(run, formulation, integrator=integrator, tol=tol)
            row[f"{formulation}_steps"] = result.stats.steps
            row[f"{formulation}_rhs_evals"] = result.stats.rhs_evals
            row[f"{formulation}_error"] = result.errors["attitude"]
        rows.append(row)
    return rows


@dataclass(frozen=True)
class RotationsConfig:
    """The study's settings: the runs (names of RUNS), the integrator and its tolerance
    (rtol = atol)."""

    runs: tuple[str, ...] = tuple(RUNS)
    integrator: str = "rk45"
    tol: float = 1e-8


@dataclass
class RotationsStudy:
    """Every formulation on every run, and the spin run's wobble sweep (empty when the
    spin run is not among the runs)."""

    config: RotationsConfig
    results: list[RotationResult]
    sweep: list[dict]

    @property
    def rows(self) -> list[dict]:
        """One summary per (run, formulation)."""
        return [result.summary() for result in self.results]


def run(config: RotationsConfig) -> RotationsStudy:
    """Run the study."""
    results = rotations_study(config.integrator, config.tol, runs=config.runs)
    sweep = spin_wobble_sweep(config.integrator, config.tol) if "spin" in config.runs else []
    return RotationsStudy(config, results, sweep)


def as_json(study: RotationsStudy) -> dict:
    """Integrator, tolerance, the rows and the wobble sweep."""
    return {"integrator": study.config.integrator, "tol": study.config.tol, "rows": study.rows,
            "spin_wobble_sweep": study.sweep}


#: Columns of the study's table.
ROTATION_COLUMNS = ("run", "formulation", "steps", "rhs_evals", "switches", "t_reached",
                    "attitude_error", "rate_error", "norm_drift", "wall_time")


def text(study: RotationsStudy) -> str:
    """The study's table, the runs' purposes and the sweep as text (Markdown tables)."""
    config, rows, sweep = study.config, study.rows, study.sweep
    lines = [f"Rotations study, {config.integrator} at rtol = atol = {config.tol:g}; errors are "
             f"maxima over the outputs against the closed-form axisymmetric top (attitude: "
             f"|log(R_true^T R)|, rad; rate: |w - w_true|, rad/s). cardan_adaptive switches "
             f"x-y-z <-> x-z-y at |a2| = {SWITCH_ANGLE} rad; the quaternion is integrated "
             f"unprojected and renormalised on output (norm_drift = max ||q| - 1|).\n"]
    lines += [f"{name}: {RUNS[name].purpose}" for name in dict.fromkeys(row["run"] for row in rows)]
    lines += ["", markdown_table(ROTATION_COLUMNS, ([row[c] for c in ROTATION_COLUMNS]
                                                    for row in rows), digits=3)]
    if sweep:
        lines += [f"\nspin with less and less wobble (w0 = ({RUNS['spin'].w0[0]:g}, wobble, 0) "
                  f"rad/s): fixed Cardan against the quaternion\n",
                  markdown_table(tuple(sweep[0]), ([row[c] for c in sweep[0]] for row in sweep),
                                 digits=3)]
    lines += [f"{row['run']} / {row['formulation']} failed: {row['failure']}"
              for row in rows if row["failure"]]
    return "\n".join(lines)
