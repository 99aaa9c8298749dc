"""The compiled scene, a frozen :class:`SimModel` (:func:`~youbot_dynamics.sim.build.compile`
turns a Scene into one, in sim/build.py).

One Pinocchio model (the plant) holds the scene's robot (locked joints removed, the scene's
gravity) followed by one free-flyer joint per free body, as Drake's MultibodyPlant holds
every body of a scene. ABA, the mass matrix, the energies and ``pin.integrate`` so treat
robot joints and free bodies alike, and one :class:`~youbot_dynamics.dynamics.contact_model
.ContactModel` on that plant serves the compliant, impulsive and constraint-based laws. The
model also holds the joint friction, the control (the controller and its gains, the default
reference, or a Python callback: :class:`~youbot_dynamics.sim.controllers.Control`), the
state layout and the divergence bounds; it never changes after compilation. What the
simulation is doing lives in a :class:`~youbot_dynamics.sim.state.SimState`.

The continuous state x (see :mod:`youbot_dynamics.sim.state`) is

    x = [q (robot joints), v (robot joints), base (x, y, yaw), base_v (vx, vy, wz),
         wheel_i (PI integrals, 1 per wheel), twist (6 per body), z (LuGre bristles),
         pose (7 per body), chart (6 per body), cardan (4 per Cardan body), s (compliant
         pairs), armed (compliant pairs)]

``base`` and ``base_v`` exist with a moving base only (scene ``base: kinematic | dynamic``;
:mod:`youbot_dynamics.sim.mobile_base`): the plant then starts with a planar root joint, its
configuration (x, y, cos yaw, sin yaw) built from ``base`` (a global chart of SE(2): no
guard, no folding), its velocity the body-frame twist ``base_v``, so that the plant's
generalised velocity is [base_v, v, twist] (an index array into x). ``wheel_i`` holds the
wheel-speed PI's integral terms of a dynamic base with a controller.

with a free body's configuration ``pin.integrate(pose, chart)``: ``pose`` (position, m, and
quaternion x, y, z, w) is a reference held constant (zero derivative), ``chart`` (6, the
tangent coordinates of Pinocchio's SE(3) exponential) moves with d chart/dt = Jlog6(exp6(
chart)) twist, and a guard folds the chart into the pose when its rotation reaches
``RECENTRE_ANGLE``, so any ODE integrator keeps the body on SE(3) exactly. Outputs come with
every chart folded (chart 0), so there ``pose`` is the body's pose. ``twist`` is the
body-frame (linear, angular) velocity, Pinocchio's free-flyer velocity, so the plant's
generalised velocity is the contiguous block [v, twist]. ``s`` is each compliant pair's
approach speed at its last touch (m/s, held; the Hunt-Crossley hysteresis factor comes from
it) and ``armed`` (0 or 1, held) whether its maximum-compression guard is armed.

That is a body in the default ``rotation_coordinates: chart``. The scene may choose other
coordinates per body (``SimModel.coordinates``), the chart block then held at 0:

- ``quaternion``: ``pose`` itself moves, p' = R v and q' = q (x) (w, 0) / 2 (quaternion x,
  y, z, w; body-frame twist (v, w)), integrated unprojected; the plant and the kinematics
  read the attitude as q / |q|, and the outputs (and the start of each run or advance, and
  the fold of another body's chart) carry q / |q| in ``pose`` (a projection, at outputs);
  ``SimulationResult.quaternion_drift`` is the largest ||q| - 1| seen at the outputs
  before it.
- ``cardan_adaptive``: ``pose``'s position moves (p' = R v); ``cardan`` holds the Cardan
  angles (a1, a2, a3; a' = B(a)^-1 w) and the sequence (0: x-y-z, 1: x-z-y), switched
  by a state event (contact_events.py) when |a2| passes SWITCH_ANGLE (1.5 rad) to the
  other sequence with the same attitude (Modia3D's remedy for gimbal lock; the formulas
  are model/rotations.py's). ``pose``'s quaternion is written from the angles at the
  outputs.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Callable, Mapping

import numpy as np
import pinocchio as pin
from numba import njit, types

from youbot_dynamics.compiled import FLOAT, unchecked
from youbot_dynamics.dynamics.compiled_tree import tree_of
from youbot_dynamics.dynamics.contact_model import ContactModel
from youbot_dynamics.dynamics.contact_stepper import ConstraintStepper
from youbot_dynamics.dynamics.friction import (JOINTS, READ_VECTOR, TABLE, WRITTEN_VECTOR, JointFriction,
                                               accumulate_friction_torque, friction_left_and_rates_unchecked,
                                               left_torque_and_rates)
from youbot_dynamics.dynamics.mobile.ramp import TwistRamp
from youbot_dynamics.dynamics.rigid_body import (forward_dynamics, kinetic_energy, potential_energy,
                                                 symmetrised)
from youbot_dynamics.model.lie import matrix_from_quaternion, quaternion_from_matrix
from youbot_dynamics.model.robot import Robot
from youbot_dynamics.model.rotations import (SEQUENCES, cardan_angle_rates, cardan_matrix,
                                             quaternion_rate)
from youbot_dynamics.scene.contacts import ROTATION_COORDINATES
from youbot_dynamics.scene.schema import IntegratorSpec, Scene
from youbot_dynamics.sim.compiled_steps import CompiledSteps
from youbot_dynamics.sim.controllers import (ComputedTorque, Control, Reference, clip_to_limits,
                                             commanded_acceleration)
from youbot_dynamics.sim.divergence import DivergenceLimits
from youbot_dynamics.sim.mobile_base import BaseModel, BaseMotion
from youbot_dynamics.sim.sensors import SensorModel
from youbot_dynamics.sim.state import StateLayout
from youbot_dynamics.sim.trajectory import POINTS, TIMING, desired_motion

#: Rotation (rad) of a free body's chart at which it is folded into the reference pose.
RECENTRE_ANGLE = 1.0
#: Floor (m/s) of the approach speed the hysteresis factor is derived from; pairs in
#: contact at t = 0 start with it.
MIN_APPROACH_SPEED = 1e-2


# The computed-torque right-hand side of a robot alone (SimModel.computed_torque_derivative)
# in two compiled calls around pin.rnea and pin.aba, each under 8 arguments (numba's entry
# point costs ~0.03 us per argument and ~0.1 us more from the 8th on). Its arrays (n joints,
# x = [q, v, z], z the LuGre bristles): the law's parameters (3, n): rows Kp (1/s^2), Kd
# (1/s), effort limit (N m); the work array (8, n): rows q_d, v_d, a_d (the desired motion at
# t), the commanded acceleration, the torque left after friction, the LuGre joints'
# steady-state bristles at v_d (the first n_lugre entries: the caller's, in Python, as
# JointFriction.steady_state_bristles), then q and v copied from x (what the two Pinocchio
# calls read: views of the work array made once, no slicing of x per call).
_LAW, _WORK = types.Array(types.float64, 2, "C", readonly=True), types.Array(types.float64, 2, "C")


@njit(types.void(POINTS, TIMING, types.float64, READ_VECTOR, _LAW, _WORK), cache=True)
def _computed_torque_command(points: np.ndarray, timing: np.ndarray, t: float, x: np.ndarray, law: np.ndarray,
                             work: np.ndarray) -> None:
    """Before the RNEA: work rows 6, 7 = q, v (x's first 2n entries), rows 0-2 = the desired
    motion at time t (s) of a compiled reference (:func:`~youbot_dynamics.sim.trajectory
    .desired_motion`), row 3 = a_d + Kp (q_d - q) + Kd (v_d - v) (:func:`~youbot_dynamics.sim
    .controllers.commanded_acceleration`); sizes checked (ValueError)."""
    n = work.shape[1]
    if law.shape[0] != 3 or work.shape[0] != 8 or x.shape[0] < 2 * n:
        raise ValueError("computed torque: the law's parameters need 3 rows, the work array 8, x q and v")
    for i in range(n):  # element by element: numba's slice assignments cost ~0.02 us each
        work[6, i], work[7, i] = x[i], x[n + i]
    desired_motion(points, timing, t, work[:3])
    commanded_acceleration(work[6], work[7], work[0], work[1], work[2], law[0], law[1], work[3])


@njit(types.void(_WORK, _LAW, TABLE, JOINTS, READ_VECTOR, WRITTEN_VECTOR, WRITTEN_VECTOR), cache=True)
def _computed_torque_derivative(work: np.ndarray, law: np.ndarray, table: np.ndarray, joints: np.ndarray,
                                x: np.ndarray, tau: np.ndarray, dx: np.ndarray) -> None:
    """Between the RNEA and the ABA, x = [q, v, z] (n joints, z the LuGre bristles): tau
    (N m, the RNEA's at the commanded acceleration) += tau_friction(v_d, bristles at v_d)
    and clipped to +-limit, as :class:`~youbot_dynamics.sim.controllers.ComputedTorque`
    does; then the plant's share of dx/dt as :meth:`SimModel.robot_derivative`'s: work
    row 4 = tau - tau_friction(v, z), dx[:n] = v, dx[2n:] = dz/dt (dx[n:2n] = ABA(q, v,
    row 4) is the caller's). Sizes checked (ValueError) before anything but tau is written."""
    n = tau.shape[0]
    if law.shape[0] != 3 or work.shape[0] != 8 or work.shape[1] != n or joints.shape[0] > n:
        raise ValueError("computed torque: the law's parameters need 3 rows, the work array 8, one column per joint")
    if dx.shape[0] != x.shape[0] or x.shape[0] < 2 * n:
        raise ValueError("computed torque: x and dx/dt need one size, at least q and v")
    accumulate_friction_torque(work[1], work[5, :joints.shape[0]], table, 1.0, tau)
    clip_to_limits(law[2], tau)
    left_torque_and_rates(x[n:2 * n], x[2 * n:], tau, table, joints, work[4], dx[2 * n:])
    for i in range(n):
        dx[i] = x[n + i]


_computed_torque_command_unchecked = unchecked(_computed_torque_command)
_computed_torque_derivative_unchecked = unchecked(_computed_torque_derivative)


#: Every block a state may hold (see the module docstring), in state order.
BLOCKS = ("q", "v", "base", "base_v", "wheel_i", "twist", "z", "pose", "chart", "cardan", "s", "armed")
#: The Cardan sequences by their number in the ``cardan`` block.
CARDAN_SEQUENCES = tuple(SEQUENCES)


@dataclass(frozen=True, eq=False)
class SimModel:
    """A compiled scene (immutable). ``plant`` is the one Pinocchio model; ``robot`` the
    scene's reduced Robot (its model is the plant's leading joints); ``control`` the
    controller, its default reference and a Python callback's period; ``contact`` is None in
    a scene without contact pairs and free bodies."""

    scene: Scene
    integrator: IntegratorSpec
    limits: DivergenceLimits
    robot: Robot
    plant: Robot
    body_names: tuple[str, ...]
    friction: JointFriction | None
    control: Control
    contact: ContactModel | None
    compliant: tuple[int, ...]
    impulsive: tuple[int, ...]
    stepper: ConstraintStepper | None
    layout: StateLayout
    bounds: np.ndarray
    penetration_limits: dict[str, float]
    conservative: bool
    passive: bool
    ee_frame: int
    velocity_index: slice | np.ndarray | None = None
    slices: Mapping[str, slice] = field(default_factory=dict)
    base: BaseModel | None = None
    coordinates: tuple[str, ...] = ()
    sensors: SensorModel | None = None

    # ---- sizes and slices ----------------------------------------------------------------
    @property
    def joint_names(self) -> tuple[str, ...]:
        """The robot's moving joints, in the order of q, v and tau."""
        return self.robot.joint_names

    @property
    def nv(self) -> int:
        """The robot's degrees of freedom (the head of the plant's)."""
        return self.robot.nv

    def block(self, symbol: str) -> slice:
        """Where block ``symbol`` sits in x (looked up once, at compilation)."""
        return self.slices[symbol]

    @property
    def velocity_block(self) -> slice | np.ndarray:
        """Where the plant's generalised velocity [base twist, v, body twists] sits in x (a
        slice, or an index array with a moving base)."""
        return self.velocity_index

    @property
    def joint_velocities(self) -> slice:
        """Where the robot's joint rates sit in the plant's velocity (after the root's)."""
        root = self.plant.root_nv
        return slice(root, root + self.nv)

    @property
    def body_offset(self) -> int:
        """Where the free bodies' coordinates start in the plant's configuration."""
        return self.plant.root_nq + self.robot.nq

    @functools.cached_property
    def robot_alone(self) -> bool:
        """Whether the plant is the robot alone: no free body, no moving base, no contact
        (the most common scene: its rhs takes the shortest path, :meth:`robot_derivative`)."""
        return self.plant is self.robot and self.base is None and self.contact is None

    @functools.cached_property
    def _fixed_robot_alone(self) -> bool:
        """Whether the compiled paths apply: a fixed-root robot alone (``robot_alone``), no
        mimic joints, a regular mass matrix, state [q, v, z]."""
        robot = self.robot
        return (self.robot_alone and robot.root == "fixed" and not robot.mimic and not robot.mass_matrix_defect
                and self.slices["v"] == slice(robot.nv, 2 * robot.nv))

    @functools.cached_property
    def _compiled_derivative(self) -> tuple | None:
        """(nv, end of the v block, Pinocchio model, friction table, LuGre joints) for
        :meth:`robot_derivative`'s compiled path: a :attr:`_fixed_robot_alone` with friction;
        None otherwise."""
        robot = self.robot
        if not (self._fixed_robot_alone and self.friction is not None):
            return None
        return robot.nv, 2 * robot.nv, robot.model, self.friction.table, self.friction.lugre_indices

    @functools.cached_property
    def _tree(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
        """(ints, reals, friction table, LuGre joints) of :meth:`compiled_steps`: a
        :attr:`_fixed_robot_alone` of one-degree-of-freedom joints (compiled_tree.tree_of);
        None otherwise. Without friction, a table of zero damping."""
        robot = self.robot
        if not self._fixed_robot_alone:
            return None
        tree = tree_of(robot.model)
        if tree is None:
            return None
        if self.friction is None:
            table, joints = np.zeros((8, robot.nv)), np.zeros(0, dtype=np.int64)
        else:
            table, joints = self.friction.table, self.friction.lugre_indices
        return (*tree, table, joints) if self.layout.size == 2 * robot.nv + len(joints) else None

    def compiled_steps(self, command: np.ndarray | None) -> CompiledSteps | None:
        """The compiled loops (sim/compiled_steps.py: the fixed-step ones and DOP853's) of a
        robot alone under the held torque ``command`` (N m, joint order) or, without one,
        under no controller (zero torque); None where they do not apply (another controller;
        see :attr:`_tree`)."""
        tree = self._tree
        if tree is None or (command is None and self.control.controller.kind != "none"):
            return None
        return CompiledSteps(*tree, np.zeros(self.robot.nv) if command is None else command)

    def robot_derivative(self, data: pin.Data, x: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """dx/dt of a robot alone (``robot_alone``): x = [q, v, z], one ABA with friction and
        the LuGre bristles' rates. For float64 x and tau (the integrators' case) on a robot
        :attr:`_compiled_derivative` allows: the friction and the rates in one compiled call
        without type dispatch, then pin.aba (the same arithmetic as the general path)."""
        fast = self._compiled_derivative
        if (fast is not None and type(tau) is np.ndarray and tau.dtype is FLOAT and tau.ndim == 1
                and type(x) is np.ndarray and x.dtype is FLOAT and x.ndim == 1):
            nv, end, model, table, joints = fast
            v, dx, left = x[nv:end], np.empty(x.shape[0]), np.empty(nv)
            try:
                friction_left_and_rates_unchecked(v, x[end:], tau, table, joints, left, dx[end:])
            except ValueError:
                pass  # a size it refuses: the general path below names it
            else:
                dx[:nv] = v
                dx[nv:end] = pin.aba(model, data, x[:nv], v, left)
                return dx
        slices = self.slices
        q_block, v_block, z_block = slices["q"], slices["v"], slices["z"]
        q, v = x[q_block], x[v_block]
        dx = np.empty_like(x)
        dx[q_block] = v
        if z_block.stop > z_block.start:
            z = x[z_block]
            dx[v_block] = forward_dynamics(self.robot, data, q, v, tau, self.friction, z)
            dx[z_block] = self.friction.state_derivative(v, z)
        else:
            dx[v_block] = forward_dynamics(self.robot, data, q, v, tau, self.friction)
        return dx

    def computed_torque_derivative(self, data: pin.Data, reference: Reference,
                                   general: Callable[[float, np.ndarray], np.ndarray]
                                   ) -> Callable[[float, np.ndarray], np.ndarray] | None:
        """dx/dt(t, x) of a robot alone under the scene's computed torque tracking
        ``reference``: the controller's law and :meth:`robot_derivative` fused into two
        compiled calls without type dispatch around pin.rnea and pin.aba on ``data`` (the same
        arithmetic in the same order as ``general``, the two called one after the other).
        The closure owns its scratch space (the work array). ``general`` takes an x the
        compiled calls cannot (not a float64 vector, or a size they refuse). None where the
        fused path does not apply: another controller, no compiled :meth:`robot_derivative`
        path, a reference whose trajectory has no compiled form (``Reference.compiled``)."""
        fast, compiled, controller = self._compiled_derivative, reference.compiled, self.control.controller
        if (fast is None or compiled is None or not isinstance(controller, ComputedTorque)
                or controller.friction is not self.friction):
            return None
        nv, end, model, table, joints = fast
        points, timing = compiled
        law = np.array([controller.kp, controller.kd, reference.limit(controller.limit)], dtype=float)
        law.setflags(write=False)
        work = np.zeros((8, nv))
        command, left, q, v = work[3], work[4], work[6], work[7]
        bristles = work[5, :joints.shape[0]] if self.friction.lugre is not None else None
        steady_state_bristles, size = self.friction.steady_state_bristles, self.layout.size
        rnea, aba, empty = pin.rnea, pin.aba, np.empty

        def rhs(t: float, x: np.ndarray) -> np.ndarray:
            if type(x) is np.ndarray and x.dtype is FLOAT and x.ndim == 1:
                try:
                    _computed_torque_command_unchecked(points, timing, t, x, law, work)
                    tau = rnea(model, data, q, v, command)
                    if bristles is not None:
                        bristles[:] = steady_state_bristles(work[1])
                    dx = empty(size)
                    _computed_torque_derivative_unchecked(work, law, table, joints, x, tau, dx)
                except ValueError:
                    pass  # a size the compiled calls refuse: the general path names it
                else:
                    dx[nv:end] = aba(model, data, q, v, left)
                    return dx
            return general(t, x)

        return rhs

    @functools.cached_property
    def bodies_in(self) -> Mapping[str, tuple[int, ...]]:
        """The free bodies' indices by their rotation coordinates."""
        return MappingProxyType({name: tuple(k for k, c in enumerate(self.coordinates) if c == name)
                                 for name in ROTATION_COORDINATES})

    @property
    def all_charts(self) -> bool:
        """Whether every free body moves in a chart (the default)."""
        return len(self.bodies_in["chart"]) == len(self.body_names)

    def cardan(self, x: np.ndarray, k: int) -> tuple[str, np.ndarray]:
        """(sequence, angles (rad)) of Cardan body k (an index of body_names) at state x."""
        j = 4 * self.bodies_in["cardan_adaptive"].index(k)
        block = x[self.block("cardan")]
        return CARDAN_SEQUENCES[int(round(block[j + 3]))], block[j:j + 3]

    # ---- state -> plant ---------------------------------------------------------------------
    def configuration(self, x: np.ndarray) -> np.ndarray:
        """The plant's configuration (nq) at state x: the planar root (x, y, cos, sin) of a
        moving base, robot q, then per body its pose integrated by its chart (position m,
        quaternion x, y, z, w)."""
        q = x[self.block("q")]
        if self.base is not None:
            q = np.concatenate([self.base.root_configuration(x[self.block("base")]), q])
        if not self.body_names:
            return q
        model = self.plant.model
        reference = np.concatenate([q, x[self.block("pose")]])
        tangent = np.concatenate([np.zeros(self.plant.root_nv + self.nv), x[self.block("chart")]])
        q = pin.integrate(model, reference, tangent)
        if self.all_charts:
            return q
        start = self.body_offset
        for k in self.bodies_in["quaternion"]:
            quaternion = x[self.block("pose")][7 * k + 3:7 * k + 7]
            q[start + 7 * k + 3:start + 7 * k + 7] = quaternion / np.linalg.norm(quaternion)
        for k in self.bodies_in["cardan_adaptive"]:
            q[start + 7 * k + 3:start + 7 * k + 7] = quaternion_from_matrix(cardan_matrix(*self.cardan(x, k)))
        return q

    def velocity(self, x: np.ndarray) -> np.ndarray:
        """The plant's generalised velocity (nv): robot v, then each body's twist."""
        return x[self.velocity_block]

    def chart_rate(self, x: np.ndarray) -> np.ndarray:
        """d chart/dt = Jlog6(exp6(chart)) twist per body in a chart (the chart's
        kinematics); 0 for the bodies in other coordinates."""
        chart = x[self.block("chart")].reshape(-1, 6)
        twist = x[self.block("twist")].reshape(-1, 6)
        return np.concatenate([pin.Jlog6(pin.exp6(c)) @ w if kind == "chart" else np.zeros(6)
                               for c, w, kind in zip(chart, twist, self.coordinates)])

    def body_rates(self, x: np.ndarray, dx: np.ndarray) -> None:
        """Write the free bodies' coordinate rates into dx: the charts' (chart_rate); for a
        quaternion body p' = R v (m/s, world) and q' = q (x) (w, 0) / 2; for a Cardan body
        p' = R v and a' = B(a)^-1 w (rad/s). The reference poses and sequences are held."""
        dx[self.block("chart")] = self.chart_rate(x)
        if self.all_charts:
            return
        twist = x[self.block("twist")].reshape(-1, 6)
        pose, pose_rate = x[self.block("pose")], dx[self.block("pose")]
        cardan_rate = dx[self.block("cardan")]
        attitudes = self.configuration(x)[self.body_offset:].reshape(-1, 7)[:, 3:]
        for k in self.bodies_in["quaternion"] + self.bodies_in["cardan_adaptive"]:
            pose_rate[7 * k:7 * k + 3] = matrix_from_quaternion(attitudes[k]) @ twist[k, :3]
        for k in self.bodies_in["quaternion"]:
            pose_rate[7 * k + 3:7 * k + 7] = quaternion_rate(pose[7 * k + 3:7 * k + 7], twist[k, 3:])
        for j, k in enumerate(self.bodies_in["cardan_adaptive"]):
            cardan_rate[4 * j:4 * j + 3] = cardan_angle_rates(*self.cardan(x, k), twist[k, 3:])

    def quaternion_drift(self, xs: np.ndarray) -> float | None:
        """max ||q| - 1| of the quaternion bodies over states xs (k, n); None without any."""
        if not self.bodies_in["quaternion"]:
            return None
        pose = np.atleast_2d(xs)[:, self.block("pose")].reshape(len(np.atleast_2d(xs)), -1, 7)
        quaternions = pose[:, list(self.bodies_in["quaternion"]), 3:]
        return float(np.max(np.abs(np.linalg.norm(quaternions, axis=-1) - 1.0)))

    def recentred(self, x: np.ndarray, q: np.ndarray | None = None) -> np.ndarray:
        """The same state with every body's chart folded into its reference pose (chart 0)
        and every ``pose`` block at its body's pose (a quaternion body's q / |q|, a Cardan
        body's attitude from its angles); ``q``: x's configuration, if known."""
        if not self.body_names:
            return x
        q = self.configuration(x) if q is None else q
        x = x.copy()
        x[self.block("pose")] = q[self.body_offset:]
        x[self.block("chart")] = 0.0
        return x

    def base_motion(self, t: float, twist: TwistRamp | None = None) -> BaseMotion | None:
        """A kinematic base's commanded motion at t (s) (under a ``twist`` command if
        given); None for a fixed or dynamic base."""
        return None if self.base is None or self.base.dynamic else self.base.motion(t, twist)

    def imposed(self, x: np.ndarray, motion: BaseMotion | None) -> np.ndarray:
        """x with a kinematic base's ``motion`` imposed (pose, twist, wheel speeds); x
        itself when ``motion`` is None."""
        if motion is None:
            return x
        x = x.copy()
        if motion.pose is not None:
            x[self.block("base")] = motion.pose
        x[self.block("base_v")] = motion.twist
        x[self.block("v").start + self.base.wheels] = motion.wheel_speeds
        return x

    # ---- dynamics ------------------------------------------------------------------------------
    def accelerations(self, data: pin.Data, x: np.ndarray, tau: np.ndarray,
                      motion: BaseMotion | None = None) -> np.ndarray:
        """The plant's accelerations (nv) at state x under robot joint torques tau (N m): ABA
        with joint friction, the compliant contact forces and a dynamic base's floor forces
        (Pinocchio's convention for the root and the bodies: the time derivative of the body
        twist); a kinematic base's root and wheels follow its ``motion``."""
        q, v = self.configuration(x), self.velocity(x)
        generalised = np.zeros(self.plant.nv)
        joints = self.joint_velocities
        generalised[joints] = tau
        if self.friction is not None:
            z = x[self.block("z")]
            generalised[joints] -= self.friction.torque(v[joints], z if z.size else None)
        if self.compliant:
            pin.framesForwardKinematics(self.plant.model, data, q)
            generalised += self.contact.compliant_force(data, q, v, self.contact.poses(data), self.compliant,
                                                        x[self.block("s")])
        if self.base is None:
            return forward_dynamics(self.plant, data, q, v, generalised)
        if self.base.dynamic:
            generalised += self.base.floor_force(self.plant.model, data, q, v)
            return forward_dynamics(self.plant, data, q, v, generalised)
        imposed = np.concatenate([motion.acceleration, motion.wheel_accelerations])
        return self.base.prescribed_accelerations(self.plant.model, data, q, v, generalised, imposed)

    def applied_torque(self, data: pin.Data, x: np.ndarray, tau: np.ndarray, a: np.ndarray) -> np.ndarray:
        """The robot's applied joint torque (N m, N) at state x: ``tau`` (the controller's or
        the command), except at a kinematic base's wheels, whose motion is imposed: there the
        torque that imposes it, (M a + b)_wheel + friction (Pinocchio's RNEA at the plant's
        accelerations ``a``)."""
        if self.base is None or self.base.dynamic:
            return tau
        v = self.velocity(x)
        joints, wheels = self.joint_velocities, self.base.wheels
        applied = np.array(tau, dtype=float)
        applied[wheels] = pin.rnea(self.plant.model, data, self.configuration(x), v, a)[joints][wheels]
        if self.friction is not None:
            z = x[self.block("z")]
            applied[wheels] += self.friction.torque(v[joints], z if z.size else None)[wheels]
        return applied

    def compliant_point_forces(self, data: pin.Data, x: np.ndarray) -> list[tuple[int, np.ndarray, np.ndarray]]:
        """The compliant pairs' contact forces at state x: (pair index, point (world, m), force
        on the pair's second geometry (world, N)) per overlapping point."""
        if not self.compliant:
            return []
        q = self.configuration(x)
        pin.framesForwardKinematics(self.plant.model, data, q)
        return [(k, point, force) for k, point, _, force in self.contact.compliant_point_forces(
            data, q, self.velocity(x), self.contact.poses(data), self.compliant, x[self.block("s")])]

    def inverse_mass(self, data: pin.Data, q: np.ndarray) -> np.ndarray:
        """M(q)^-1 of the plant (nv x nv), symmetric."""
        if self.plant.mimic:
            return np.linalg.inv(symmetrised(pin.crba(self.plant.model, data, q)))
        return symmetrised(pin.computeMinverse(self.plant.model, data, q))

    def geometry_poses(self, data: pin.Data, q: np.ndarray) -> list[np.ndarray]:
        """World poses (4x4) of the contact geometries at plant configuration q."""
        pin.framesForwardKinematics(self.plant.model, data, q)
        return self.contact.poses(data)

    def energy(self, data: pin.Data, x: np.ndarray, q: np.ndarray | None = None) -> float:
        """Kinetic plus potential energy (J) of robot and bodies at state x (``q``: its
        configuration, if known)."""
        q, v = self.configuration(x) if q is None else q, self.velocity(x)
        return kinetic_energy(self.plant, data, q, v) + potential_energy(self.plant, data, q)

    def stored_energy(self, data: pin.Data, x: np.ndarray, q: np.ndarray | None = None) -> float:
        """Kinetic, potential and contact-spring energy (J): what a passive scene may only lose
        (``q``: x's configuration, if known)."""
        springs = 0.0
        if self.compliant:
            q = self.configuration(x) if q is None else q
            springs = self.contact.elastic_energy(self.geometry_poses(data, q), self.compliant)
        return self.energy(data, x, q) + springs

    def body_poses(self, data: pin.Data, x: np.ndarray, q: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """World pose (4x4, m) of every free body at state x (``q``: its configuration, if
        known), by name."""
        if not self.body_names:
            return {}
        q = self.configuration(x) if q is None else q
        nq = self.body_offset
        return {name: pin.XYZQUATToSE3(q[nq + 7 * k:nq + 7 * k + 7]).homogeneous
                for k, name in enumerate(self.body_names)}

    def body_motion(self, xs: np.ndarray) -> dict[str, np.ndarray]:
        """The free bodies along states xs (k, n): ``position`` (k, nb, 3; centre of mass, m),
        ``rotation`` (k, nb, 3, 3; body axes in the world), ``velocity`` and ``angular_velocity``
        (k, nb, 3; world frame, m/s and rad/s)."""
        xs = np.atleast_2d(xs)
        nb, nq = len(self.body_names), self.body_offset
        q = np.array([self.configuration(x)[nq:] for x in xs]).reshape(len(xs), nb, 7)
        rotation = matrix_from_quaternion(q[:, :, 3:])
        twist = xs[:, self.block("twist")].reshape(len(xs), nb, 6)
        return {"position": q[:, :, :3], "rotation": rotation,
                "velocity": np.einsum("kbij,kbj->kbi", rotation, twist[:, :, :3]),
                "angular_velocity": np.einsum("kbij,kbj->kbi", rotation, twist[:, :, 3:])}

    def ee_pose(self, data: pin.Data, x: np.ndarray) -> np.ndarray:
        """4x4 pose (m) of the end-effector link at state x: in the root frame, or in the
        world (odom) frame with a moving base."""
        pin.framesForwardKinematics(self.plant.model, data, self.configuration(x))
        return data.oMf[self.ee_frame].homogeneous.copy()

    def clipped(self, tau) -> np.ndarray:
        """A torque command (sequence in joint order or mapping by joint name) clipped to the
        effort limits (N m, N)."""
        limit = np.asarray(self.robot.effort_limit)
        return np.clip(self.robot.vector(tau, what="tau_command"), -limit, limit)

    def is_passive(self, command: np.ndarray | None) -> bool:
        """Whether nothing feeds energy in: no controller, and no or a zero command."""
        return self.passive and self.control.callback is None and (command is None or not np.any(command))
