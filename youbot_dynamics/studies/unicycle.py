"""The differential drive (unicycle), document 002's mobile-robot system, as equations.

Two driven wheels of radius r on one axle, a distance 2 d apart; a body of mass m and yaw
inertia I_z about the axle's midpoint, which is also its centre of mass. The wheels roll
without slipping sideways or along (the non-holonomic constraint y' cos theta = x' sin
theta); their own inertia is lumped into m and I_z. Linear friction b (N s/m) resists the
forward speed, angular friction beta (N m s/rad) the yaw rate.

State (STATE_NAMES) x = (x, y, theta, v, omega): the axle midpoint in the world (m), the
heading (rad, from the world x axis), the forward speed (m/s) and the yaw rate (rad/s).
Inputs: the wheel torques tau_r, tau_l (N m, right and left; positive drives forward).

    x' = v cos theta        y' = v sin theta        theta' = omega
    m v' = F - b v,              F = (tau_r + tau_l) / r
    I_z omega' = M - beta omega, M = d (tau_r - tau_l) / r

F and M are the torques' virtual power: the wheels turn at u_r = (v + d omega) / r and
u_l = (v - d omega) / r, and tau_r u_r + tau_l u_l = F v + M omega.

Closed forms for constant torques (:func:`unicycle_closed_form`, :func:`heading_and_speeds`): v(t) = F/b + (v0 - F/b)
exp(-b t / m), so from rest v(t) = (F/b)(1 - exp(-b t / m)); likewise omega(t) with M, beta
and I_z. Equal torques from rest with omega0 = 0 drive a straight line along theta0; opposite
torques from rest (F = 0, v0 = 0) spin the robot in place: x and y stay constant.

Parameters (:class:`Unicycle`): the defaults are document 002's ``UnicycleDynamics``: m = 10 kg,
I_z = 0.5 kg m^2, r = 0.05 m, wheel base L = 0.3 m (d = L / 2 = 0.15 m), b = 1 N s/m
(``friction_linear``), beta = 0.5 N m s/rad (``friction_angular``). Its equations are these
with M = (tau_r - tau_l) L / (2 r). Other parameters (the tests' second run, b = 5 N s/m)
are given explicitly.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Callable

import numpy as np

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import Solution, integrate
from youbot_dynamics.model import limits

STATE_NAMES = ("x", "y", "theta", "v", "omega")

Torques = Callable[[float], tuple[float, float]]
#: Longest simulated time (s, 2.8 h): dop853 takes about 800 steps per 1e4 s at rtol 1e-10.
MAX_DURATION = limits.DURATION.maximum
#: Shortest time constant m / b or I_z / beta (s): below it the model is stiff beyond use.
MIN_TIME_CONSTANT = 1e-6
_BOUNDS = {"mass": limits.MASS, "yaw_inertia": limits.INERTIA, "wheel_radius": limits.LENGTH,
           "half_track": limits.LENGTH, "linear_friction": limits.DAMPING, "angular_friction": limits.DAMPING}


@dataclass(frozen=True)
class Unicycle:
    """Parameters (SI): mass m (kg), yaw_inertia I_z (kg m^2), wheel_radius r (m),
    half_track d (m, half the distance between the wheels), linear_friction b (N s/m),
    angular_friction beta (N m s/rad). All positive."""

    mass: float = 10.0
    yaw_inertia: float = 0.5
    wheel_radius: float = 0.05
    half_track: float = 0.15
    linear_friction: float = 1.0
    angular_friction: float = 0.5

    def __post_init__(self) -> None:
        for name, value in asdict(self).items():
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0.0):
                raise UserInputError(f"unicycle: {name} must be a positive finite number, got {value!r}")
            problem = _BOUNDS[name].problem(value)
            if problem:
                raise UserInputError(f"unicycle: {name}: {problem}")
        for what, constant in (("m / b", self.mass / self.linear_friction),
                               ("I_z / beta", self.yaw_inertia / self.angular_friction)):
            if not constant >= MIN_TIME_CONSTANT:
                raise UserInputError(f"unicycle: the time constant {what} = {constant:.3g} s is below "
                                     f"{MIN_TIME_CONSTANT:g} s: raise the mass or inertia, or lower the friction")

    def force_and_moment(self, tau_right: float, tau_left: float) -> tuple[float, float]:
        """(F (N), M (N m)) of the wheel torques (N m): F = (tau_r + tau_l) / r,
        M = d (tau_r - tau_l) / r."""
        return ((tau_right + tau_left) / self.wheel_radius,
                self.half_track * (tau_right - tau_left) / self.wheel_radius)

    def wheel_speeds(self, v: float, omega: float) -> tuple[float, float]:
        """(u_r, u_l) (rad/s) of the rolling wheels at forward speed v (m/s), yaw rate omega
        (rad/s): ((v + d omega) / r, (v - d omega) / r)."""
        return ((v + self.half_track * omega) / self.wheel_radius,
                (v - self.half_track * omega) / self.wheel_radius)


def unicycle_rhs(t: float, state: np.ndarray, model: Unicycle, torques: Torques) -> np.ndarray:
    """d/dt (x, y, theta, v, omega) with the wheel torques ``torques(t)`` = (tau_r, tau_l)."""
    _, _, theta, v, omega = state
    force, moment = model.force_and_moment(*torques(t))
    return np.array([v * math.cos(theta), v * math.sin(theta), omega,
                     (force - model.linear_friction * v) / model.mass,
                     (moment - model.angular_friction * omega) / model.yaw_inertia])


def _first_order(rate0: float, drive: float, friction: float, inertia: float, t: float) -> tuple[float, float]:
    """(w(t), integral of w over [0, t]) of inertia w' = drive - friction w from w(0) = rate0."""
    settled = drive / friction
    decay = inertia / friction
    fading = -math.expm1(-t / decay)  # 1 - exp(-t / decay), without cancellation for small t
    return settled + (rate0 - settled) * (1.0 - fading), settled * t + (rate0 - settled) * decay * fading


def heading_and_speeds(model: Unicycle, tau_right: float, tau_left: float, state0: np.ndarray,
                       t: float) -> tuple[np.ndarray, float]:
    """(theta, v, omega) at t (s) under constant torques (N m) from ``state0``, in closed form
    for any torques, and the distance travelled along the path (m)."""
    _, _, theta0, v0, omega0 = np.asarray(state0, dtype=float)
    force, moment = model.force_and_moment(tau_right, tau_left)
    v, travelled = _first_order(v0, force, model.linear_friction, model.mass, t)
    omega, turned = _first_order(omega0, moment, model.angular_friction, model.yaw_inertia, t)
    return np.array([theta0 + turned, v, omega]), travelled


def unicycle_closed_form(model: Unicycle, tau_right: float, tau_left: float, state0: np.ndarray,
                         t: float) -> np.ndarray:
    """The state at t (s) under constant torques (N m) from ``state0``, in closed form (module
    docstring): x and y need a straight line (tau_r = tau_l and omega0 = 0) or a spin in place
    (tau_r = -tau_l and v0 = 0); :func:`heading_and_speeds` holds for any torques."""
    x0, y0, theta0, v0, omega0 = np.asarray(state0, dtype=float)
    force, moment = model.force_and_moment(tau_right, tau_left)
    rest, travelled = heading_and_speeds(model, tau_right, tau_left, state0, t)
    if moment == 0.0 and omega0 == 0.0:
        x, y = x0 + math.cos(theta0) * travelled, y0 + math.sin(theta0) * travelled
    elif force == 0.0 and v0 == 0.0:
        x, y = x0, y0
    else:
        raise UserInputError("unicycle: no closed form for x and y when the robot both drives and turns "
                             f"(F = {force:g} N, M = {moment:g} N m, v0 = {v0:g}, omega0 = {omega0:g})")
    return np.array([x, y, *rest])


def simulate_unicycle(model: Unicycle, tau_right: float, tau_left: float, t_end: float, integrator: str, *,
                      state0: np.ndarray = (0.0, 0.0, 0.0, 0.0, 0.0), rtol: float = 1e-6,
                      atol: float | np.ndarray = 1e-8, dt: float | None = None, n_out: int = 101) -> Solution:
    """Integrate from ``state0`` over [0, t_end] (s) under constant wheel torques (N m), with
    outputs at n_out equally spaced times."""
    if not (math.isfinite(t_end) and 0.0 < t_end <= MAX_DURATION):
        raise UserInputError(f"unicycle: t_end must be a time in (0, {MAX_DURATION:g}] s, got {t_end!r}")
    if not (math.isfinite(tau_right) and math.isfinite(tau_left)):
        raise UserInputError(f"unicycle: wheel torques must be finite (N m), got {tau_right!r}, {tau_left!r}")
    force, moment = model.force_and_moment(tau_right, tau_left)
    problem = (limits.SPEED.problem(force / model.linear_friction)
               or limits.ANGULAR_SPEED.problem(moment / model.angular_friction))
    if problem:
        raise UserInputError(f"unicycle: the wheel torques {tau_right:g}, {tau_left:g} N m would settle "
                             f"where {problem}")
    state = np.asarray(state0, dtype=float).ravel()
    if state.shape != (5,):
        raise UserInputError(f"unicycle: state0 must be x, y, theta, v, omega (5 numbers), got {state.size}")
    return integrate(lambda t, x: unicycle_rhs(t, x, model, lambda _: (tau_right, tau_left)), state,
                     np.linspace(0.0, t_end, n_out), integrator, rtol=rtol, atol=atol, dt=dt,
                     state_names=STATE_NAMES)


#: dop853 at rtol 1e-10, atol 1e-12 meets the closed forms to about 1e-10 on the defaults.
DEFAULT_INTEGRATOR, DEFAULT_RTOL, DEFAULT_ATOL = "dop853", 1e-10, 1e-12
#: Output times of a run, equally spaced over [0, duration].
OUTPUTS = 101


@dataclass(frozen=True)
class UnicycleConfig:
    """One run from rest: the model, the wheel torques (N m), the simulated ``duration``
    (s), the integrator, its tolerances (a number or one per state component) and a fixed
    step ``dt`` (s)."""

    model: Unicycle = Unicycle()
    tau_right: float = 0.5
    tau_left: float = 0.5
    duration: float = 10.0
    integrator: str = DEFAULT_INTEGRATOR
    rtol: float = DEFAULT_RTOL
    atol: object = DEFAULT_ATOL
    dt: float | None = None


@dataclass
class UnicycleRun:
    """The run, the closed form it is compared with at the outputs (x, y, theta, v, omega
    where they exist; theta, v, omega only for general torques), and the largest gap."""

    config: UnicycleConfig
    solution: Solution
    case: str
    compared: slice
    reference: np.ndarray
    max_error: float

    @property
    def final_state(self) -> dict[str, float]:
        """The simulated state at the end (m, rad, m/s, rad/s)."""
        return dict(zip(STATE_NAMES, map(float, self.solution.x[-1])))

    @property
    def closed_form(self) -> dict[str, float]:
        """The closed form's compared components at the end."""
        return dict(zip(STATE_NAMES[self.compared], map(float, self.reference[-1, self.compared])))


def run(config: UnicycleConfig) -> UnicycleRun:
    """Simulate from rest and compare with the closed form where one exists (IntegrationError
    if the integrator fails)."""
    model, tau_right, tau_left = config.model, config.tau_right, config.tau_left
    state0 = np.zeros(5)
    solution = simulate_unicycle(model, tau_right, tau_left, config.duration, config.integrator,
                                 rtol=config.rtol, atol=config.atol, dt=config.dt, n_out=OUTPUTS)
    straight, spin = tau_right == tau_left, tau_right == -tau_left
    if straight or spin:
        compared = slice(0, 5)
        reference = np.array([unicycle_closed_form(model, tau_right, tau_left, state0, t)
                              for t in solution.t])
    else:  # x, y have no closed form: compare theta, v, omega
        compared = slice(2, 5)
        reference = np.array([[0.0, 0.0, *heading_and_speeds(model, tau_right, tau_left, state0, t)[0]]
                              for t in solution.t])
    error = float(np.abs(solution.x[:, compared] - reference[:, compared]).max())
    case = "equal torques: straight line" if straight else "opposite torques: spin in place" if spin else \
        "general torques: closed forms of theta, v, omega only"
    return UnicycleRun(config, solution, case, compared, reference, error)


def as_json(result: UnicycleRun) -> dict:
    """Parameters, torques, the case, the final state beside the closed form, the largest
    gap and the statistics."""
    config = result.config
    return {"parameters": asdict(config.model), "tau_right": config.tau_right,
            "tau_left": config.tau_left, "case": result.case, "t_end": float(result.solution.t[-1]),
            "final_state": result.final_state, "closed_form": result.closed_form,
            "max_error": result.max_error, "stats": result.solution.stats.as_dict()}


def text(result: UnicycleRun) -> str:
    """The case, the parameters, the final state beside the closed form, the largest gap and
    the statistics."""
    config, solution, closed = result.config, result.solution, result.closed_form
    return "\n".join([
        f"unicycle, {result.case}; tau_r = {config.tau_right:g}, tau_l = {config.tau_left:g} N m; "
        f"{config.integrator}, t = {solution.t[-1]:g} s",
        "parameters: " + ", ".join(f"{k} = {v:g}" for k, v in asdict(config.model).items()),
        "final state:  " + ", ".join(f"{k}={v:.12g}" for k, v in result.final_state.items()),
        "closed form:  " + ", ".join(f"{k}={v:.12g}" for k, v in closed.items()),
        f"max |simulated - closed form| over {len(solution.t)} outputs ({', '.join(closed)}): "
        f"{result.max_error:.3e}",
        f"statistics: {solution.stats.summary()}"])
