"""What the engine returns: a :class:`Snapshot` of the simulation at one instant and the
:class:`SimulationResult` of a whole run (youbot_dynamics.sim.engine builds both)."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from youbot_dynamics.integrate.integrators import IntegratorStats
from youbot_dynamics.scene.schema import IntegratorSpec
from youbot_dynamics.sim.model import SimModel
from youbot_dynamics.sim.sensors import Readings
from youbot_dynamics.sim.state import ContactEvent, StateLayout


@dataclass(frozen=True)
class Snapshot:
    """The simulation at one instant: t (s), q (rad, m), v (rad/s, m/s), z (LuGre bristle
    deflections), tau (applied joint torque, N m or N), energy (kinetic + potential, J) and
    ee_pose (4x4 homogeneous pose of the end-effector link in the robot's root frame, m;
    the first robot's for composed robots, ``Robot.end_effectors``; computed when read, from ``kinematics`` = (model, x));
    bodies: the world pose (4x4, m) of each free body by name, in the scene's order;
    base: a moving base's (x, y, yaw, vx, vy, wz) (world pose in m and rad, body-frame twist
    in m/s and rad/s), None for a fixed base; sensors: what the scene's sensors read
    (:mod:`youbot_dynamics.sim.sensors`), when :func:`advance` was asked for them."""

    t: float
    joint_names: tuple[str, ...]
    q: np.ndarray
    v: np.ndarray
    z: np.ndarray
    tau: np.ndarray
    energy: float
    kinematics: tuple[SimModel, np.ndarray] = dataclasses.field(repr=False, compare=False)
    bodies: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)
    base: np.ndarray | None = None
    sensors: Readings | None = None

    @property
    def ee_pose(self) -> np.ndarray:
        return self.kinematics[0].ee_pose(self.kinematics[0].plant.model.createData(), self.kinematics[1])


@dataclass
class SimulationResult:
    """A run: states x (k, n) at times t (k,), named by ``layout``; ``series`` holds the
    recorded extras (``tau`` (k, nv), ``energy`` (k,), ``ee_position`` (k, 3)); ``stats``
    the integrator's statistics. ``energy_error`` (J) is max |E(t) - E(0)| in a conservative
    scene, None otherwise (friction or a controller change the energy). ``energy_dissipated``
    (J) is the ledger of a passive scene, E(0) - E(end) of the stored energy (kinetic,
    potential, contact springs): what friction, damping and contact hysteresis took, >= 0
    up to the tolerance; None when a controller acts. A contact scene adds its
    ``contact_events`` and ``max_penetration`` (m: the deepest overlap at the located
    maximum compressions of the compliant law, or over the constraint stepper's steps).
    Free bodies add ``attitude_events`` (how many chart folds, ``recentre``, and Cardan
    sequence switches, ``sequence``, the run took) and, for bodies in quaternion
    coordinates, ``quaternion_drift`` (max ||q| - 1| at the outputs before their
    renormalisation)."""

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
    attitude_events: dict[str, int] = dataclasses.field(default_factory=dict)
    quaternion_drift: float | None = None
    error_estimate: object | None = None   # its ErrorEstimate, from sim/companion.py's run (else None)

    @property
    def final_state(self) -> dict[str, float]:
        """The last state by component name (``q[arm_joint_1]`` ...)."""
        return dict(zip(self.layout.names, map(float, self.x[-1])))

    def columns(self, record: Sequence[str]) -> tuple[list[str], np.ndarray]:
        """Column names and the (k, m) table of t and the recorded quantities."""
        names, blocks = ["t"], [self.t[:, None]]
        for item in record:
            if item in ("q", "v", "z", "base", "base_v"):
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
