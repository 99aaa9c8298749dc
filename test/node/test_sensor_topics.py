"""The sensor topics of the simulate session: which scenes publish them, their frames, and
that they carry the simulator's readings."""
from __future__ import annotations

import numpy as np
import pytest

from youbot_dynamics.node.interface import pair_topic, published
from youbot_dynamics.node.simulate import SimulationSession
from youbot_dynamics.scene.schema import load_scene

SENSORS = ("/wrist_wrench", "/imu")


@pytest.mark.parametrize("scene, expected", [
    ("arm_ptp", {"/wrist_wrench"}),                              # a palm, fixed base, no contact
    ("ball_drop", {"/contacts/floor/ball"}),                     # no robot: pairs only
    ("grasp", {"/contacts/pad_l/sphere", "/contacts/pad_r/sphere"}),   # pads, no palm
    ("base_square", {"/wrist_wrench", "/imu"}),
])
def test_only_the_scenes_that_have_a_sensor_publish_it(scene, expected):
    session = SimulationSession(load_scene(scene), 100.0)
    found = {t for t in session.topics if t in SENSORS or t.startswith("/contacts/")}
    assert found == expected


def test_the_messages_carry_the_readings_in_their_frames():
    """mobile_pick: the wrist wrench in the palm's frame, the IMU in base_link (gravity up at
    rest), each pair in its second geometry's frame, from the snapshot's readings."""
    session = SimulationSession(load_scene("mobile_pick"), 50.0, frame_prefix="yb/")
    outputs = dict(session.step())
    readings = session.snapshot.sensors
    wrench = outputs["/wrist_wrench"]
    assert wrench.header.frame_id == "yb/gripper_palm_link"
    assert [wrench.wrench.force.x, wrench.wrench.force.y, wrench.wrench.force.z] == readings.wrist[0].tolist()
    imu = outputs["/imu"]
    assert imu.header.frame_id == "yb/base_link" and imu.linear_acceleration.z == pytest.approx(9.81, abs=1e-9)
    pair = outputs[pair_topic("pad_l", "sphere")]
    assert pair.header.frame_id == "yb/sphere"
    table = outputs[pair_topic("table", "sphere")]
    assert np.isfinite(table.wrench.force.z)


def test_pair_topics_are_valid_ros_names():
    assert pair_topic("pad-l", "2nd body") == "/contacts/pad_l/_2nd_body"
    assert published("simulate", frozenset({"contact_pairs"}), [("a", "b")])[1] == "/contacts/a/b"
