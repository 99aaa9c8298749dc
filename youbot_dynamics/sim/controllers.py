"""Joint-torque controllers for the simulator: none, gravity-compensated PD, computed torque.

Every controller maps (t, q, v) and a :class:`Reference` to a joint torque (N m, or N for
prismatic joints) in the reduced Robot's joint order, clipped to the URDF effort limits
(the :class:`Controller` protocol). It tracks the desired (q_d, v_d, a_d) of the reference's
trajectory, or holds its set point when it has none. The reference is part of the
simulation's state (:class:`~youbot_dynamics.sim.state.SimState`), not of the controller:
a controller holds only its gains and scratch space. Controllers are memoryless (no integral
state), so they add no continuous state. The PD controller knows gravity only; computed torque knows the rigid-body model and feeds
the friction model forward along the desired motion (it cannot see the bristle states).

- ``NoController``: tau = 0 (a free fall).
- ``GravityCompensatedPD``: tau = g(q) + Kp (q_d - q) + Kd (v_d - v), gains in N m/rad and
  N m s/rad.
- ``ComputedTorque``: tau = M(q) (a_d + Kp e + Kd e') + C(q, v) v + g(q) (RNEA), e = q_d - q,
  plus the friction model's torque at the desired velocity, tau_f(v_d) (LuGre bristles at
  their steady state for v_d) as feedforward; gains in 1/s^2 and 1/s (each joint's error
  obeys e'' + Kd e' + Kp e = 0 when the model is exact and no limit is hit).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Callable, Protocol

import numpy as np
import pinocchio as pin
from numba import njit, types
from numba.extending import register_jitable

from youbot_dynamics.compiled import FLOAT, unchecked
from youbot_dynamics.dynamics.friction import (NO_BRISTLES, READ_VECTOR, WRITTEN_VECTOR, JointFriction,
                                               accumulate_friction_torque)
from youbot_dynamics.dynamics.mobile.ramp import TwistRamp
from youbot_dynamics.dynamics.rigid_body import gravity_torque, inverse_dynamics
from youbot_dynamics.model.robot import Robot
from youbot_dynamics.sim.trajectory import POINTS, TIMING, PointToPointTrajectory, desired_motion

#: A Python controller: (t s, q rad, v rad/s) of the robot's moving joints -> joint torques (N m).
ControllerCallback = Callable[[float, np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class Reference:
    """What the controllers track: a trajectory, or a constant set point ``hold`` (rad); a
    moving base's twist command ``base_twist`` (vx m/s, vy m/s, wz rad/s, body frame, reached
    within the base's a_max; None: the scene's base path); ``effort_limit`` (N m, N; one per
    joint) clips the controller's torque where it is below the URDF effort limit (a
    gripper's max_effort; None: the URDF's limits)."""

    hold: np.ndarray
    trajectory: PointToPointTrajectory | None = None
    base_twist: TwistRamp | None = None
    effort_limit: np.ndarray | None = None

    def limit(self, urdf_limit: np.ndarray) -> np.ndarray:
        """The effort limit (N m, N) a controller clips to: the URDF's, lowered by
        ``effort_limit`` where given."""
        return urdf_limit if self.effort_limit is None else np.minimum(urdf_limit, self.effort_limit)

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Desired position, velocity and acceleration at t (s)."""
        if self.trajectory is None:
            zero = np.zeros_like(self.hold)
            return self.hold, zero, zero
        return self.trajectory.evaluate(t)

    @functools.cached_property
    def compiled(self) -> tuple[np.ndarray, np.ndarray] | None:
        """(points, timing) as :func:`~youbot_dynamics.sim.trajectory.desired_motion` reads
        them: a point-to-point trajectory's (``PointToPointTrajectory.compiled``), or the hold
        as the only point of a motion without segments; None for another trajectory (its
        ``evaluate`` runs in Python)."""
        if self.trajectory is None:  # the hold itself where it is float64 (as ``at`` returns it)
            timing = np.zeros((0, 5))
            timing.setflags(write=False)
            return np.ascontiguousarray(self.hold, dtype=float).reshape(1, -1), timing
        if isinstance(self.trajectory, PointToPointTrajectory):
            return self.trajectory.compiled
        return None


class Controller(Protocol):
    """What the simulator needs of a controller: its ``kind`` and the torque law."""

    kind: str

    def torque(self, t: float, q: np.ndarray, v: np.ndarray, reference: Reference) -> np.ndarray:
        """Joint torques (N m, N) at time t (s), positions q and velocities v, tracking
        ``reference``."""


class NoController:
    """Zero torque."""

    kind = "none"

    def __init__(self, robot: Robot) -> None:
        self.zero = np.zeros(robot.nv)

    def torque(self, t: float, q: np.ndarray, v: np.ndarray, reference: Reference) -> np.ndarray:
        return self.zero


class GravityCompensatedPD:
    """tau = g(q) + Kp (q_d - q) + Kd (v_d - v), clipped to the effort limits."""

    kind = "pd"

    def __init__(self, robot: Robot, kp: np.ndarray, kd: np.ndarray) -> None:
        self.robot, self.data = robot, robot.model.createData()
        self.kp, self.kd = (np.array(np.broadcast_to(k, robot.nv), dtype=float) for k in (kp, kd))
        self.limit = np.asarray(robot.effort_limit)

    def torque(self, t: float, q: np.ndarray, v: np.ndarray, reference: Reference) -> np.ndarray:
        gravity = gravity_torque(self.robot, self.data, q)
        effort = self.limit if reference.effort_limit is None else reference.effort_limit
        compiled = reference.compiled
        if compiled is not None and _float_vector(q) and _float_vector(v) and _float_vector(effort):
            # float64 q, v and limits and the trajectory's arrays: the law in one compiled call
            n = self.kp.shape[0]
            tau, motion = np.empty(n), np.empty((3, n))
            _pd_torque_unchecked(compiled[0], compiled[1], float(t), q, v, gravity, self.kp, self.kd, self.limit,
                                 effort, motion, tau)
            return tau
        q_d, v_d, _ = reference.at(t)
        limit = reference.limit(self.limit)
        return np.clip(gravity + self.kp * (q_d - q) + self.kd * (v_d - v), -limit, limit)


@register_jitable
def commanded_acceleration(q: np.ndarray, v: np.ndarray, q_d: np.ndarray, v_d: np.ndarray, a_d: np.ndarray,
                           kp: np.ndarray, kd: np.ndarray, out: np.ndarray) -> None:
    """out = a_d + Kp (q_d - q) + Kd (v_d - v), joint by joint (numpy's operation order);
    sizes checked (ValueError) before anything is written."""
    n = out.shape[0]
    if not (q.shape[0] == v.shape[0] == q_d.shape[0] == v_d.shape[0] == a_d.shape[0] == kp.shape[0] == kd.shape[0] == n):
        raise ValueError("computed torque: q, v, the reference and the gains need one value per joint")
    for i in range(n):
        out[i] = a_d[i] + kp[i] * (q_d[i] - q[i]) + kd[i] * (v_d[i] - v[i])


@register_jitable
def clip_to_limits(limit: np.ndarray, tau: np.ndarray) -> None:
    """tau = clip(tau, -limit, limit) in place (a NaN stays NaN, as with np.clip)."""
    if limit.shape[0] != tau.shape[0]:
        raise ValueError("computed torque: one effort limit per joint")
    for i in range(tau.shape[0]):
        if tau[i] < -limit[i]:
            tau[i] = -limit[i]
        if tau[i] > limit[i]:
            tau[i] = limit[i]


@register_jitable
def clip_to_lower_limits(urdf_limit: np.ndarray, effort_limit: np.ndarray, tau: np.ndarray) -> None:
    """tau = clip(tau, -limit, limit) in place with limit = np.minimum(urdf_limit, effort_limit)
    (N m, N; a NaN in either passes through as numpy's minimum passes it)."""
    n = tau.shape[0]
    if urdf_limit.shape[0] != n or effort_limit.shape[0] != n:
        raise ValueError("controller: one effort limit per joint")
    limit = np.empty(n)
    for i in range(n):
        urdf, effort = urdf_limit[i], effort_limit[i]
        limit[i] = urdf if urdf != urdf else effort if effort != effort else urdf if urdf <= effort else effort
    clip_to_limits(limit, tau)


@njit(types.void(*(READ_VECTOR,) * 7, WRITTEN_VECTOR), cache=True)
def _commanded_acceleration(q: np.ndarray, v: np.ndarray, q_d: np.ndarray, v_d: np.ndarray, a_d: np.ndarray,
                            kp: np.ndarray, kd: np.ndarray, out: np.ndarray) -> None:
    """out = a_d + Kp (q_d - q) + Kd (v_d - v) (see :func:`commanded_acceleration`)."""
    commanded_acceleration(q, v, q_d, v_d, a_d, kp, kd, out)


@njit(types.void(POINTS, TIMING, types.float64, *(READ_VECTOR,) * 4, types.Array(types.float64, 2, "C"),
                 WRITTEN_VECTOR), cache=True)
def _tracking_acceleration(points: np.ndarray, timing: np.ndarray, t: float, q: np.ndarray, v: np.ndarray,
                           kp: np.ndarray, kd: np.ndarray, motion: np.ndarray, out: np.ndarray) -> None:
    """motion = (q_d, v_d, a_d) of the trajectory at t (s) (:func:`~youbot_dynamics.sim
    .trajectory.desired_motion`, (3, n)) and out = a_d + Kp (q_d - q) + Kd (v_d - v)
    (:func:`commanded_acceleration`): what :meth:`ComputedTorque.torque` feeds the RNEA,
    in one call."""
    desired_motion(points, timing, t, motion)
    commanded_acceleration(q, v, motion[0], motion[1], motion[2], kp, kd, out)


@njit(types.void(READ_VECTOR, READ_VECTOR, types.Array(types.float64, 2, "A", readonly=True), types.boolean,
                 READ_VECTOR, READ_VECTOR, WRITTEN_VECTOR), cache=True)
def _feedforward_and_clip(v_d: np.ndarray, bristles: np.ndarray, table: np.ndarray, with_friction: bool,
                          urdf_limit: np.ndarray, effort_limit: np.ndarray, tau: np.ndarray) -> None:
    """tau += tau_friction(v_d, bristles) (with ``with_friction``; the friction ``table``),
    then tau = clip(tau, -limit, limit) with limit = np.minimum(urdf_limit, effort_limit)
    (N m, N; a NaN in either passes through as numpy's minimum passes it), in place."""
    if with_friction:
        accumulate_friction_torque(v_d, bristles, table, 1.0, tau)
    clip_to_lower_limits(urdf_limit, effort_limit, tau)


@njit(types.void(POINTS, TIMING, types.float64, *(READ_VECTOR,) * 7, types.Array(types.float64, 2, "C"),
                 WRITTEN_VECTOR), cache=True)
def _pd_torque(points: np.ndarray, timing: np.ndarray, t: float, q: np.ndarray, v: np.ndarray, gravity: np.ndarray,
               kp: np.ndarray, kd: np.ndarray, urdf_limit: np.ndarray, effort_limit: np.ndarray, motion: np.ndarray,
               tau: np.ndarray) -> None:
    """:meth:`GravityCompensatedPD.torque` in one call: motion = (q_d, v_d, a_d) of the
    trajectory at t (s), tau = g + Kp (q_d - q) + Kd (v_d - v) (:func:`commanded_acceleration`
    with g in place of a_d: numpy's operations in its order), clipped to
    np.minimum(urdf_limit, effort_limit) (N m, N)."""
    desired_motion(points, timing, t, motion)
    commanded_acceleration(q, v, motion[0], motion[1], gravity, kp, kd, tau)
    clip_to_lower_limits(urdf_limit, effort_limit, tau)


_commanded_acceleration_unchecked = unchecked(_commanded_acceleration)
_tracking_acceleration_unchecked = unchecked(_tracking_acceleration)
_feedforward_and_clip_unchecked = unchecked(_feedforward_and_clip)
_pd_torque_unchecked = unchecked(_pd_torque)


class ComputedTorque:
    """tau = RNEA(q, v, a_d + Kp e + Kd e'), clipped to the effort limits.

    For float64 q and v (the simulator's) the arithmetic around the RNEA runs compiled (the
    same operations in the same order as numpy's), about 6 us less per call. The integrators'
    rhs of a robot alone does not call it: it runs the same law fused with the robot's
    derivative (:meth:`~youbot_dynamics.sim.model.SimModel.computed_torque_derivative`)."""

    kind = "computed_torque"

    def __init__(self, robot: Robot, kp: np.ndarray, kd: np.ndarray, friction: JointFriction | None) -> None:
        self.robot, self.data = robot, robot.model.createData()
        self.kp, self.kd = (np.array(np.broadcast_to(k, robot.nv), dtype=float) for k in (kp, kd))
        self.friction = friction
        self.limit = np.asarray(robot.effort_limit)

    def torque(self, t: float, q: np.ndarray, v: np.ndarray, reference: Reference) -> np.ndarray:
        effort = self.limit if reference.effort_limit is None else reference.effort_limit
        if _float_vector(q) and _float_vector(v) and _float_vector(effort):
            tau = self._compiled_torque(t, q, v, effort, reference)
            if tau is not None:
                return tau
        q_d, v_d, a_d = reference.at(t)
        a_command = a_d + self.kp * (q_d - q) + self.kd * (v_d - v)
        tau = inverse_dynamics(self.robot, self.data, q, v, a_command)
        friction = self.friction
        if friction is not None:
            tau += friction.torque(v_d, friction.steady_state_bristles(v_d))
        limit = reference.limit(self.limit)
        return np.clip(tau, -limit, limit)

    def _compiled_torque(self, t: float, q: np.ndarray, v: np.ndarray, effort: np.ndarray,
                         reference: Reference) -> np.ndarray | None:
        """:meth:`torque` for float64 q, v and ``effort`` (the reference's effort limit, N m,
        N; the URDF's without one): the desired motion and commanded acceleration in one
        compiled call (the trajectory's ``compiled`` arrays; another trajectory's ``at``),
        the RNEA, then the friction feedforward and the clip in another; the same operations
        in the same order as numpy's. None for a desired motion that is not float64."""
        compiled, n = reference.compiled, self.kp.shape[0]
        a_command = np.empty(n)
        if compiled is not None:
            motion = np.empty((3, n))
            _tracking_acceleration_unchecked(compiled[0], compiled[1], float(t), q, v, self.kp, self.kd, motion,
                                             a_command)
            v_d = motion[1]
        else:
            q_d, v_d, a_d = reference.at(t)
            if not (_float_vector(q_d) and _float_vector(v_d) and _float_vector(a_d)):
                return None
            _commanded_acceleration_unchecked(q, v, q_d, v_d, a_d, self.kp, self.kd, a_command)
        tau = pin.rnea(self.robot.model, self.data, q, v, a_command)
        friction = self.friction
        if friction is None:
            _feedforward_and_clip_unchecked(v_d, NO_BRISTLES, NO_TABLE, False, self.limit, effort, tau)
        else:
            bristles = NO_BRISTLES if friction.lugre is None else friction.steady_state_bristles(v_d)
            _feedforward_and_clip_unchecked(v_d, bristles, friction.table, True, self.limit, effort, tau)
        return tau


def _float_vector(array: np.ndarray) -> bool:
    """Whether ``array`` is a float64 vector (what the compiled controller loops may take)."""
    return type(array) is np.ndarray and array.dtype is FLOAT and array.ndim == 1


#: The friction table handed to :func:`_feedforward_and_clip` without friction (not read).
NO_TABLE = np.zeros((0, 0))


def make_controller(kind: str, robot: Robot, kp: np.ndarray, kd: np.ndarray,
                    friction: JointFriction | None) -> Controller:
    """The controller of the given kind (``none``, ``pd``, ``computed_torque``); ``friction``
    is the plant's friction model (used by computed torque)."""
    if kind == "none":
        return NoController(robot)
    if kind == "pd":
        return GravityCompensatedPD(robot, kp, kd)
    return ComputedTorque(robot, kp, kd, friction)


@dataclass(frozen=True)
class Control:
    """What drives a compiled scene's joints: the scene's ``controller`` law and the
    ``reference`` it tracks by default, or a Python ``callback`` (t, q, v) -> tau asked every
    ``period`` (s), its torque held in between (both None without one)."""

    controller: Controller
    reference: Reference
    callback: ControllerCallback | None = None
    period: float | None = None
