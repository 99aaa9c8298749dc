"""The simulator: a Scene compiled into a right-hand side and driven by an integrator.

From a :class:`~youbot_dynamics.sim.scene.Scene` it builds only what the scene names: the
reduced Robot (locked joints removed from the model and the state), the scene's gravity,
the joint friction (none at all for a frictionless scene; LuGre bristle states only for
LuGre joints), the controller and its trajectory, the state layout and the divergence
checks. The state is x = [q, v, z] (see :mod:`youbot_dynamics.sim.state`) and

    dq/dt = v,   dv/dt = ABA(q, v, tau(t, q, v) - tau_friction(v, z)),   dz/dt = LuGre(v, z).

Two ways to drive it:

- ``Simulator(scene).run()`` -> :class:`SimulationResult`: the whole scene from its
  initial state, outputs at the scene's rate, statistics and the energy error.
- Step-wise, for a ROS node or any outer loop: ``reset()``, then repeatedly
  ``advance(t_next, tau_command=None)`` -> :class:`Snapshot` (or ``advance_through(times,
  ...)`` -> one per time); ``tau_command`` (joint order
  of ``joint_names``, N m) replaces the scene's controller until the next call (zero-order
  hold, clipped to the effort limits). The current ``t``, ``q``, ``v``, ``z``, ``tau``,
  ``energy`` and ``ee_pose`` are properties; ``stats`` sums the statistics of every call.
  Each ``advance`` restarts the integrator at the current state (adaptive methods start
  with a fresh step-size guess).

Divergence is a :class:`~youbot_dynamics.sim.integrators.DivergenceError`: a non-finite
state, a joint velocity beyond ``VELOCITY_LIMIT_FACTOR`` x its limit, a step size that
collapses, or a limit of :mod:`youbot_dynamics.sim.divergence` exceeded: in a passive
scene (no controller, no commanded effort; friction and contact only dissipate) a stored
energy that grows by more than the scene's ``integrator.energy_tolerance`` (J, checked at
outputs), a free body too fast or a pair overlapping too deep, or a step budget spent.
"""
from __future__ import annotations

import csv
import dataclasses
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np
import pinocchio as pin

from youbot_dynamics.dynamics.contact_stepper import ConstraintStepper, StepperSettings
from youbot_dynamics.dynamics.rigid_body import (forward_dynamics, kinetic_energy, mass_matrix,
                                                 potential_energy)
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.configuration import require_fixed_root
from youbot_dynamics.model.lie import matrix_from_quaternion, quaternion_from_matrix
from youbot_dynamics.sim.contact_system import ContactEvent, ContactSystem
from youbot_dynamics.sim.controllers import Reference, make_controller
from youbot_dynamics.sim.divergence import (DivergenceLimits, Monitor, all_of, energy_ledger_monitor,
                                            penetration_limit, penetration_monitor)
from youbot_dynamics.sim.events import Mode, simulate_hybrid
from youbot_dynamics.sim.integration import StateCheck
from youbot_dynamics.sim.integrators import (DivergenceError, IntegratorStats, Solution,
                                             checked_fixed_step, checked_output_spacing, integrate,
                                             integrate_dae)
from youbot_dynamics.sim.registry import STEPPERS
from youbot_dynamics.sim.scene import IntegratorSpec, Scene
from youbot_dynamics.sim.state import StateLayout
from youbot_dynamics.sim.trajectory import PointToPointTrajectory

#: A torque command: a sequence in joint order or a mapping by joint name (N m, N).
TorqueCommand = Sequence[float] | np.ndarray | Mapping[str, float]
#: A joint velocity beyond this multiple of its URDF limit is divergence.
VELOCITY_LIMIT_FACTOR = 100.0


@dataclass(frozen=True)
class Snapshot:
    """The simulation at one instant: t (s), q (rad, m), v (rad/s, m/s), z (LuGre bristle
    deflections), tau (applied joint torque, N m or N), energy (kinetic + potential, J) and
    ee_pose (4x4 homogeneous pose of the end-effector link in the robot's root frame, m;
    the first robot's for composed robots, ``Robot.end_effectors``);
    bodies: the world pose (4x4, m) of each free body by name, in the scene's order."""

    t: float
    joint_names: tuple[str, ...]
    q: np.ndarray
    v: np.ndarray
    z: np.ndarray
    tau: np.ndarray
    energy: float
    ee_pose: np.ndarray
    bodies: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)


@dataclass
class SimulationResult:
    """A run: states x (k, n) at times t (k,), named by ``layout``; ``series`` holds the
    recorded extras (``tau`` (k, nv), ``energy`` (k,), ``ee_position`` (k, 3)); ``stats``
    the integrator's statistics. ``energy_error`` (J) is max |E(t) - E(0)| in a conservative
    scene, None otherwise (friction or a controller change the energy). ``energy_dissipated``
    (J) is the ledger of a passive scene, E(0) - E(end) of the stored energy (kinetic,
    potential, contact springs): what friction, damping and contact hysteresis took, >= 0
    up to the tolerance; None when a controller acts. A contact scene adds
    its ``contact_events`` and ``max_penetration`` (m: the deepest overlap at the located
    maximum compressions of the compliant law, or over the constraint stepper's steps)."""

    scene: str
    integrator: IntegratorSpec
    layout: StateLayout
    t: np.ndarray
    x: np.ndarray
    series: dict[str, np.ndarray]
    stats: IntegratorStats
    conservative: bool
    energy_error: float | None
    contact_events: list[ContactEvent] = dataclasses.field(default_factory=list)
    max_penetration: float | None = None
    energy_dissipated: float | None = None

    @property
    def final_state(self) -> dict[str, float]:
        """The last state by component name (``q[arm_joint_1]`` ...)."""
        return dict(zip(self.layout.names, map(float, self.x[-1])))

    def columns(self, record: tuple[str, ...]) -> tuple[list[str], np.ndarray]:
        """Column names and the (k, m) table of t and the recorded quantities."""
        names, blocks = ["t"], [self.t[:, None]]
        for item in record:
            if item in ("q", "v", "z"):
                part = self.layout.slice(item)
                names += list(self.layout.names[part])
                blocks.append(self.x[:, part])
            elif item == "tau":
                names += [f"tau[{n}]" for n in self.layout.joint_names]
                blocks.append(self.series["tau"])
            elif item == "energy":
                names.append("energy")
                blocks.append(self.series["energy"][:, None])
            elif item == "ee_position":
                names += ["ee_x", "ee_y", "ee_z"]
                blocks.append(self.series["ee_position"])
        return names, np.hstack(blocks)

    def write_csv(self, path: str | Path, record: tuple[str, ...]) -> None:
        """The trajectory as CSV (SI units; one row per output time)."""
        names, table = self.columns(record)
        with open(path, "w", newline="", encoding="utf-8") as handle:
            writer = csv.writer(handle)
            writer.writerow(names)
            writer.writerows(table.tolist())


class Simulator:
    """A compiled scene: model, friction, controller, state layout, rhs and checks."""

    def __init__(self, scene: Scene, integrator: IntegratorSpec | None = None,
                 limits: DivergenceLimits | None = None) -> None:
        self.scene = scene
        self.integrator = integrator or scene.integrator
        self.limits = limits or DivergenceLimits()
        if self.integrator.method == "auto":
            raise UserInputError(f"{scene.source}: integrator.method: 'auto' must be resolved first "
                                 "(youbot_dynamics.analysis.work_precision.resolve_integrator)")
        self.robot = scene.robot  # reduced, with the scene's gravity
        require_fixed_root(self.robot, scene.source)  # the state layout and steppers assume nq == nv
        self.data = self.robot.model.createData()
        self.friction = scene.joint_friction(self.robot)
        lugre = [] if self.friction is None else \
            [name for name, law in zip(self.friction.joint_names, self.friction.laws) if law == "lugre"]
        self.contact = ContactSystem(scene, self.robot, self.data) if scene.has_contact else None
        extra = {"z": lugre, **(self.contact.extra_blocks() if self.contact else {})}
        self.layout = StateLayout.for_joints(self.robot.joint_names, extra)
        if self.contact:
            self.contact.bind({symbol: self.layout.slice(symbol) for symbol in extra if symbol != "z"})
        spec = scene.controller
        trajectory = None if spec.trajectory is None else PointToPointTrajectory.through(
            np.vstack([scene.q0, spec.trajectory.waypoints]), spec.trajectory.v_max,
            spec.trajectory.a_max, spec.trajectory.dwell)
        self.trajectory = trajectory
        self.controller = make_controller(spec.type, self.robot, Reference(scene.q0, trajectory), spec.kp, spec.kd,
                                          self.friction)
        self.conservative = self.friction is None and spec.type == "none" and not scene.contacts
        self.passive = spec.type == "none"
        self.effort_limit = np.asarray(self.robot.effort_limit)
        self.ee_frame = self.robot.frame_id(self.robot.end_effectors[0])
        self.bounds = self.layout.velocity_bounds(self.robot.velocity_limit, VELOCITY_LIMIT_FACTOR)
        self.bounds[self.layout.slice("u")] = self.limits.body_speed
        self.bounds[self.layout.slice("w")] = self.limits.body_spin
        shapes = {g.name: g.shape for g in scene.geometries}
        self.penetration_limits = {p.name: penetration_limit(shapes[p.geometry1], shapes[p.geometry2],
                                                             self.limits.penetration_fraction)
                                   for p in scene.contacts}
        self._q, self._v, self._z = (self.layout.slice(s) for s in ("q", "v", "z"))
        self._stepper: ConstraintStepper | None = None
        self.reset()

    # ---- the model ----------------------------------------------------------------------
    @property
    def joint_names(self) -> tuple[str, ...]:
        """The moving joints, in the order of q, v and tau."""
        return self.robot.joint_names

    @property
    def state_dim(self) -> int:
        """Dimension of the continuous state x."""
        return self.layout.size

    def initial_state(self) -> np.ndarray:
        """x0 from the scene: q0, v0 and LuGre bristles at their steady state for v0."""
        z0 = self.friction.steady_state_bristles(self.scene.v0) if self.friction is not None else np.zeros(0)
        bodies = self.contact.initial_blocks() if self.contact else {}
        return self.layout.pack(q=self.scene.q0, v=self.scene.v0, **({"z": z0} if z0.size else {}), **bodies)

    def derivative(self, t: float, x: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """dx/dt under applied joint torques tau (N m, N)."""
        q, v, z = x[self._q], x[self._v], x[self._z]
        dx = np.empty_like(x)
        dx[self._q] = v
        if self.contact:
            tau_contact, wrenches = self.contact.forces(x, q, v)
            tau = tau + tau_contact
            slices = self.contact.slices
            for symbol, rate in self.contact.body_derivative(x, wrenches).items():
                dx[slices[symbol]] = rate
            dx[slices["s"]] = 0.0
        if self.robot.nv:
            dx[self._v] = forward_dynamics(self.robot, self.data, q, v, tau, self.friction, z if z.size else None)
        if z.size:
            dx[self._z] = self.friction.state_derivative(v, z)
        return dx

    def rhs(self, t: float, x: np.ndarray) -> np.ndarray:
        """dx/dt with the scene's controller (what the integrators call)."""
        return self.derivative(t, x, self.controller.torque(t, x[self._q], x[self._v]))

    def rhs_cost(self) -> dict[str, int | str]:
        """What one rhs evaluation computes, by count: the state dimension, the model's
        degrees of freedom and bodies (ABA is O(nv) over them), the friction laws evaluated
        and the controller's extra rigid-body pass (RNEA or gravity: O(nv))."""
        laws = () if self.friction is None else sorted(set(self.friction.laws))
        return {"state_dim": self.layout.size, "nv": self.robot.model.nv,
                "bodies": self.robot.model.nbodies, "lugre_states": self._z.stop - self._z.start,
                "friction_laws": ",".join(laws) or "none", "controller": self.controller.kind,
                "rigid_body_passes": 1 + (self.controller.kind != "none"),
                "free_bodies": len(self.scene.free_bodies), "contact_pairs": len(self.scene.contacts)}

    def energy_of(self, x: np.ndarray) -> float:
        """Kinetic plus potential energy (J) of state x."""
        q, v = x[self._q], x[self._v]
        bodies = self.contact.energy(x) if self.contact else 0.0
        return kinetic_energy(self.robot, self.data, q, v) + potential_energy(self.robot, self.data, q) + bodies

    def stored_energy_of(self, x: np.ndarray) -> float:
        """Kinetic, potential and contact-spring energy (J) of state x: what a passive scene
        may only lose."""
        springs = self.contact.elastic_energy(x, x[self._q]) if self.contact else 0.0
        return self.energy_of(x) + springs

    def is_passive(self, tau_command: np.ndarray | None) -> bool:
        """Whether nothing feeds energy in: no controller, and no or a zero command."""
        return self.passive and (tau_command is None or not np.any(tau_command))

    def monitor_for(self, x0: np.ndarray, tau_command: np.ndarray | None,
                    energy0: float | None = None) -> Monitor | None:
        """The output-time checks of a run from x0: the energy ledger when the run is
        passive (against ``energy0``, J, default x0's stored energy) and the pairs'
        penetration limits (not for the constraint stepper, which holds every step, outputs
        included, to the smallest of those limits)."""
        reference = self.stored_energy_of(x0) if energy0 is None else energy0
        ledger = energy_ledger_monitor(self.stored_energy_of, reference,
                                       self.integrator.energy_tolerance) if self.is_passive(tau_command) else None
        overlap = penetration_monitor(lambda x: self.contact.overlaps(x, x[self._q]),
                                      self.penetration_limits) if self.contact and self.integrator.method not in STEPPERS else None
        return all_of(ledger, overlap)

    def ee_pose_of(self, q: np.ndarray) -> np.ndarray:
        """4x4 pose of the end-effector link in the root frame at joint positions q."""
        pin.framesForwardKinematics(self.robot.model, self.data, q)
        return self.data.oMf[self.ee_frame].homogeneous.copy()

    def body_in_link(self, result: SimulationResult, body: str, link: str) -> np.ndarray:
        """(k, 3) positions (m) of free body ``body``'s centre of mass in the frame of robot
        link ``link`` at the result's output times: constant while the link holds the body
        rigidly (a grasp that does not slip)."""
        bodies = self.contact.body_index if self.contact else {}
        if body not in bodies:
            raise UserInputError(f"{self.scene.source}: no free body {body!r} (free_bodies: "
                                 f"{', '.join(bodies) or 'none'})")
        index = bodies[body]
        positions = result.x[:, self.layout.slice("p")][:, 3 * index:3 * index + 3]
        frame = self.robot.frame_id(link)
        out = np.empty_like(positions)
        for k, (q, p) in enumerate(zip(result.x[:, self._q], positions)):
            pin.framesForwardKinematics(self.robot.model, self.data, q)
            out[k] = self.data.oMf[frame].actInv(p)
        return out

    def clipped(self, tau: TorqueCommand) -> np.ndarray:
        """A torque command in joint order, clipped to the effort limits."""
        tau = self.robot.vector(tau, what="tau_command")
        return np.clip(tau, -self.effort_limit, self.effort_limit)

    # ---- integration ----------------------------------------------------------------------
    def solve(self, x0: np.ndarray, t_eval: np.ndarray, tau_command: np.ndarray | None = None, *,
              max_steps: int | None = None, progress: Callable[[float], None] | None = None,
              energy0: float | None = None) -> Solution:
        """Integrate from x0 at t_eval[0] with outputs at t_eval (s), with the divergence
        checks; ``tau_command`` (held) replaces the controller. More than ``max_steps``
        steps (per segment of a contact scene) are a StepBudgetError; ``progress(t)`` is
        told the time reached (s) after each output; ``energy0`` (J) is the ledger's
        reference (default: x0's stored energy)."""
        spec, names = self.integrator, self.layout.names
        monitor = self.monitor_for(x0, tau_command, energy0)
        if spec.method in STEPPERS:
            return self._step_constraints(x0, t_eval, tau_command, monitor, max_steps, progress)
        rhs = self.rhs if tau_command is None else (lambda t, x: self.derivative(t, x, tau_command))
        if self.contact:
            return self._solve_hybrid(rhs, x0, t_eval, monitor, max_steps, progress)
        if spec.method == "ida":
            def residual(t: float, y: np.ndarray, yp: np.ndarray) -> np.ndarray:
                return yp - rhs(t, y)

            return integrate_dae(residual, x0, rhs(t_eval[0], x0), t_eval, algebraic=[False] * x0.size,
                                 rtol=spec.rtol, atol=spec.absolute_tolerance(x0), state_names=names, bounds=self.bounds,
                                 monitor=monitor, max_steps=max_steps, progress=progress)
        return integrate(rhs, x0, t_eval, spec.method, dt=spec.dt, rtol=spec.rtol, atol=spec.absolute_tolerance(x0),
                         state_names=names, n_positions=self.robot.nv, bounds=self.bounds, monitor=monitor,
                         max_steps=max_steps, progress=progress)

    def _solve_hybrid(self, rhs: Callable[[float, np.ndarray], np.ndarray], x0: np.ndarray, t_eval: np.ndarray,
                      monitor: Monitor | None, max_steps: int | None,
                      progress: Callable[[float], None] | None) -> Solution:
        """The contact scene as a hybrid run (impacts, touches, re-centring are guards);
        returns the samples at ``t_eval`` (after any reset at the same time)."""
        spec = self.integrator
        mode = Mode("contact", rhs, self.contact.transitions(
            self._q, self._v, lambda q: mass_matrix(self.robot, self.data, q)))
        options = {"rtol": spec.rtol, "atol": spec.absolute_tolerance(x0), "state_names": self.layout.names,
                   "bounds": self.bounds, "monitor": monitor, "max_steps": max_steps, "progress": progress}
        if spec.dt is not None:
            options.update(dt=spec.dt, n_positions=self.robot.nv or None)
        elif spec.method != "ida" and self.contact.impulsive:
            options["max_step"] = self.contact.shortest_flight(float(np.linalg.norm(self.scene.gravity)))
        hybrid = simulate_hybrid([mode], "contact", x0, t_eval, spec.method, **options)
        keep = np.searchsorted(hybrid.t, t_eval, side="right") - 1  # the last sample at each t
        return Solution(hybrid.t[keep], hybrid.x[keep], hybrid.stats, hybrid.state_names)

    def constraint_stepper(self) -> ConstraintStepper:
        """The scene's constraint stepper (built on first use)."""
        if self._stepper is None:
            index = {g.name: i for i, g in enumerate(self.scene.geometries)}
            pairs = [(p.name, index[p.geometry1], index[p.geometry2], p.law) for p in self.scene.contacts]
            self._stepper = ConstraintStepper(self.robot.model, [b.body for b in self.scene.free_bodies],
                                              self.scene.geometries, pairs,
                                              StepperSettings(solver=self.integrator.method))
        return self._stepper

    def _step_constraints(self, x0: np.ndarray, t_eval: np.ndarray, tau_command: np.ndarray | None,
                          monitor: Monitor | None, max_steps: int | None,
                          progress: Callable[[float], None] | None) -> Solution:
        """Fixed steps of the constraint stepper from x0 with outputs at t_eval (each output
        interval in equal steps of at most dt); contact events are the steps at which a
        pair starts carrying an impulse. ``monitor`` runs at the outputs; the deepest
        overlap of every step is held to the smallest of the pairs' penetration limits."""
        start = time.perf_counter()
        if self._z.stop > self._z.start:
            raise UserInputError(f"{self.scene.source}: the constraint stepper does not integrate LuGre bristles")
        stepper, h = self.constraint_stepper(), self.integrator.dt
        check = StateCheck(self.integrator.method, self.layout.names, self.bounds, monitor)
        checked_fixed_step(self.integrator.method, h, t_eval, max_steps)
        deepest_allowed = min(self.penetration_limits.values(), default=math.inf)
        nv = self.robot.nv
        q, v = self._pin_state(x0)
        t, outputs = float(t_eval[0]), [x0.copy()]
        # one dynamics pass (Delassus operator and solve) per step; no Jacobian counter applies
        stats = IntegratorStats(self.integrator.method, jac_evals=None,
                                nonlinear_convergence_failures=None)
        penetration, events_before = 0.0, len(self.contact.events)
        for t_next in map(float, t_eval[1:]):
            # equal steps of at most h that end on t_next: a sliver of a step left over by
            # round-off would turn the overlap correction (depth / dt) into a huge impulse
            count = max(1, math.ceil((t_next - t) / h - 1e-9))
            start_interval, dt = t, (t_next - t) / count
            for i in range(1, count + 1):
                tau = np.zeros(stepper.model.nv)
                if nv:
                    qr, vr = q[:nv], v[:nv]
                    command = tau_command if tau_command is not None else self.controller.torque(t, qr, vr)
                    tau[:nv] = command - (self.friction.torque(vr) if self.friction is not None else 0.0)
                q, v, report = stepper.step(q, v, tau, dt)
                t = t_next if i == count else start_interval + i * dt
                stats.steps += 1
                stats.rhs_evals += 1
                stats.nonlinear_iterations += report.iterations
                penetration = max(penetration, report.penetration)
                touching = {name for name, impulse in report.normal_impulse.items() if impulse > 0}
                for name in sorted(touching - self.stepper_touching):
                    self.contact.events.append(ContactEvent(t, name, "contact", report.normal_impulse[name]))
                self.stepper_touching = touching
                if not np.all(np.isfinite(v)):
                    raise DivergenceError(t, self.integrator.method, dt, "non-finite velocity")
                if not report.penetration <= deepest_allowed:
                    raise DivergenceError(t, self.integrator.method, dt, f"overlap {report.penetration:.3g} m "
                                          f"beyond the penetration limit {deepest_allowed:.3g} m")
            x = self._ode_state(q, v)
            check.step(t, x, dt)
            check.output(t, x, dt)
            outputs.append(x)
            if progress is not None:
                progress(t)
        stats.events = len(self.contact.events) - events_before
        stats.simulated_time = float(t_eval[-1] - t_eval[0])
        stats.wall_time = time.perf_counter() - start
        self.stepper_penetration = max(self.stepper_penetration, penetration)
        return Solution(np.asarray(t_eval, dtype=float), np.array(outputs), stats, self.layout.names)

    def _pin_state(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pinocchio (q, v) of the combined model from our state x: per free body its
        position and quaternion (x, y, z, w) and its body-frame (linear, angular) velocity."""
        poses = self.contact.poses_of(x)
        parts = self.layout.split(x)
        q, v = [x[self._q]], [x[self._v]]
        for k, body in enumerate(self.scene.free_bodies):
            pose = poses[body.body.name]
            rotation = pose[:3, :3]
            q += [pose[:3, 3], quaternion_from_matrix(rotation)]
            v += [rotation.T @ parts["u"][3 * k:3 * k + 3], rotation.T @ parts["w"][3 * k:3 * k + 3]]
        return np.concatenate(q), np.concatenate(v)

    def _ode_state(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Our state x from Pinocchio's (q, v): orientation in r, phi = 0, velocities in the world frame."""
        nv = self.robot.nv
        blocks = {"q": q[:nv], "v": v[:nv]}
        p, r, u, w = [], [], [], []
        for k in range(len(self.scene.free_bodies)):
            xyzquat = q[nv + 7 * k:nv + 7 * k + 7]
            rotation = matrix_from_quaternion(xyzquat[3:])
            p.append(xyzquat[:3])
            r.append(xyzquat[3:] / np.linalg.norm(xyzquat[3:]))
            u.append(rotation @ v[nv + 6 * k:nv + 6 * k + 3])
            w.append(rotation @ v[nv + 6 * k + 3:nv + 6 * k + 6])
        if p:
            blocks.update(p=np.concatenate(p), r=np.concatenate(r), u=np.concatenate(u), w=np.concatenate(w))
        return self.layout.pack(**blocks)

    def run(self, t_eval: np.ndarray | None = None,
            progress: Callable[[float], None] | None = None) -> SimulationResult:
        """The scene from its initial state over ``t_eval`` (default: the scene's output
        times); leaves the step-wise state at the end of the run. A fixed step larger than
        the output spacing is refused; at most ``limits.max_steps`` steps; ``progress(t)``
        is told the time reached (s) after each output."""
        times = self.scene.output_times if t_eval is None else np.asarray(t_eval, dtype=float)
        checked_output_spacing(self.integrator.dt, times, f"{self.scene.source}: integrator.dt "
                               f"(outputs.rate {self.scene.outputs.rate:g} Hz)")
        x0 = self.initial_state()
        self._clear_contact_record()
        solution = self.solve(x0, times, max_steps=self.limits.max_steps, progress=progress)
        series = self._series(solution, set(self.scene.outputs.record) | ({"energy"} if self.conservative else set()))
        energy_error = float(np.max(np.abs(series["energy"] - series["energy"][0]))) if self.conservative else None
        self.t, self.x = float(solution.t[-1]), solution.x[-1].copy()
        self.stats = solution.stats
        self._tau = self.controller.torque(self.t, self.x[self._q], self.x[self._v]).copy()
        penetration = None
        if self.contact:
            penetration = self.stepper_penetration if self.integrator.method in STEPPERS else self.contact.deepest
        dissipated = self.stored_energy_of(x0) - self.stored_energy_of(solution.x[-1]) if self.passive else None
        return SimulationResult(self.scene.name, self.integrator, self.layout, solution.t, solution.x,
                                series, solution.stats, self.conservative, energy_error,
                                list(self.contact.events) if self.contact else [], penetration, dissipated)

    def _series(self, solution: Solution, wanted: set[str]) -> dict[str, np.ndarray]:
        series = {}
        if "tau" in wanted:
            series["tau"] = np.array([self.controller.torque(t, x[self._q], x[self._v])
                                      for t, x in zip(solution.t, solution.x)])
        if "energy" in wanted:
            series["energy"] = np.array([self.energy_of(x) for x in solution.x])
        if "ee_position" in wanted:
            series["ee_position"] = np.array([self.ee_pose_of(x[self._q])[:3, 3] for x in solution.x])
        return series

    # ---- step-wise API -------------------------------------------------------------------
    def reset(self, q: np.ndarray | None = None, v: np.ndarray | None = None) -> Snapshot:
        """Back to t = 0 at the scene's initial state (or the given q, v in joint order)."""
        x = self.initial_state()
        if q is not None:
            x[self._q] = self.robot.vector(q, what="reset q")
        if v is not None:
            x[self._v] = self.robot.vector(v, what="reset v")
        self.t, self.x = 0.0, x
        self.stats = IntegratorStats(self.integrator.method)
        self._clear_contact_record()
        self._tau = self.controller.torque(0.0, x[self._q], x[self._v]).copy()
        self._ledger_start: float | None = None
        return self.snapshot()

    def _clear_contact_record(self) -> None:
        """Forget the contact events, the deepest overlap and which pairs touch (a new run).
        Step-wise calls keep them, so a contact that lasts over several calls is one event."""
        self.stepper_penetration, self.stepper_touching = 0.0, set()
        if self.contact:
            self.contact.events.clear()
            self.contact.deepest = 0.0
            self.contact.awaiting[:] = False

    def advance(self, t_next: float, tau_command: TorqueCommand | None = None) -> Snapshot:
        """Integrate from the current time to ``t_next`` (s); ``tau_command`` (sequence in
        joint order or mapping by joint name, N m) replaces the controller until then."""
        return self.advance_through([t_next], tau_command)[-1]

    def advance_through(self, times: Sequence[float] | np.ndarray,
                        tau_command: TorqueCommand | None = None) -> list[Snapshot]:
        """``advance`` with a snapshot at each of ``times`` (s, increasing, after the current
        time) from ONE integrator run (cheaper than one ``advance`` per time: no restart in
        between); ``tau_command`` is held over all of them."""
        times = np.asarray(times, dtype=float).reshape(-1)
        if not times.size or not times[0] > self.t or np.any(np.diff(times) <= 0.0):
            raise UserInputError(f"advance: times {times.tolist()} s must increase from after the "
                                 f"current time {self.t:.9g} s")
        command = None if tau_command is None else self.clipped(tau_command)
        # the ledger spans the whole passive stretch (since the reset or the last command
        # that fed energy in), not one call: slow growth adds up over calls
        if not self.is_passive(command):
            self._ledger_start = None
        elif self._ledger_start is None:
            self._ledger_start = self.stored_energy_of(self.x)
        solution = self.solve(self.x, np.concatenate([[self.t], times]), command,
                              max_steps=self.limits.max_steps_per_call, energy0=self._ledger_start)
        self.stats += solution.stats
        snapshots = []
        for t, x in zip(solution.t[1:], solution.x[1:]):
            self.t, self.x = float(t), x.copy()
            self._tau = command if command is not None else \
                self.controller.torque(self.t, self.x[self._q], self.x[self._v]).copy()
            snapshots.append(self.snapshot())
        return snapshots

    @property
    def q(self) -> np.ndarray:
        """Joint positions (rad, m) at the current time."""
        return self.x[self._q].copy()

    @property
    def v(self) -> np.ndarray:
        """Joint velocities (rad/s, m/s) at the current time."""
        return self.x[self._v].copy()

    @property
    def z(self) -> np.ndarray:
        """LuGre bristle deflections (rad, m; empty without LuGre joints)."""
        return self.x[self._z].copy()

    @property
    def tau(self) -> np.ndarray:
        """The joint torque applied at the current time (N m, N)."""
        return np.array(self._tau)

    @property
    def energy(self) -> float:
        """Kinetic plus potential energy (J) at the current time."""
        return self.energy_of(self.x)

    @property
    def ee_pose(self) -> np.ndarray:
        """4x4 end-effector pose (m) in the root frame at the current time."""
        return self.ee_pose_of(self.x[self._q])

    def snapshot(self) -> Snapshot:
        """The current instant."""
        return Snapshot(self.t, self.joint_names, self.q, self.v, self.z, self.tau, self.energy, self.ee_pose,
                        self.contact.poses_of(self.x) if self.contact else {})
