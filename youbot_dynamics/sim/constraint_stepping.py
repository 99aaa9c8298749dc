"""The constraint stepper as a :class:`~youbot_dynamics.integrate.drive.Stepper`: the engine's
loop for scenes whose contact is constraint-based (velocity level, impulses, fixed dt), its
outputs folded once per output time, its counters, contact events and divergence checks."""
from __future__ import annotations

import math
from typing import Callable

import numpy as np
import pinocchio as pin

from youbot_dynamics.dynamics.mobile.wheel_floor import TipOverError
from youbot_dynamics.integrate.integrators import DivergenceError, IntegratorStats
from youbot_dynamics.sim.model import SimModel
from youbot_dynamics.sim.state import ContactEvent, SimState

#: joint torque (N m) and a moving base's PI integral rate (N m/s), or None where it has none
TorqueAndRate = tuple[np.ndarray, np.ndarray | None]


class ConstraintStepping:
    """The constraint stepper behind ``drive()``: equal steps of at most ``dt`` that end on
    each output time (a sliver of a step left over by round-off would turn the overlap
    correction, depth / dt, into a huge impulse); joint friction applied explicitly. After
    every step: a non-finite velocity or an overlap beyond ``deepest_allowed`` (m) is
    divergence; a pair that starts carrying an impulse is a ``contact`` event. Its state at
    each output time (and at the start) is the output itself: every body's chart folded into
    its pose (:meth:`SimModel.recentred`), the plant configuration it was folded from kept
    for the energy ledger (:meth:`output_configuration`)."""

    def __init__(self, model: SimModel, state: SimState, torque: Callable[[float, np.ndarray], TorqueAndRate],
                 deepest_allowed: float, record: bool = False) -> None:
        self.model, self.data, self.torque, self.twist = model, state.data, torque, state.reference.base_twist
        self.t, self.q, self.v = state.t, model.configuration(state.x), model.velocity(state.x).copy()
        self.x = model.recentred(state.x, self.q) if model.body_names else state.x.copy()  # a copy either way
        self._configuration = self.q if model.body_names else None
        self.h, self.steps, self.iterations = 0.0, 0, 0
        self.touching = state.touching
        self.events: list[ContactEvent] = []
        self.deepest, self.deepest_allowed = 0.0, deepest_allowed
        self.t_previous, self.x_previous = self.t, self.x
        #: with ``record``, per output time: the last step's (report, acceleration, h); the next step's robot torque
        self.records, self.torques = ({}, {}) if record else (None, None)
        # what every step reads, looked up once: where the plant's q and v go in x (packed
        # before each controller call), the robot's joints in the plant's v, the base's wheels
        root, nv = model.plant.root_nq, model.plant.nv
        self._robot_q, self._q_block, self._v_block = slice(root, root + model.robot.nq), model.block("q"), \
            model.velocity_block
        self._bodies = (model.block("pose"), model.block("chart"), model.body_offset) if model.body_names else None
        self._base_block, self._integral = model.block("base"), model.block("wheel_i")
        self._joints, self._nv, self._moving = model.joint_velocities, nv, model.nv > 0
        self._wheels = None if model.base is None else np.arange(nv)[self._joints][model.base.wheels]
        self._zero_tangent, self._no_force = np.zeros(nv), np.zeros(nv)
        self._no_force.setflags(write=False)
        self._unforced = not self._moving and model.base is None

    def _pack_robot(self) -> np.ndarray:
        """``x`` with the stepper's robot q, base pose and plant v written in, in place (what
        the controller reads before a step): :meth:`advance` steps its own copy of the state
        (the previous one stays as ``x_previous``)."""
        model, x = self.model, self.x
        x[self._q_block] = self.q[self._robot_q]
        if model.base is not None:
            pose = self._base_block
            x[pose] = model.base.unwrapped_pose(self.q[:self._robot_q.start], x[pose.stop - 1])
        x[self._v_block] = self.v
        return x

    def _output_state(self) -> np.ndarray:
        """``x`` packed whole at an output time: the free bodies' poses from the stepper's q,
        their charts 0, then recentred (the plant configuration it was folded from kept)."""
        x = self._pack_robot()
        if self._bodies is None:
            return x
        pose, chart, offset = self._bodies
        x[pose] = self.q[offset:]
        x[chart] = 0.0
        self._configuration = self._unfolded_configuration(x)
        return self.model.recentred(x, self._configuration)

    def _unfolded_configuration(self, x: np.ndarray) -> np.ndarray:
        """:meth:`SimModel.configuration` of ``x`` as packed (the stepper's robot q and body
        poses, charts 0). Without a moving base (whose root it rebuilds from x's yaw) that is
        pin.integrate of the stepper's own q by a zero tangent: the same call on the same
        numbers, without assembling them from x."""
        if self.model.base is not None:
            return self.model.configuration(x)
        return pin.integrate(self.model.plant.model, self.q, self._zero_tangent)

    def output_configuration(self, x: np.ndarray) -> np.ndarray:
        """The plant configuration (nq) of output state ``x``, the stepper's state at its time
        t: the one its free bodies' charts were folded from (:meth:`SimModel.configuration`
        of the state before folding), so that the energy at an output is the same to the bit
        as the unfolded state's."""
        return self.model.configuration(x) if self._configuration is None else self._configuration

    def _generalised_force(self, h: float, keep: bool = False) -> np.ndarray:
        """The plant's applied generalised force (nv; N, N m) over the next step of h (s): the
        robot's torque less its joint friction (explicit) and a dynamic base's floor forces;
        the base's PI integral terms move on by explicit Euler. Nothing acts on a plant of
        free bodies alone: the same zeros every step, read-only (a write into them raises).
        ``keep``: the robot's torque kept in ``torques`` at the step's start time."""
        if self._unforced:
            return self._no_force
        tau, rate = np.zeros(self._nv), None
        if self._moving:
            joints, friction = self._joints, self.model.friction
            tau[joints], rate = self.torque(self.t, self._pack_robot())
            if keep:
                self.torques[self.t] = tau[joints].copy()
            if friction is not None:
                friction.add_torque(tau[joints], self.v[joints], None, -1.0)
        base = self.model.base
        if base is not None:  # dynamic (a kinematic base refuses the stepper)
            model, integral = self.model, self._integral
            try:
                tau += base.floor_force(model.plant.model, self.data, self.q, self.v)
            except TipOverError as error:
                raise DivergenceError(self.t, model.integrator.method, h, f"the base tips over: {error}") from None
            if integral.stop > integral.start:
                self.x[integral] += h * (base.wheel_torques(self.t, self.v[self._wheels], self.x[integral], self.twist)[1]
                                         if rate is None else rate)
        return tau

    def _account(self, report, h: float) -> None:
        """After a step of h (s) that reached t: its counters, the contact events and the
        divergence checks (a non-finite velocity, an overlap beyond the limit)."""
        self.steps += 1
        self.iterations += report.iterations
        if report.penetration > self.deepest:
            self.deepest = report.penetration
        if report.normal_impulse or self.touching:
            touching = frozenset(name for name, impulse in report.normal_impulse.items() if impulse > 0)
            if touching != self.touching:
                self.events += [ContactEvent(self.t, name, "contact", report.normal_impulse[name])
                                for name in sorted(touching - self.touching)]
                self.touching = touching
        if not math.isfinite(self.v.dot(self.v)):  # a NaN, an infinity, or |v| beyond 1e154
            raise DivergenceError(self.t, self.model.integrator.method, h, "non-finite velocity")
        if not report.penetration <= self.deepest_allowed:
            raise DivergenceError(self.t, self.model.integrator.method, h, f"overlap {report.penetration:.3g} m "
                                  f"beyond the penetration limit {self.deepest_allowed:.3g} m")

    def advance(self, t_target: float) -> None:
        stepper, data = self.model.stepper, self.data
        count = max(1, math.ceil((t_target - self.t) / self.model.integrator.dt - 1e-9))
        start, h = self.t, (t_target - self.t) / count
        self.t_previous, self.x_previous, self.x = self.t, self.x, self.x.copy()
        for i in range(1, count + 1):
            tau = self._generalised_force(h, i == 1 and self.torques is not None)
            v_before = self.v
            self.q, self.v, report = stepper.step(data, self.q, self.v, tau, h)
            self.t = t_target if i == count else start + i * h
            self._account(report, h)
        self.h = h
        self.x = self._output_state()
        if self.records is not None:
            self.records[self.t] = (report, (self.v - v_before) / h, h)

    def interpolate(self, t: float) -> np.ndarray:
        share = (t - self.t_previous) / (self.t - self.t_previous)
        return self.x_previous + share * (self.x - self.x_previous)

    def finish(self, stats: IntegratorStats) -> None:
        # one dynamics pass (Delassus operator and solve) per step; no Jacobian counter applies
        stats.steps = stats.rhs_evals = self.steps
        stats.nonlinear_iterations = self.iterations
        stats.jac_evals = stats.nonlinear_convergence_failures = None
        stats.rejected_steps = 0
