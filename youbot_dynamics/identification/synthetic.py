"""Synthetic data for identification round trips: a perturbed URDF and a bag of the
/joint_states a robot would record along a trajectory.

"Recording" is the inverse dynamics of the robot (Pinocchio's RNEA plus the simulator's
friction law, :func:`~youbot_dynamics.dynamics.rigid_body.inverse_dynamics`) along the
trajectory's exact q, qd, qdd, with Gaussian noise added to every effort: the torques a
perfectly tracking controller would apply, as a torque sensor with that noise would report.
"""
from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np
from lxml import etree

from youbot_dynamics.dynamics.friction import JointFriction
from youbot_dynamics.dynamics.rigid_body import inverse_dynamics
from youbot_dynamics.identification.excitation import FourierTrajectory
from youbot_dynamics.io import messages
from youbot_dynamics.io.mcap_log import McapLogger
from youbot_dynamics.model.robot import Robot, keep_joints


def perturbed_urdf(path: str | Path, joints: Sequence[str], rng: np.random.Generator, *,
                   mass: float = 0.2, com_shift: float = 0.01, inertia: tuple[float, float] = (0.7, 1.3),
                   friction: tuple[float, float] = (0.2, 0.8)) -> str:
    """The URDF at ``path`` with every inertial perturbed: mass x U(1 - mass, 1 + mass),
    centre of mass moved ``com_shift`` m in a random direction, inertia tensor x U(inertia);
    ``joints``' damping (N m s/rad) and Coulomb friction (N m) drawn from U(friction)."""
    tree = etree.parse(str(path))
    for inertial in tree.iter("inertial"):
        element = inertial.find("mass")
        element.set("value", str(float(element.get("value")) * rng.uniform(1 - mass, 1 + mass)))
        origin = inertial.find("origin")
        shift = rng.standard_normal(3)
        xyz = np.array(origin.get("xyz").split(), float) + com_shift * shift / np.linalg.norm(shift)
        origin.set("xyz", " ".join(str(float(x)) for x in xyz))
        element, scale = inertial.find("inertia"), rng.uniform(*inertia)
        for key in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"):
            element.set(key, str(float(element.get(key)) * scale))
    for joint in tree.iter("joint"):
        if joint.get("name") in joints:
            joint.find("dynamics").set("damping", str(rng.uniform(*friction)))
            joint.find("dynamics").set("friction", str(rng.uniform(*friction)))
    return etree.tostring(tree, encoding="unicode")


def record_joint_states(path: str | Path, robot: Robot, trajectory: FourierTrajectory, duration: float,
                        rate: float, noise: float, rng: np.random.Generator,
                        passengers: Sequence[str] = ()) -> None:
    """Write an MCAP bag of /joint_states at ``rate`` Hz for ``duration`` s: the
    trajectory's joints moving exactly along it (the robot's other joints locked at 0),
    efforts of ``robot`` plus N(0, noise^2) N m. ``passengers`` are extra joint names
    listed first at 0; the trajectory's joints follow in reverse order, so readers must
    match by name."""
    moving = keep_joints(robot, list(trajectory.joint_names))
    friction, data = JointFriction.from_urdf(moving), moving.model.createData()
    t_ns = np.rint(np.arange(int(round(duration * rate))) * 1e9 / rate).astype(np.int64)
    q, v, a = trajectory.evaluate(t_ns * 1e-9)
    names, zeros = [*passengers, *reversed(moving.joint_names)], [0.0] * len(passengers)
    with McapLogger(path) as log:
        log.add_topic("/joint_states", "sensor_msgs/msg/JointState")
        for k, stamp in enumerate(t_ns):
            tau = inverse_dynamics(moving, data, q[k], v[k], a[k], friction) + rng.normal(0.0, noise, moving.nv)
            log.write("/joint_states", messages.joint_state(int(stamp), names, [*zeros, *q[k][::-1]],
                                                            [*zeros, *v[k][::-1]], [*zeros, *tau[::-1]]),
                      log_time_ns=int(stamp))
