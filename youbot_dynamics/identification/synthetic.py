"""Synthetic data for identification round trips: a perturbed URDF and bags of the
/joint_states a robot records along an excitation trajectory, made in one of two ways.

- Through the simulator (:func:`simulate_excitation`): the dynamics node's simulation
  session runs the scene config/scenes/identification.yaml with the robot to identify
  (:func:`excitation_scene`); the excitation arrives as a /joint_trajectory (its samples,
  positions and velocities, the controller interpolating between them) and the
  computed-torque controller tracks it; the node's own MCAP log is the bag. Its efforts are
  the applied (clipped) torques, exact; :func:`add_effort_noise` then writes a copy of the
  bag's /joint_states with Gaussian noise on the efforts, as a torque sensor would report.
- By inverse dynamics (:func:`record_joint_states`): Pinocchio's RNEA plus the simulator's
  friction law over all samples at once
  (:func:`~youbot_dynamics.dynamics.rigid_body.inverse_dynamics_batch`) along the
  trajectory's exact q, qd, qdd, with the noise added to every effort: the torques a
  perfectly tracking controller would apply. Fast, and independent of the simulator.
"""
from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np
from lxml import etree

import yaml

from youbot_dynamics.dynamics.friction import JointFriction
from youbot_dynamics.dynamics.rigid_body import inverse_dynamics_batch
from youbot_dynamics.identification.excitation import FourierTrajectory, message_rate
from youbot_dynamics.io import messages
from youbot_dynamics.io.bag_reader import read_bag
from youbot_dynamics.io.cdr_template import Refilled
from youbot_dynamics.io.mcap_log import McapLogger
from youbot_dynamics.io.stamps import NS_PER_S, stamp_ns_of
from youbot_dynamics.model.robot import Robot, keep_joints
from youbot_dynamics.scene.schema import Scene, load_scene, scene_dir

#: The scene that records an excitation (computed torque, URDF friction, at rest until a
#: /joint_trajectory arrives).
EXCITATION_SCENE = "identification"


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
    t_ns = np.rint(np.arange(int(round(duration * rate))) * 1e9 / rate).astype(np.int64)
    q, v, a = trajectory.evaluate(t_ns * 1e-9)
    tau = inverse_dynamics_batch(moving, q, v, a, JointFriction.from_urdf(moving)) + \
        rng.normal(0.0, noise, (len(t_ns), moving.nv))
    names, zeros = [*passengers, *reversed(moving.joint_names)], np.zeros((len(t_ns), len(passengers)))
    values = np.hstack([zeros, q[:, ::-1], zeros, v[:, ::-1], zeros, tau[:, ::-1]])
    joint_states = Refilled()
    with McapLogger(path) as log:
        log.add_topic("/joint_states", "sensor_msgs/msg/JointState")
        for stamp, row in zip(t_ns.tolist(), values):
            log.write("/joint_states", joint_states(stamp, row, lambda stamp, row: messages.joint_state(
                stamp, names, *np.split(row, 3))), log_time_ns=stamp)


def excitation_scene(robot_urdf: str | Path, trajectory: FourierTrajectory, duration: float,
                     path: str | Path) -> Scene:
    """The packaged identification scene with ``robot_urdf`` as its robot, starting at rest
    at the trajectory's first point, running ``duration`` s; written to ``path`` (YAML) and
    loaded from there."""
    document = yaml.safe_load((scene_dir() / f"{EXCITATION_SCENE}.yaml").read_text())
    q_start = trajectory.evaluate(np.zeros(1))[0][0]
    document.update(robot=str(Path(robot_urdf).resolve()), duration=float(duration),
                    initial={"q": dict(zip(trajectory.joint_names, q_start.tolist()))})
    Path(path).write_text(yaml.safe_dump(document, sort_keys=False))
    return load_scene(path)


def trajectory_points(trajectory: FourierTrajectory, duration: float) -> list[tuple[int, list, list]]:
    """The trajectory over [0, duration] s as /joint_trajectory points (time_from_start in
    ns, positions, velocities), as densely as one message allows (:func:`message_rate`)."""
    rate = message_rate(duration)
    t_ns = np.rint(np.arange(int(duration * rate) + 1) * NS_PER_S / rate).astype(np.int64)
    q, v, _ = trajectory.evaluate(t_ns / NS_PER_S)
    return [(int(t), q[k].tolist(), v[k].tolist()) for k, t in enumerate(t_ns)]


def simulate_excitation(scene: Scene, trajectory: FourierTrajectory, rate: float, bag: str | Path) -> dict:
    """Run ``scene`` in the dynamics node's simulation session at ``rate`` Hz for its
    duration, the trajectory sent at t = 0 as a /joint_trajectory (:func:`trajectory_points`),
    the node logging to the MCAP ``bag``; returns the integrator statistics."""
    from youbot_dynamics.node.simulate import SimulationSession  # the node's session, no rclpy

    with SimulationSession(scene, rate, mcap_path=bag) as session:
        session.step()
        session.trajectory(list(trajectory.joint_names), trajectory_points(trajectory, scene.duration), 0)
        for _ in range(int(round(scene.duration * rate))):
            session.step()
        if session.failure:
            raise RuntimeError(f"simulating {scene.source}: {session.failure}")
        return session.simulator.stats.as_dict()


def add_effort_noise(source: str | Path, destination: str | Path, joints: Sequence[str], noise: float,
                     rng: np.random.Generator, topic: str = "/joint_states") -> None:
    """Copy ``topic`` (sensor_msgs/JointState) of the bag ``source`` to the MCAP
    ``destination`` with N(0, noise^2) (N m) added to the efforts of ``joints`` (the others
    copied as they are): a torque sensor's noise on the node's exact applied torques."""
    with McapLogger(destination) as log:
        log.add_topic(topic, "sensor_msgs/msg/JointState")
        for record in read_bag(source):
            if record.topic != topic:
                continue
            message = record.message
            names = list(message.name)
            effort = np.array(message.effort, float)
            noisy = np.isin(names, list(joints))
            effort[noisy] += rng.normal(0.0, noise, int(noisy.sum()))
            log.write(topic, messages.joint_state(stamp_ns_of(message.header.stamp), names, message.position,
                                                  message.velocity, effort), log_time_ns=record.log_time_ns)
