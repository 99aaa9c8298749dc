"""Excitation trajectories: finite Fourier series per joint (Swevers et al. 1997, 2007).

Joint j follows, with fundamental pulsation w = 2 pi / period and L harmonics,

    q_j(t)   = q0_j + sum_l  a_jl / (w l) sin(w l t) - b_jl / (w l) cos(w l t)      (rad)
    qd_j(t)  = sum_l  a_jl cos(w l t) + b_jl sin(w l t)                             (rad/s)
    qdd_j(t) = sum_l -a_jl w l sin(w l t) + b_jl w l cos(w l t)                     (rad/s^2)

periodic, so a measurement can be averaged over periods and needs no windowing. The
coefficients are chosen by scipy.optimize (SLSQP) to minimise cond(Y_base) over one period
sampled at ``grid`` points, under the URDF's position limits (less ``margin``), a fraction
of its velocity limits, an acceleration limit (the URDF has none: an option) and a fraction
of its effort limits (the nominal robot's inverse dynamics with friction, Y theta), with
qd(0) = qdd(0) = 0 so the robot can start from rest at q(0). Between grid points the effort
is checked again on a dense grid and the series shrunk about q0 until it fits.

Written as /joint_trajectory points, a period fits one message: :func:`message_rate`
samples it at most as densely as the node takes (``MAX_TRAJECTORY_POINTS`` points).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import scipy.optimize
import yaml

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.identification.base_parameters import BaseParameters
from youbot_dynamics.identification.regressor import RegressorLayout
from youbot_dynamics.node.commands import MAX_TRAJECTORY_POINTS  # one /joint_trajectory's points

#: Hz: the sample rate of written points unless one message cannot hold them (:func:`message_rate`).
DEFAULT_RATE = 100.0
#: Points per period on which the effort limits are checked after the optimisation.
DENSE_GRID = 2000


def message_rate(duration: float, rate: float = DEFAULT_RATE) -> float:
    """The sample rate (Hz), at most ``rate``, at which the points of [0, duration] s (both
    ends) fit one /joint_trajectory: at most ``MAX_TRAJECTORY_POINTS``, the node's bound."""
    return min(rate, (MAX_TRAJECTORY_POINTS - 1) / duration)


@dataclass(frozen=True)
class FourierTrajectory:
    """A finite Fourier series per joint: ``q0`` (n,) rad, ``a`` and ``b`` (n, L) rad/s,
    ``period`` s, for ``joint_names`` (n)."""

    joint_names: tuple[str, ...]
    period: float
    q0: np.ndarray
    a: np.ndarray
    b: np.ndarray

    @property
    def pulsation(self) -> float:
        """Fundamental pulsation w = 2 pi / period (rad/s)."""
        return 2.0 * np.pi / self.period

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """q, qd, qdd (len(t), n) at times t (s)."""
        harmonics = np.arange(1, self.a.shape[1] + 1)
        wl = self.pulsation * harmonics                        # (L,)
        phase = np.outer(np.asarray(t, float), wl)             # (N, L)
        sin, cos = np.sin(phase), np.cos(phase)
        q = self.q0 + (sin / wl) @ self.a.T - (cos / wl) @ self.b.T
        v = cos @ self.a.T + sin @ self.b.T
        acc = -(sin * wl) @ self.a.T + (cos * wl) @ self.b.T
        return q, v, acc

    def point_count(self, rate: float, periods: int = 1) -> int:
        """How many points ``periods`` periods sampled at ``rate`` Hz hold (both ends)."""
        return int(round(periods * self.period * rate)) + 1

    def to_dict(self, rate: float | None = None, periods: int = 1) -> dict[str, Any]:
        """The series and its samples at ``rate`` Hz (default :func:`message_rate`) over
        ``periods`` periods, as trajectory_msgs/JointTrajectory fields (joint_names, points
        with positions, velocities, accelerations, time_from_start {sec, nanosec}) plus
        ``fourier``."""
        rate = message_rate(periods * self.period) if rate is None else rate
        steps = self.point_count(rate, periods) - 1
        t_ns = np.rint(np.arange(steps + 1) * 1e9 / rate).astype(np.int64)
        q, v, acc = self.evaluate(t_ns * 1e-9)
        points = [{"positions": q[k].tolist(), "velocities": v[k].tolist(), "accelerations": acc[k].tolist(),
                   "time_from_start": {"sec": int(t // 1_000_000_000), "nanosec": int(t % 1_000_000_000)}}
                  for k, t in enumerate(t_ns)]
        return {"joint_names": list(self.joint_names), "points": points,
                "fourier": {"period": self.period, "q0": self.q0.tolist(), "a": self.a.tolist(),
                            "b": self.b.tolist()}}

    def write(self, path: str | Path, rate: float | None = None, periods: int = 1) -> None:
        """Write :meth:`to_dict` as YAML."""
        Path(path).write_text(yaml.safe_dump(self.to_dict(rate, periods), sort_keys=False))

    @classmethod
    def read(cls, path: str | Path) -> FourierTrajectory:
        """The series of a file written by :meth:`write`; UserInputError naming the file."""
        try:
            document = yaml.safe_load(Path(path).read_text())
            fourier = document["fourier"]
            return cls(tuple(document["joint_names"]), float(fourier["period"]), np.array(fourier["q0"], float),
                       np.array(fourier["a"], float), np.array(fourier["b"], float))
        except (OSError, yaml.YAMLError, KeyError, TypeError, ValueError) as error:
            raise UserInputError(f"excitation file {path}: cannot be read as a Fourier trajectory "
                                 f"({type(error).__name__}: {error})") from None


@dataclass(frozen=True)
class ExcitationLimits:
    """Bounds an excitation must keep: position limits shrunk by ``margin`` (rad), speeds
    within ``velocity_fraction`` of the URDF's velocity limits, |qdd| <= ``acceleration``
    (rad/s^2; the URDF states none), the nominal robot's joint efforts within
    ``effort_fraction`` of the URDF's effort limits on the optimiser's grid (within the limits
    themselves on a dense one)."""

    margin: float = 0.1
    velocity_fraction: float = 0.8
    acceleration: float = 4.0
    effort_fraction: float = 0.95


@dataclass(frozen=True)
class ExcitationResult:
    """The optimised trajectory, the random start it came from, their condition numbers
    and the optimiser's report."""

    trajectory: FourierTrajectory
    initial: FourierTrajectory
    condition: float
    initial_condition: float
    iterations: int
    message: str


def _bounds(layout: RegressorLayout, limits: ExcitationLimits) -> tuple[np.ndarray, ...]:
    robot = layout.robot
    lower = np.where(np.isfinite(robot.lower), robot.lower, -np.pi) + limits.margin
    upper = np.where(np.isfinite(robot.upper), robot.upper, np.pi) - limits.margin
    if np.any(upper <= lower):
        raise UserInputError(f"excitation: position range of a joint is below twice the margin {limits.margin} rad")
    vmax = np.where(np.isfinite(robot.velocity_limit), robot.velocity_limit, 2.0) * limits.velocity_fraction
    return lower, upper, vmax, np.full(robot.nv, limits.acceleration)


def efforts(layout: RegressorLayout, q: np.ndarray, v: np.ndarray, acc: np.ndarray) -> np.ndarray:
    """(N, nv) joint efforts (N m) of the nominal robot (the layout's URDF, its friction
    included) along N samples of q, qd, qdd: Y(q, qd, qdd) theta."""
    return (layout.stacked(q, v, acc) @ layout.standard_parameters()).reshape(len(q), -1)


def effort_ratio(layout: RegressorLayout, trajectory: FourierTrajectory, grid: int = DENSE_GRID) -> np.ndarray:
    """(nv,) the largest |effort| / effort limit per joint over one period sampled at
    ``grid`` points (0 for a joint without a limit)."""
    q, v, acc = trajectory.evaluate(np.linspace(0.0, trajectory.period, grid, endpoint=False))
    return (np.abs(efforts(layout, q, v, acc)) / _effort_limits(layout)).max(axis=0)


def _effort_limits(layout: RegressorLayout) -> np.ndarray:
    limit = np.asarray(layout.robot.effort_limit, dtype=float)
    return np.where(np.isfinite(limit) & (limit > 0.0), limit, np.inf)


def within_efforts(layout: RegressorLayout, trajectory: FourierTrajectory, fraction: float = 1.0,
                   grid: int = DENSE_GRID) -> FourierTrajectory:
    """``trajectory`` with its Fourier coefficients shrunk about q0 (by factors of 0.95) until
    the nominal efforts stay within ``fraction`` of the effort limits on ``grid`` points per
    period (itself if they do); UserInputError when even a small motion about q0 exceeds them."""
    for _ in range(100):
        ratio = effort_ratio(layout, trajectory, grid)
        if ratio.max() <= fraction:
            return trajectory
        trajectory = FourierTrajectory(trajectory.joint_names, trajectory.period, trajectory.q0,
                                       0.95 * trajectory.a, 0.95 * trajectory.b)
    joint = layout.robot.joint_names[int(np.argmax(ratio))]
    raise UserInputError(f"excitation: {joint} needs {ratio.max():.3g} x its effort limit even near q0 "
                         f"(the static load at mid-range exceeds it)")


def random_fourier(layout: RegressorLayout, period: float, harmonics: int, limits: ExcitationLimits,
                   rng: np.random.Generator, grid: int = 200) -> FourierTrajectory:
    """A random series about mid-range that starts at rest and is scaled into the limits
    (positions, speeds and accelerations at once, then the efforts)."""
    lower, upper, vmax, amax = _bounds(layout, limits)
    n, harmonic = layout.robot.nv, np.arange(1, harmonics + 1)
    a, b = rng.standard_normal((n, harmonics)), rng.standard_normal((n, harmonics))
    a -= a.mean(axis=1, keepdims=True)                                   # qd(0) = sum a = 0
    b -= np.outer(b @ harmonic / (harmonic @ harmonic), harmonic)        # qdd(0) ~ sum l b = 0
    shape = FourierTrajectory(layout.robot.joint_names, period, np.zeros(n), a, b)
    q, v, acc = shape.evaluate(np.linspace(0.0, period, grid, endpoint=False))
    span = np.abs(q - q[0]).max(axis=0) + np.abs(q[0])                   # |q - q0| bound, q0 = 0
    scale = 0.9 * np.min([((upper - lower) / 2 / span).min(), (vmax / np.abs(v).max(axis=0)).min(),
                          (amax / np.abs(acc).max(axis=0)).min()])
    return within_efforts(layout, FourierTrajectory(shape.joint_names, period, (lower + upper) / 2,
                                                    scale * a, scale * b), limits.effort_fraction, grid)


def condition_number(layout: RegressorLayout, base: BaseParameters, trajectory: FourierTrajectory,
                     grid: int = 200) -> float:
    """cond(Y_base) over one period sampled at ``grid`` points (2-norm)."""
    q, v, acc = trajectory.evaluate(np.linspace(0.0, trajectory.period, grid, endpoint=False))
    return float(np.linalg.cond(base.columns(layout.stacked(q, v, acc))))


def optimise_excitation(layout: RegressorLayout, base: BaseParameters, *, period: float = 10.0,
                        harmonics: int = 5, limits: ExcitationLimits = ExcitationLimits(), grid: int = 60,
                        iterations: int = 60, seed: int = 0) -> ExcitationResult:
    """Minimise cond(Y_base) over the Fourier coefficients (SLSQP, finite-difference
    gradients) from a random feasible series; constraints on ``grid`` points per period. The
    result is the feasible iterate of least condition number (the last one shrunk about its
    q0 until feasible among them), its efforts checked again on ``DENSE_GRID``
    (:func:`within_efforts`)."""
    lower, upper, vmax, amax = _bounds(layout, limits)
    tau_max = limits.effort_fraction * _effort_limits(layout)
    limited = np.isfinite(tau_max)
    initial = random_fourier(layout, period, harmonics, limits, np.random.default_rng(seed))
    n, harmonic = layout.robot.nv, np.arange(1, harmonics + 1)
    times = np.linspace(0.0, period, grid, endpoint=False)
    w = initial.pulsation

    def unpack(x: np.ndarray) -> FourierTrajectory:
        a, b = x[n:].reshape(2, n, harmonics)
        return FourierTrajectory(initial.joint_names, period, x[:n], a, b)

    theta, cache = layout.standard_parameters(), {}

    def along(x: np.ndarray) -> tuple[np.ndarray, ...]:
        """q, qd, qdd on the grid and the stacked regressor there (the last x's, kept)."""
        key = x.tobytes()
        if key not in cache:
            q, v, acc = unpack(x).evaluate(times)
            cache.clear()
            cache[key] = q, v, acc, layout.stacked(q, v, acc)
        return cache[key]

    def objective(x: np.ndarray) -> float:
        return float(np.log(np.linalg.cond(base.columns(along(x)[3]))))

    def inequalities(x: np.ndarray) -> np.ndarray:
        q, v, acc, regressor = along(x)
        tau = np.abs(regressor @ theta).reshape(len(times), -1)
        return np.concatenate([(q - lower).ravel(), (upper - q).ravel(), (vmax - np.abs(v)).ravel(),
                               (amax - np.abs(acc)).ravel(), (tau_max[limited] - tau[:, limited]).ravel()])

    def at_rest(x: np.ndarray) -> np.ndarray:
        a, b = x[n:].reshape(2, n, harmonics)
        return np.concatenate([a.sum(axis=1), w * (b @ harmonic)])

    x0 = np.concatenate([initial.q0, initial.a.ravel(), initial.b.ravel()])
    kept = {"x": x0, "objective": objective(x0)}          # the random start is feasible

    def keep(x: np.ndarray) -> bool:
        """Remember the feasible iterate of least condition number (SLSQP's callback);
        whether ``x`` is feasible."""
        feasible = bool(np.all(inequalities(x) >= -1e-6) and np.all(np.abs(at_rest(x)) <= 1e-9))
        if feasible and objective(x) < kept["objective"]:
            kept.update(x=x.copy(), objective=objective(x))
        return feasible

    result = scipy.optimize.minimize(objective, x0, method="SLSQP",
                                     constraints=[{"type": "ineq", "fun": inequalities},
                                                  {"type": "eq", "fun": at_rest}],
                                     options={"maxiter": iterations}, callback=keep)
    for k in range(60):      # the last iterate, shrunk about its q0 until it is feasible
        if keep(np.concatenate([result.x[:n], 0.95 ** k * result.x[n:]])):
            break
    best = within_efforts(layout, unpack(kept["x"]))
    return ExcitationResult(best, initial, condition_number(layout, base, best),
                            condition_number(layout, base, initial), int(result.nit), str(result.message))


