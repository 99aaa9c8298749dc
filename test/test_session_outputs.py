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

from youbot_dynamics.ros import frames
from youbot_dynamics.ros.session import SimulationSession
from youbot_dynamics.sim.scene import load_scene

SCENE = load_scene("gripping")
RATE = 500.0


@pytest.fixture
def kinematics_passes(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """Counts LinkFrames.at calls."""
    calls: list[int] = []
    original = frames.LinkFrames.at
    monkeypatch.setattr(frames.LinkFrames, "at", lambda self, q: calls.append(1) or original(self, q))
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
