"""A convenience wrapper that keeps one compiled scene and one state together.

``Simulator(scene)`` is :func:`~youbot_dynamics.sim.build.compile` plus a
:class:`~youbot_dynamics.sim.state.SimState`; its methods call the engine's free functions
(:mod:`youbot_dynamics.sim.engine`):

- ``run()`` -> :class:`~youbot_dynamics.sim.engine.SimulationResult`: the whole scene from
  its initial state; afterwards the wrapper's state is the run's end.
- Step-wise, for a ROS node or any outer loop: ``reset()``, then ``advance(t_next,
  tau_command=None)`` -> Snapshot (or ``advance_through(times, ...)``, one per time, from one
  integrator run); ``tau_command`` (joint order or by name, N m) replaces the controller until
  the next call (zero-order hold, clipped to the effort limits). ``state`` is the public
  SimState (t, x, reference, tau, events, deepest, stats); ``get_state()`` / ``set_state()``
  save and restore it.
"""
from __future__ import annotations

from typing import Callable, Mapping, Sequence

import numpy as np

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.scene.schema import IntegratorSpec, Scene
from youbot_dynamics.sim import engine
from youbot_dynamics.sim.build import compile
from youbot_dynamics.sim.controllers import ControllerCallback
from youbot_dynamics.sim.divergence import DivergenceLimits
from youbot_dynamics.sim.engine import SimulationResult, Snapshot
from youbot_dynamics.sim.model import SimModel
from youbot_dynamics.sim.state import SimState

#: A torque command: a sequence in joint order or a mapping by joint name (N m, N).
TorqueCommand = Sequence[float] | np.ndarray | Mapping[str, float]

__all__ = ["Simulator", "Snapshot", "SimulationResult", "TorqueCommand"]


class Simulator:
    """A SimModel and its SimState."""

    def __init__(self, scene: Scene, integrator: IntegratorSpec | None = None,
                 limits: DivergenceLimits | None = None, controller: ControllerCallback | None = None,
                 control_rate: float | None = None) -> None:
        self.model: SimModel = compile(scene, integrator, limits, controller, control_rate)
        self.state: SimState = engine.initial_state(self.model)
        self._rhs: tuple[SimState | None, object, Callable | None] = (None, None, None)

    # ---- the model ----------------------------------------------------------------------
    @property
    def scene(self) -> Scene:
        return self.model.scene

    @property
    def integrator(self) -> IntegratorSpec:
        return self.model.integrator

    @property
    def robot(self):
        return self.model.robot

    @property
    def layout(self):
        return self.model.layout

    @property
    def friction(self):
        return self.model.friction

    @property
    def controller(self):
        return self.model.control.controller

    @property
    def conservative(self) -> bool:
        return self.model.conservative

    @property
    def trajectory(self):
        """The scene's trajectory (None without one)."""
        return self.model.control.reference.trajectory

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The moving joints, in the order of q, v and tau."""
        return self.model.joint_names

    @property
    def state_dim(self) -> int:
        """Dimension of the continuous state x."""
        return self.model.layout.size

    def initial_state(self) -> np.ndarray:
        """x0 from the scene."""
        return engine.initial_state(self.model).x

    def rhs(self, t: float, x: np.ndarray) -> np.ndarray:
        """dx/dt with the scene's controller: what the integrators call (the engine's
        :func:`~youbot_dynamics.sim.engine.right_hand_side`, built once per state)."""
        state, (built_for, reference, rhs) = self.state, self._rhs
        if built_for is not state or reference is not state.reference:
            rhs = engine.right_hand_side(self.model, state.data, state.reference)[1]
            self._rhs = (state, state.reference, rhs)
        return rhs(t, x)

    def rhs_cost(self) -> dict[str, int | str]:
        """What one rhs evaluation computes, by count: the state dimension, the plant's
        degrees of freedom and bodies (ABA is O(nv) over them), the friction laws evaluated
        and the controller's extra rigid-body pass (RNEA or gravity: O(nv))."""
        model, kind = self.model, self.model.control.controller.kind
        laws = () if model.friction is None else sorted(set(model.friction.laws))
        z = model.block("z")
        return {"state_dim": model.layout.size, "nv": model.plant.model.nv, "bodies": model.plant.model.nbodies,
                "lugre_states": z.stop - z.start, "friction_laws": ",".join(laws) or "none",
                "controller": kind, "rigid_body_passes": 1 + (kind != "none"),
                "free_bodies": len(model.body_names), "contact_pairs": len(model.scene.contacts)}

    def energy_of(self, x: np.ndarray) -> float:
        """Kinetic plus potential energy (J) of state x."""
        return self.model.energy(self.state.data, x)

    def ee_pose_of(self, q: np.ndarray) -> np.ndarray:
        """4x4 pose of the end-effector link in the root frame at joint positions q (no
        free bodies in the way: the plant's leading joints are the robot's)."""
        x = self.state.x.copy()
        x[self.model.block("q")] = q
        return self.model.ee_pose(self.state.data, x)

    def body_in_link(self, result: SimulationResult, body: str, link: str) -> np.ndarray:
        """(k, 3) positions (m) of free body ``body``'s centre of mass in the frame of robot
        link ``link`` at the result's output times: constant while the link holds the body
        rigidly (a grasp that does not slip)."""
        names = self.model.body_names
        if body not in names:
            raise UserInputError(f"{self.scene.source}: no free body {body!r} (free_bodies: "
                                 f"{', '.join(names) or 'none'})")
        positions = self.model.body_motion(result.x)["position"][:, names.index(body)]
        frame = self.robot.frame_id(link)
        out = np.empty_like(positions)
        data = self.state.data
        for k, (x, p) in enumerate(zip(result.x, positions)):
            self.model.ee_pose(data, x)  # places every frame of the plant
            out[k] = data.oMf[frame].actInv(p)
        return out

    def clipped(self, tau: TorqueCommand) -> np.ndarray:
        """A torque command in joint order, clipped to the effort limits."""
        return self.model.clipped(tau)

    # ---- runs ---------------------------------------------------------------------------
    def run(self, t_eval: np.ndarray | None = None, progress: Callable[[float], None] | None = None) -> SimulationResult:
        """The scene from its initial state over ``t_eval`` (default: the scene's output
        times); the wrapper's state is then the run's end."""
        result = engine.run(self.model, None, t_eval, progress)
        t, x, reference = float(result.t[-1]), result.x[-1].copy(), self.model.control.reference
        self.state = SimState(t, x, reference, engine.robot_torque(self.model, reference, t, x, None),
                              self.state.data, result.stats, list(result.contact_events),
                              result.max_penetration or 0.0)  # Pinocchio's scratch space kept
        return result

    # ---- step-wise API ------------------------------------------------------------------
    def get_state(self) -> SimState:
        """A copy of the current state."""
        return self.state.copy()

    def set_state(self, state: SimState) -> None:
        """Continue from a saved state (a copy is kept)."""
        self.state = state.copy()

    def reset(self, q: np.ndarray | None = None, v: np.ndarray | None = None) -> Snapshot:
        """Back to t = 0 at the scene's initial state (or the given q, v in joint order),
        with the scene's reference and an empty contact record."""
        self.state = engine.initial_state(self.model, q, v)
        return self.snapshot()

    def advance(self, t_next: float, tau_command: TorqueCommand | None = None) -> Snapshot:
        """Integrate from the current time to ``t_next`` (s)."""
        return self.advance_through([t_next], tau_command)[-1]

    def advance_through(self, times: Sequence[float] | np.ndarray,
                        tau_command: TorqueCommand | None = None, sensors: bool = False) -> list[Snapshot]:
        """A snapshot at each of ``times`` (s, increasing, after the current time) from ONE
        integrator run; ``tau_command`` is held over all of them; ``sensors``: with the
        sensor readings (:mod:`youbot_dynamics.sim.sensors`)."""
        return engine.advance(self.model, self.state, times, tau_command, sensors)

    @property
    def t(self) -> float:
        return self.state.t

    @property
    def x(self) -> np.ndarray:
        return self.state.x

    @property
    def stats(self):
        return self.state.stats

    @property
    def events(self):
        """The contact events since the last reset or run."""
        return self.state.events

    @property
    def q(self) -> np.ndarray:
        """Joint positions (rad, m) at the current time."""
        return self.state.x[self.model.block("q")].copy()

    @property
    def v(self) -> np.ndarray:
        """Joint velocities (rad/s, m/s) at the current time."""
        return self.state.x[self.model.block("v")].copy()

    @property
    def z(self) -> np.ndarray:
        """LuGre bristle deflections (rad, m; empty without LuGre joints)."""
        return self.state.x[self.model.block("z")].copy()

    @property
    def tau(self) -> np.ndarray:
        """The joint torque applied at the current time (N m, N)."""
        return np.array(self.state.tau)

    @property
    def energy(self) -> float:
        """Kinetic plus potential energy (J) at the current time."""
        return self.energy_of(self.state.x)

    @property
    def ee_pose(self) -> np.ndarray:
        """4x4 end-effector pose (m) in the root frame at the current time."""
        return self.model.ee_pose(self.state.data, self.state.x)

    def snapshot(self, sensors: bool = False) -> Snapshot:
        """The current instant (``sensors``: with the sensor readings at the state)."""
        return engine.snapshot(self.model, self.state, sensors)
