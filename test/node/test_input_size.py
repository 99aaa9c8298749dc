"""Sizes read from a serialized message before it is deserialised
(:mod:`youbot_dynamics.node.input_size`): the counts it announces, against messages
serialised by rosbags (an independent CDR writer) in both byte orders."""
from __future__ import annotations

import numpy as np
import pytest

from youbot_dynamics.io.messages import TYPESTORE
from youbot_dynamics.node.commands import MAX_NAMES, MAX_TRAJECTORY_POINTS, InputRejected
from youbot_dynamics.node.input_size import check_serialized, leading_counts
from youbot_dynamics.node.interface import TOPICS

JOINT_STATE, TRAJECTORY = "sensor_msgs/msg/JointState", "trajectory_msgs/msg/JointTrajectory"
LIMIT = {topic.type: topic.max_bytes for topic in TOPICS if topic.direction == "sub"}


def header(frame: str) -> object:
    types = TYPESTORE.types
    return types["std_msgs/msg/Header"](stamp=types["builtin_interfaces/msg/Time"](sec=3, nanosec=7),
                                        frame_id=frame)


def joint_state(names: list[str]) -> object:
    values = np.arange(len(names), dtype=float)
    return TYPESTORE.types[JOINT_STATE](header=header("base"), name=names, position=values, velocity=values,
                                         effort=np.array([], dtype=float))


def trajectory(names: list[str], points: int, positions: bool = True) -> object:
    types = TYPESTORE.types
    empty = np.array([], dtype=float)
    point = [types["trajectory_msgs/msg/JointTrajectoryPoint"](
        positions=np.full(len(names), 0.1) if positions else empty, velocities=empty, accelerations=empty,
        effort=empty, time_from_start=types["builtin_interfaces/msg/Duration"](sec=k, nanosec=0))
        for k in range(points)]
    return types[TRAJECTORY](header=header("odd_frame"), joint_names=names, points=point)


def cdr(message: object, little_endian: bool = True) -> bytes:
    return bytes(TYPESTORE.serialize_cdr(message, message.__msgtype__, little_endian=little_endian))


@pytest.mark.parametrize("little_endian", [True, False])
@pytest.mark.parametrize("names", [[], ["a"], ["ab", "abc", "arm_joint_1"], [f"j{k}" for k in range(MAX_NAMES)]])
def test_counts_are_read_from_the_bytes(names: list[str], little_endian: bool) -> None:
    """Names of every length (every alignment after them), both byte orders: the counts are
    the message's."""
    assert leading_counts(cdr(joint_state(names), little_endian), JOINT_STATE) == {"joint names": len(names)}
    assert leading_counts(cdr(trajectory(names, 3), little_endian), TRAJECTORY) == \
        {"joint names": len(names), "points": 3}


def test_a_40000_point_trajectory_under_the_byte_limit_is_refused_by_its_count() -> None:
    """40 000 points with empty arrays: under the 1 MiB byte limit, refused by the point
    count; 1000 points of 16 joints (the largest allowed) pass."""
    big = cdr(trajectory([], 40_000, positions=False))
    assert len(big) < LIMIT[TRAJECTORY]
    with pytest.raises(InputRejected, match="40000 points, more than the limit of 1000") as caught:
        check_serialized(big, TRAJECTORY, LIMIT[TRAJECTORY])
    assert caught.value.kind == "too_large"
    check_serialized(cdr(trajectory([f"j{k}" for k in range(16)], MAX_TRAJECTORY_POINTS)), TRAJECTORY,
                     LIMIT[TRAJECTORY])


def test_too_many_names_and_too_many_bytes_are_refused() -> None:
    names = [f"j{k}" for k in range(MAX_NAMES + 1)]
    for message, msgtype in ((joint_state(names), JOINT_STATE), (trajectory(names, 1), TRAJECTORY)):
        with pytest.raises(InputRejected, match=f"{MAX_NAMES + 1} joint names"):
            check_serialized(cdr(message), msgtype, LIMIT[msgtype])
    data = cdr(joint_state(["a"]))
    with pytest.raises(InputRejected, match=f"{len(data)} bytes, more than the {len(data) - 1} byte limit"):
        check_serialized(data, JOINT_STATE, len(data) - 1)


def test_truncated_bytes_are_left_to_the_deserialiser() -> None:
    """Bytes too short for what they announce give the counts reached and no error here."""
    data = cdr(trajectory(["a", "b"], 2))
    assert leading_counts(data[:32], TRAJECTORY) == {"joint names": 2}
    assert leading_counts(data[:10], TRAJECTORY) == {}
    check_serialized(data[:32], TRAJECTORY, LIMIT[TRAJECTORY])
