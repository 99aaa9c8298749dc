"""The one engine: free functions that run a compiled scene (:class:`~youbot_dynamics.sim
.model.SimModel`) from a :class:`~youbot_dynamics.sim.state.SimState`.

- :func:`initial_state` -> the scene's state at t = 0 (or at given q, v).
- :func:`advance` (model, state, times, command) moves the state on, in place (as
  ``mj_step`` moves mjData), and returns a :class:`Snapshot` at each time; ``command`` (N m,
  held) replaces the controller.
- :func:`run` (model, state0, t_eval) -> :class:`SimulationResult`: a whole run with outputs,
  statistics and the energy balance; ``state0`` is left as it was.

The equations: the plant's accelerations come from ABA with joint friction and the compliant
contact forces (:meth:`SimModel.accelerations`); dq/dt = v for the robot joints, the free
bodies' charts follow their twists. A moving base (:mod:`youbot_dynamics.sim.mobile_base`) adds
its pose rate R(yaw) (vx, vy), wz, the floor's roller forces and the wheel-speed PI (dynamic),
or imposes its path's motion on the root and the wheels (kinematic); a twist command
(``Reference.base_twist``, reached within the base's a_max) replaces the path. Every integrator of the registry runs through
``drive()`` (integrate/drive.py) with the same divergence checks: the ODE integrators
(through ``integrate`` or, with contact guards, ``simulate_hybrid``), IDA, and the constraint
stepper (:class:`ConstraintStepping`, a Stepper whose steps are Pinocchio contact solves).

Divergence is a :class:`~youbot_dynamics.integrate.integrators.DivergenceError`: a non-finite
state, a velocity beyond its bound (``VELOCITY_LIMIT_FACTOR`` of sim/build.py x a joint's URDF
limit, the free bodies' speed and spin limits), a step size that collapses, or a limit of
:mod:`youbot_dynamics.sim.divergence` exceeded: in a passive scene (no controller, no
commanded effort) a stored energy that grows by more than ``integrator.energy_tolerance``
(J, checked at outputs), a pair overlapping too deep, or a step budget spent.
"""
from __future__ import annotations

import dataclasses
import functools
import math
import time
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from youbot_dynamics.dynamics.mobile.ramp import TwistRamp
from youbot_dynamics.dynamics.mobile.wheel_floor import TipOverError
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.drive import StateCheck, drive
from youbot_dynamics.integrate.events import Mode, simulate_hybrid
from youbot_dynamics.integrate.integrators import (DivergenceError, IntegratorStats, Solution,
                                                   checked_fixed_step, checked_output_spacing,
                                                   integrate, integrate_dae)
from youbot_dynamics.integrate.registry import integrator_kind
from youbot_dynamics.model.lie import matrix_from_quaternion
from youbot_dynamics.model.rotations import adaptive_angles
from youbot_dynamics.sim.constraint_stepping import ConstraintStepping, TorqueAndRate
from youbot_dynamics.sim.contact_events import MODE, ContactGuards
from youbot_dynamics.sim.divergence import (Monitor, all_of, body_energy, energy_ledger_monitor,
                                            penetration_monitor)
from youbot_dynamics.sim.model import CARDAN_SEQUENCES, MIN_APPROACH_SPEED, SimModel
from youbot_dynamics.sim.results import SimulationResult, Snapshot
from youbot_dynamics.sim.sensors import contact_forces
from youbot_dynamics.sim.state import ContactEvent, SimState

Progress = Callable[[float], None]


# ---- state ------------------------------------------------------------------------------------
def initial_state(model: SimModel, q: np.ndarray | None = None, v: np.ndarray | None = None) -> SimState:
    """The scene's state at t = 0: q0, v0 (or the given q, v in joint order), LuGre bristles
    at their steady state for v, the free bodies' initial poses and twists (world-frame
    velocities in the scene turned into body-frame twists), compliant pairs unarmed."""
    scene, robot = model.scene, model.robot
    q = scene.q0 if q is None else robot.vector(q, what="reset q")
    v = scene.v0 if v is None else robot.vector(v, what="reset v")
    blocks = {"q": q, "v": v}
    if model.friction is not None and model.layout.slice("z").stop > model.layout.slice("z").start:
        blocks["z"] = model.friction.steady_state_bristles(v)
    if model.body_names:
        twist, pose, cardan = [], [], []
        for spec in scene.free_bodies:
            rotation = matrix_from_quaternion(spec.orientation)
            twist += [rotation.T @ spec.velocity, rotation.T @ spec.angular_velocity]
            pose += [spec.position, np.asarray(spec.orientation) / np.linalg.norm(spec.orientation)]
            if spec.rotation_coordinates == "cardan_adaptive":
                sequence, angles = adaptive_angles(rotation)
                cardan += [angles, [CARDAN_SEQUENCES.index(sequence)]]
        blocks.update(twist=np.concatenate(twist), pose=np.concatenate(pose))
        if cardan:
            blocks["cardan"] = np.concatenate(cardan)
    if model.compliant:
        blocks["s"] = np.full(len(model.compliant), MIN_APPROACH_SPEED)
    if model.base is not None:
        blocks.update(base=model.base.pose0, base_v=model.base.twist0)
    x = model.imposed(model.layout.pack(**blocks), model.base_motion(0.0))
    state = SimState(0.0, x, model.control.reference, np.zeros(robot.nv), model.plant.model.createData(),
                     IntegratorStats(model.integrator.method))
    if model.control.callback is None:  # a Python controller is first asked when the run starts
        state.tau = robot_torque(model, state.reference, 0.0, x, None)
    return state


def robot_torque(model: SimModel, reference, t: float, x: np.ndarray, command: np.ndarray | None) -> np.ndarray:
    """The robot's applied joint torque (N m) at (t, x): the command if given, else the
    scene's controller tracking ``reference``."""
    return command if command is not None else controlled_torque(model, reference, t, x)[0]


def controlled_torque(model: SimModel, reference, t: float, x: np.ndarray) -> TorqueAndRate:
    """(joint torque (N m) of the scene's controller tracking ``reference`` at (t, x), a moving
    base's PI integral rate dI/dt (N m/s) from the same wheel-loop call, or None)."""
    tau = model.control.controller.torque(t, x[model.block("q")], x[model.block("v")], reference)
    if model.base is None:
        return tau, None
    base = model.base
    tau = np.array(tau, dtype=float)
    tau[base.wheels], rate = base.wheel_torques(t, x[model.block("v")][base.wheels], x[model.block("wheel_i")],
                                                reference.base_twist)
    return tau, rate


def derivative(model: SimModel, data, x: np.ndarray, tau: np.ndarray, t: float = 0.0,
               twist: TwistRamp | None = None, integral_rate: np.ndarray | None = None) -> np.ndarray:
    """dx/dt at state x and time t (s) under robot joint torques tau (N m, N), a moving base's
    ``twist`` command (None: its path) and PI ``integral_rate`` (N m/s; None: the base asked)."""
    if model.robot_alone:
        return model.robot_derivative(data, x, tau)
    motion = model.base_motion(t, twist)
    x = model.imposed(x, motion)
    dx = np.zeros_like(x)
    dx[model.block("q")] = x[model.block("v")]
    if model.plant.nv:
        try:
            dx[model.velocity_block] = model.accelerations(data, x, tau, motion)
        except TipOverError as error:
            raise DivergenceError(t, model.integrator.method, math.nan, f"the base tips over: {error}") from None
    z = model.block("z")
    if z.stop > z.start:
        dx[z] = model.friction.state_derivative(x[model.block("v")], x[z])
    if model.body_names:
        model.body_rates(x, dx)
    if model.base is not None:
        base = model.base
        dx[model.block("base")] = base.pose_rate(x[model.block("base")], x[model.block("base_v")])
        integral = model.block("wheel_i")
        if integral.stop > integral.start:
            dx[integral] = base.wheel_torques(t, x[model.block("v")][base.wheels], x[integral], twist)[1] \
                if integral_rate is None else integral_rate
    return dx


# ---- the controller callback ---------------------------------------------------------------
class HeldTorque:
    """A Python controller's torque, recomputed at each control tick (t = k period) and held
    in between (zero-order hold, clipped to the effort limits)."""

    def __init__(self, model: SimModel, t: float, x: np.ndarray) -> None:
        self.model, self.period = model, model.control.period
        self.value = self._ask(t, x)
        self.next = (math.floor(t / self.period + 1e-9) + 1) * self.period
        self.applied: dict[float, np.ndarray] = {t: self.value}

    def _ask(self, t: float, x: np.ndarray) -> np.ndarray:
        tau = self.model.control.callback(t, x[self.model.block("q")].copy(), x[self.model.block("v")].copy())
        return self.model.clipped(tau)

    def ticks(self, t_end: float) -> np.ndarray:
        """The control ticks from the next one to before ``t_end`` (s)."""
        return np.arange(self.next, t_end - 1e-9 * self.period, self.period)

    def at_output(self, t: float, x: np.ndarray) -> None:
        """At an output time: a new torque if a tick has come; the torque applied from
        there on is recorded (``applied``, by time)."""
        if t >= self.next - 1e-9 * self.period:
            self.value = self._ask(t, x)
            self.next = (math.floor(t / self.period + 1e-9) + 1) * self.period
        self.applied[t] = self.value


# ---- solving ---------------------------------------------------------------------------------
def _monitor(model: SimModel, state: SimState, command: np.ndarray | None, energy0: float | None,
             configuration: Callable[[np.ndarray], np.ndarray]) -> Monitor | None:
    """The output-time checks: the energy ledger when the run is passive (against
    ``energy0``, J, default the state's stored energy; ``configuration(x)``: the plant
    configuration of an output state) and the pairs' penetration limits (the constraint
    stepper holds every step to the smallest of them itself)."""
    data = state.data
    ledger = None
    if model.is_passive(command):
        reference = model.stored_energy(data, state.x) if energy0 is None else energy0
        plant = model.plant
        estimate = None if model.compliant or plant.mimic or plant.model.armature.any() else \
            (lambda x: body_energy(plant, data, configuration(x), model.velocity(x)))
        ledger = energy_ledger_monitor(lambda x: model.stored_energy(data, x, configuration(x)), reference,
                                       model.integrator.energy_tolerance, estimate)
    overlap = None
    if model.contact and model.stepper is None:
        overlap = penetration_monitor(
            lambda x: model.contact.overlaps(model.geometry_poses(data, model.configuration(x))),
            model.penetration_limits)
    return all_of(ledger, overlap)


@dataclass
class _Outcome:
    solution: Solution
    events: list[ContactEvent]
    deepest: float
    touching: frozenset[str]
    held: HeldTorque | None = None
    records: dict[float, tuple] | None = None
    torques: dict[float, np.ndarray] | None = None  # ConstraintStepping.torques
    #: whether the solution's states are the outputs already (charts folded, nothing imposed)
    folded: bool = False
    attitude_events: dict[str, int] = dataclasses.field(default_factory=dict)
    quaternion_drift: float | None = None


def right_hand_side(model: SimModel, data, reference, command: np.ndarray | None = None,
                    held: HeldTorque | None = None) -> tuple[Callable[[float, np.ndarray], TorqueAndRate], Callable]:
    """(torque(t, x), rhs(t, x)): the robot's applied torque (N m) with a moving base's PI integral
    rate from the same call (:func:`controlled_torque`; None: the base asked) and dx/dt, under a
    held ``command``, a Python controller's ``held`` torque or the scene's controller tracking
    ``reference``; each chosen once here, so the integrators' calls take the shortest path (a robot
    alone: the controller and one ABA with friction, fused under computed torque: SimModel's)."""
    if held is not None:
        def applied(t: float, x: np.ndarray) -> np.ndarray:
            return held.value
    elif command is not None:
        def applied(t: float, x: np.ndarray) -> np.ndarray:
            return command
    elif model.base is None:
        controller, q_block, v_block = model.control.controller, model.slices["q"], model.slices["v"]

        def applied(t: float, x: np.ndarray) -> np.ndarray:
            return controller.torque(t, x[q_block], x[v_block], reference)
    else:
        def rhs(t: float, x: np.ndarray) -> np.ndarray:
            tau, rate = controlled_torque(model, reference, t, x)
            return derivative(model, data, x, tau, t, reference.base_twist, rate)
        return functools.partial(controlled_torque, model, reference), rhs

    def torque(t: float, x: np.ndarray) -> TorqueAndRate:
        return applied(t, x), None

    if model.robot_alone:
        robot_derivative = model.robot_derivative

        def rhs(t: float, x: np.ndarray) -> np.ndarray:
            return robot_derivative(data, x, applied(t, x))

        if held is None and command is None:
            rhs = model.computed_torque_derivative(data, reference, rhs) or rhs
        loop = None if held is not None else model.compiled_steps(command)
        if loop is not None:     # the fixed-step integrators run it (integrate/fixed_step.py)
            rhs.compiled_steps = loop
    else:
        def rhs(t: float, x: np.ndarray) -> np.ndarray:
            return derivative(model, data, x, applied(t, x), t, reference.base_twist)
    return torque, rhs


def _solve(model: SimModel, state: SimState, t_eval: np.ndarray, command: np.ndarray | None,
           max_steps: int | None, progress: Progress | None, energy0: float | None, record: bool = False) -> _Outcome:
    """Integrate from the state over t_eval (its first time is the state's) with the checks."""
    data = state.data
    x0 = model.recentred(state.x)
    held = HeldTorque(model, state.t, x0) if model.control.callback is not None and command is None else None
    grid = t_eval if held is None else np.union1d(t_eval, held.ticks(t_eval[-1]))

    def checks(configuration: Callable[[np.ndarray], np.ndarray] = model.configuration) -> Monitor | None:
        """The output-time checks (:func:`_monitor`), after a Python controller's tick."""
        monitor = _monitor(model, state, command, energy0, configuration)
        if held is None:
            return monitor

        def ticked(t: float, x: np.ndarray) -> str | None:
            held.at_output(t, x)
            return monitor(t, x) if monitor is not None else None
        return ticked

    reference = state.reference
    torque, rhs = right_hand_side(model, data, reference, command, held)
    outcome = _integrate(model, state, x0, grid, rhs, torque, checks, max_steps, progress, record)
    outcome.held = held
    s = outcome.solution
    keep = np.searchsorted(s.t, t_eval) if grid is not t_eval else slice(None)
    outcome.quaternion_drift = model.quaternion_drift(s.x[keep])
    # outputs with every chart folded into its pose: the pose block is the body's pose
    outputs = s.x[keep] if outcome.folded else np.array([
        model.imposed(model.recentred(x), model.base_motion(t, reference.base_twist))
        for t, x in zip(s.t[keep], s.x[keep])])
    outcome.solution = Solution(s.t[keep], outputs, s.stats, s.state_names)
    return outcome


def _integrate(model: SimModel, state: SimState, x0: np.ndarray, t_eval: np.ndarray, rhs, torque,
               checks: Callable[..., Monitor | None], max_steps: int | None, progress: Progress | None,
               record: bool = False) -> _Outcome:
    spec, names = model.integrator, model.layout.names
    kind = integrator_kind(spec.method)
    if kind == "stepper":
        return _step_constraints(model, state, x0, t_eval, torque, checks, max_steps, progress, record)
    options = {"rtol": spec.rtol, "atol": spec.absolute_tolerance(x0), "state_names": names,
               "bounds": model.bounds, "monitor": checks(), "max_steps": max_steps, "progress": progress}
    if model.contact:
        guards = ContactGuards(model, state.data)
        if spec.dt is not None:
            options.update(dt=spec.dt, n_positions=model.nv or None)
        elif spec.method != "ida" and model.impulsive:
            options["max_step"] = _shortest_flight(model)
        hybrid = simulate_hybrid([Mode(MODE, rhs, guards.transitions())], MODE, x0, t_eval, spec.method, **options)
        keep = np.searchsorted(hybrid.t, t_eval, side="right") - 1  # the last sample at each t
        events, deepest = guards.contact_events(hybrid.switches)
        return _Outcome(Solution(hybrid.t[keep], hybrid.x[keep], hybrid.stats, hybrid.state_names), events,
                        deepest, state.touching, attitude_events=guards.attitude_events(hybrid.switches))
    if kind == "dae":
        def residual(t: float, y: np.ndarray, yp: np.ndarray) -> np.ndarray:
            return yp - rhs(t, y)

        solution = integrate_dae(residual, x0, rhs(t_eval[0], x0), t_eval, algebraic=[False] * x0.size, **options)
    else:
        solution = integrate(rhs, x0, t_eval, spec.method, dt=spec.dt, n_positions=model.nv, **options)
    return _Outcome(solution, [], 0.0, state.touching)


def _shortest_flight(model: SimModel) -> float:
    """Duration (s) of the shortest ballistic hop an impulsive pair accepts, 2 e v_rest / g
    (e at least 0.05): the step-size cap of adaptive integrators, so that a step never spans
    a whole hop (its impact would go unseen)."""
    gravity = max(float(np.linalg.norm(model.scene.gravity)), 1e-9)
    laws = [model.contact.pairs[k].law for k in model.impulsive]
    return min(2.0 * max(law.restitution, 0.05) * law.rest_speed / gravity for law in laws)


def _step_constraints(model: SimModel, state: SimState, x0: np.ndarray, t_eval: np.ndarray, torque,
                      checks: Callable[..., Monitor | None], max_steps: int | None, progress: Progress | None,
                      record: bool = False) -> _Outcome:
    """The constraint stepper over t_eval; its states are the outputs (``folded``), checked
    with the plant configurations it kept (:meth:`ConstraintStepping.output_configuration`)."""
    start = time.perf_counter()
    z = model.block("z")
    if z.stop > z.start:
        raise UserInputError(f"{model.scene.source}: the constraint stepper does not integrate LuGre bristles")
    checked_fixed_step(model.integrator.method, model.integrator.dt, t_eval, max_steps)
    stepping = ConstraintStepping(model, dataclasses.replace(state, x=x0), torque,
                                  min(model.penetration_limits.values(), default=math.inf), record)
    check = StateCheck(model.integrator.method, model.layout.names, model.bounds,
                       checks(stepping.output_configuration))
    solution = drive(stepping, model.integrator.method, t_eval, [], check, model.layout.names,
                     max_steps=max_steps, progress=progress)
    solution.stats.events = len(stepping.events)
    solution.stats.wall_time = time.perf_counter() - start
    return _Outcome(solution, stepping.events, stepping.deepest, stepping.touching, records=stepping.records,
                    torques=stepping.torques, folded=True)


# ---- public entry points ---------------------------------------------------------------------
def advance(model: SimModel, state: SimState, times: Sequence[float] | np.ndarray,
            command=None, sensors: bool = False) -> list[Snapshot]:
    """Move ``state`` on (in place) to each of ``times`` (s, increasing, after state.t) in
    ONE integrator run, returning a Snapshot at each; ``command`` (sequence in joint order or
    mapping by joint name, N m; clipped to the effort limits) replaces the controller over
    all of them (zero-order hold). The energy ledger of a passive scene spans the whole
    passive stretch (since the reset or the last command that fed energy in), not one call.
    ``sensors``: each snapshot carries its sensor readings (:func:`snapshot`)."""
    times = np.asarray(times, dtype=float).reshape(-1)
    if not times.size or not times[0] > state.t or np.any(np.diff(times) <= 0.0):
        raise UserInputError(f"advance: times {times.tolist()} s must increase from after the "
                             f"current time {state.t:.9g} s")
    command = None if command is None else model.clipped(command)
    if not model.is_passive(command):
        state.ledger_start = None
    elif state.ledger_start is None:
        state.ledger_start = model.stored_energy(state.data, state.x)
    outcome = _solve(model, state, np.concatenate([[state.t], times]), command,
                     model.limits.max_steps_per_call, None, state.ledger_start, sensors)
    _record(state, outcome)
    snapshots = []
    for t, x in zip(outcome.solution.t[1:], outcome.solution.x[1:]):
        state.t, state.x = float(t), x.copy()
        state.tau = _output_torque(model, state, outcome, command)
        snapshots.append(snapshot(model, state, sensors, outcome.records and outcome.records.get(state.t)))
    return snapshots


def _output_torque(model: SimModel, state: SimState, outcome: _Outcome, command: np.ndarray | None) -> np.ndarray:
    """The robot's applied torque (N m, a new array) at ``state``, an output of ``outcome``: a
    Python controller's held torque, the constraint stepper's for its step from there (the
    same call on the same numbers), else :func:`robot_torque`."""
    kept = None if outcome.torques is None or outcome.held is not None else outcome.torques.get(state.t)
    return kept if kept is not None else np.array(outcome.held.value if outcome.held is not None else
                                                  robot_torque(model, state.reference, state.t, state.x, command),
                                                  dtype=float)


def _record(state: SimState, outcome: _Outcome) -> None:
    state.stats += outcome.solution.stats
    state.events += outcome.events
    state.deepest = max(state.deepest, outcome.deepest)
    state.touching = outcome.touching


def run(model: SimModel, state0: SimState | None = None, t_eval: np.ndarray | None = None,
        progress: Progress | None = None) -> SimulationResult:
    """The scene from ``state0`` (default: its initial state; not changed) over ``t_eval``
    (default: the scene's output times from state0's time). A fixed step larger than the
    output spacing is refused; at most ``limits.max_steps`` steps; ``progress(t)`` is told
    the time reached (s) after each output."""
    scene = model.scene
    state = initial_state(model) if state0 is None else state0.copy()
    state.events, state.deepest, state.touching = [], 0.0, frozenset()
    times = scene.output_times + state.t if t_eval is None else np.asarray(t_eval, dtype=float)
    checked_output_spacing(model.integrator.dt, times, f"{scene.source}: integrator.dt "
                           f"(outputs.rate {scene.outputs.rate:g} Hz)")
    x0 = state.x.copy()
    outcome = _solve(model, state, times, None, model.limits.max_steps, progress, None)
    solution = outcome.solution
    wanted = set(scene.outputs.record) | ({"energy"} if model.conservative else set())
    series = _series(model, state, solution, wanted, outcome.held)
    energy_error = float(np.max(np.abs(series["energy"] - series["energy"][0]))) if model.conservative else None
    dissipated = None
    if model.passive and model.control.callback is None:
        dissipated = model.stored_energy(state.data, x0) - model.stored_energy(state.data, solution.x[-1])
    return SimulationResult(scene.name, model.integrator, model.layout, solution.t, solution.x, series,
                            solution.stats, model.conservative, energy_error, outcome.events,
                            outcome.deepest if model.contact else None, dissipated, outcome.attitude_events,
                            outcome.quaternion_drift)


def _series(model: SimModel, state: SimState, solution: Solution, wanted: set[str],
            held: HeldTorque | None) -> dict[str, np.ndarray]:
    """The recorded extras at the outputs: ``tau`` (the Python controller's held torque, or
    the scene controller's), ``energy``, ``ee_position``."""
    series, data = {}, state.data
    if "tau" in wanted:
        series["tau"] = np.array([held.applied[t] if held is not None else
                                  robot_torque(model, state.reference, t, x, None)
                                  for t, x in zip(solution.t.tolist(), solution.x)])
    if "energy" in wanted:
        series["energy"] = np.array([model.energy(data, x) for x in solution.x])
    if "ee_position" in wanted:
        series["ee_position"] = np.array([model.ee_pose(data, x)[:3, 3] for x in solution.x])
    return series


def snapshot(model: SimModel, state: SimState, sensors: bool = False, step: tuple | None = None) -> Snapshot:
    """The state's instant as a Snapshot (its end effector's pose on demand). A kinematic base's
    wheels report the torque that imposes their motion (:meth:`SimModel.applied_torque`). ``sensors``:
    with the readings, from the constraint ``step`` that ended here ((report, plant accelerations,
    h)) or, without one, from the accelerations and compliant contact forces at the state."""
    x, data, q = state.x, state.data, model.configuration(state.x)     # q: once for the readings, energy, bodies
    tau, readings = np.array(state.tau), None
    if sensors or (model.base is not None and not model.base.dynamic):
        twist = state.reference.base_twist
        a = step[1] if step is not None else derivative(model, data, x, tau, state.t, twist)[model.velocity_block]
        tau = model.applied_torque(data, x, tau, a)
        if sensors:
            forces = contact_forces(model.contact, step[0], step[2]) if step is not None else \
                model.compliant_point_forces(data, x)
            readings = model.sensors.read(data, q, model.velocity(x), a, forces)
    return Snapshot(state.t, model.joint_names, x[model.block("q")].copy(), x[model.block("v")].copy(),
                    x[model.block("z")].copy(), tau, model.energy(data, x, q), (model, x.copy()),
                    model.body_poses(data, x, q),
                    None if model.base is None else np.concatenate([x[model.block("base")], x[model.block("base_v")]]),
                    readings)
