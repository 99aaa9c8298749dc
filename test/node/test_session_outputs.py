"""Outputs built only when consumed (issue 14): a session builds the messages of the topics
subscribed (``consumed_by``, the node's publishers' subscriber counts) or recorded in its
MCAP and no others, skips the kinematics pass when nothing takes it, and the messages
refilled after the first sample (io/cdr_template.py) carry the same numbers as a fresh
Pinocchio pass over the published joint positions."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from rosbags.highlevel import AnyReader

from youbot_dynamics.dynamics.mobile.mecanum import base_twist
from youbot_dynamics.dynamics.mobile.odometry import odometry_step
from youbot_dynamics.node import frames
from youbot_dynamics.node.simulate import SimulationSession
from youbot_dynamics.scene.schema import load_scene

SCENE = load_scene("gripping")
RATE = 500.0


@pytest.fixture
def kinematics_passes(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """Counts kinematics passes (LinkFrames.at_many calls: one per batch of samples)."""
    calls: list[int] = []
    original = frames.LinkFrames.at_many
    monkeypatch.setattr(frames.LinkFrames, "at_many", lambda self, q: calls.append(1) or original(self, q))
    return calls


def test_only_subscribed_topics_are_built(kinematics_passes: list[int]) -> None:
    with SimulationSession(SCENE, RATE) as session:
        everything = {topic for topic, _ in session.step()}
        assert everything == set(session.topics) - {"/diagnostics"} and len(kinematics_passes) == 1
        session.consumed_by(set())
        assert [session.step() for _ in range(5)] == [[]] * 5 and session.k == 5
        assert len(kinematics_passes) == 1                 # nothing wanted /tf or /ee_pose
        session.consumed_by({"/joint_states", "/free_bodies"})
        assert [topic for topic, _ in session.step()] == ["/joint_states", "/free_bodies"]
        assert len(kinematics_passes) == 1
        session.consumed_by({"/ee_pose"})
        assert [topic for topic, _ in session.step()] == ["/ee_pose"] and len(kinematics_passes) == 2


def test_the_logs_want_every_topic_they_record(tmp_path) -> None:
    path = tmp_path / "run.mcap"
    with SimulationSession(SCENE, RATE, mcap_path=path) as session:
        session.consumed_by(set())                         # no subscriber: the MCAP still records all
        built = [[topic for topic, _ in session.step()] for _ in range(4)]
    assert all(set(topics) == set(session.topics) - {"/diagnostics"} for topics in built)
    with AnyReader([path]) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
    assert all(counts[topic] == 4 for topic in built[0])


def test_refilled_samples_match_a_fresh_kinematics_pass() -> None:
    robot = SCENE.robot
    data = robot.model.createData()
    with SimulationSession(SCENE, RATE) as session:
        samples = [dict(session.step()) for _ in range(30)]
    for sample in samples[1::7]:                           # refilled ones (the first is built)
        names, position = sample["/joint_states"].name, sample["/joint_states"].position
        q = pin.neutral(robot.model)
        for name, value in zip(names, position):
            if name in robot.joint_names:
                q[robot.model.joints[robot.model.getJointId(name)].idx_q] = value
        pin.framesForwardKinematics(robot.model, data, q)
        root = data.oMf[robot.frame_id(robot.root_link)]
        palm = root.actInv(data.oMf[robot.frame_id(session.frames.links.ee_link)])
        pose = sample["/ee_pose"].pose
        assert np.allclose([pose.position.x, pose.position.y, pose.position.z], palm.translation, atol=1e-12)
        quaternion = np.array(pin.Quaternion(palm.rotation).coeffs())          # x, y, z, w
        quaternion *= np.sign(quaternion[3])
        assert np.allclose([pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w],
                           quaternion, atol=1e-12)
        stamps = {t.header.stamp.sec * 10**9 + t.header.stamp.nanosec for t in sample["/tf"].transforms}
        assert stamps == {sample["/clock"].clock.sec * 10**9 + sample["/clock"].clock.nanosec}
        sphere = sample["/free_bodies"].poses[0].position
        marker = sample["/free_bodies_markers"].markers[0].pose.position
        assert np.allclose([marker.x, marker.y, marker.z], [sphere.x, sphere.y, sphere.z], atol=1e-12)


def _pinocchio_rows(placements: list[pin.SE3]) -> np.ndarray:
    """What the kinematics pass computed through Pinocchio's Python calls: SE3ToXYZQUAT of
    each placement, the quaternion's sign flipped to w >= 0."""
    rows = np.array([pin.SE3ToXYZQUAT(placement) for placement in placements])
    rows[rows[:, 6] < 0.0, 3:] *= -1.0
    return rows


def test_compiled_kinematics_rows_are_pinocchios_to_the_bit() -> None:
    """LinkFrames.at's compiled relative poses and quaternions against Pinocchio's actInv and
    SE3ToXYZQUAT, bit for bit, on 2000 configurations of the two youBots (random within the
    limits, rounded to 0.1 rad, all zero: every branch of the quaternion conversion); and
    pose_rows against SE3ToXYZQUAT of SE3(pose) on random rotations and half turns."""
    robot = SCENE.robot
    links = frames.LinkFrames(robot)
    data = robot.model.createData()
    rng = np.random.default_rng(7)
    for k in range(2000):
        q = rng.uniform(np.maximum(robot.lower, -4.0), np.minimum(robot.upper, 4.0))
        q = np.round(q, 1) if k % 3 == 1 else (q * 0.0 if k % 50 == 2 else q)
        sample = links.at(q)
        pin.framesForwardKinematics(robot.model, data, q)
        oMf = data.oMf
        pairs = [(robot.frame_id(parent), robot.frame_id(child)) for parent, child in sample.edges]
        pairs += [(robot.frame_id(robot.root_link), robot.frame_id(link)) for link in links.ee_links]
        expected = _pinocchio_rows([oMf[parent].actInv(oMf[child]) for parent, child in pairs])
        got = np.vstack([sample.link_poses, sample.ee[:sample.ee_count]])
        assert np.array_equal(got.view(np.int64), expected.view(np.int64)), k
    poses = [pin.SE3.Random().homogeneous for _ in range(500)]
    poses += [np.diag([sx, sy, sx * sy, 1.0]) for sx in (1.0, -1.0) for sy in (1.0, -1.0)]
    expected = _pinocchio_rows([pin.SE3(pose) for pose in poses])
    assert np.array_equal(frames.pose_rows(poses).view(np.int64), expected.view(np.int64))


def _odometry(flip: bool) -> list[tuple[float, ...]]:
    """/odom (stamp ns, x, y, quaternion z and w) of mobile_pick's first 30 samples, every
    topic consumed; with ``flip``, /odom alone from sample 4 and every topic again from
    sample 13: the samples then built are not those of their block."""
    session = SimulationSession(load_scene("mobile_pick"), RATE, samples_per_solve=10)
    rows = []
    for k in range(30):
        if flip and k in (4, 13):
            session.consumed_by({"/odom"} if k == 4 else None)
        odom = dict(session.step())["/odom"]
        pose = odom.pose.pose
        rows.append((odom.header.stamp.sec * 10**9 + odom.header.stamp.nanosec, pose.position.x, pose.position.y,
                     pose.orientation.z, pose.orientation.w))
    return rows


def test_moving_base_odometry_advances_once_per_sample() -> None:
    """A moving base's samples are built a block at a time, the wheel odometry advanced once
    per sample in order: a sample rebuilt because its consumers changed (here in the middle
    of a block) gives the /odom it would have given (the base drives from the start: the
    odometry's x moves by about 1e-5 m a sample, so advancing twice would show)."""
    plain, flipped = _odometry(False), _odometry(True)
    assert [row[0] for row in plain] == [k * 2_000_000 for k in range(30)]
    assert plain[-1][1] != plain[0][1]      # the base moved: a doubled step would change x
    assert flipped == plain


def test_moving_base_outputs_follow_the_odometry_step_and_the_slip_formula() -> None:
    """Each sample's /odom (the block's batch fill, each sample's twist computed once) against
    the reference path: odometry_step of the previous sample's wheel speeds from
    /joint_states held over the samples' times (s, from their stamps), the twist base_twist
    of the sample's own, to the bit; base.slip in
    /diagnostics the largest hub speed of the twist's difference from the true twist
    (/base_pose_ground_truth) over the samples published since the last report."""
    session = SimulationSession(load_scene("mobile_pick"), RATE, samples_per_solve=10)
    mecanum, wheels = session.moving_base.base.mecanum, session.moving_base.base.wheels
    pose, speeds_before, slip = session.moving_base.odometry.pose0.copy(), None, 0.0
    for k in range(25):
        sample = dict(session.step())
        speeds = np.array(sample["/joint_states"].velocity)[:len(session.robot.joint_names)][wheels]
        if speeds_before is not None:
            pose = odometry_step(mecanum, pose, speeds_before, k * session.step_ns / 1e9 - (k - 1) * session.step_ns / 1e9)
        twist, speeds_before = base_twist(mecanum, speeds), speeds
        odom, truth = sample["/odom"].twist.twist, sample["/base_pose_ground_truth"].twist.twist
        assert (odom.linear.x, odom.linear.y, odom.angular.z) == tuple(twist)
        position = sample["/odom"].pose.pose.position
        assert (position.x, position.y) == (pose[0], pose[1])
        difference = twist - np.array([truth.linear.x, truth.linear.y, truth.angular.z])
        slip = max(slip, float(np.max(np.linalg.norm(mecanum.hub_velocities(difference), axis=1))))
    assert slip > 0.0                                   # the rollers creep as the base drives
    assert session.moving_base.report()[1]["base.slip"] == slip
