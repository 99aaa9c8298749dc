"""The node refuses an oversized input before deserialising it: a /joint_trajectory of
40 000 points with empty arrays is under the 1 MiB byte limit (0.96 MB of CDR) and used to
be deserialised (0.3 s idle, 2 s under load) before its point count was refused; now its
count is read from the serialized bytes. Deserialisation is watched by wrapping the
node's ``deserialize_message``."""
from __future__ import annotations

import numpy as np
import pytest

from ros_support import ros_context, spinning, wait_until

pytestmark = [pytest.mark.ros, pytest.mark.timeout(240)]

from rclpy.parameter import Parameter  # noqa: E402
from trajectory_msgs.msg import JointTrajectory  # noqa: E402

from youbot_dynamics.io.messages import TYPESTORE  # noqa: E402
from youbot_dynamics.node.interface import TOPICS  # noqa: E402
from youbot_dynamics.ros import dynamics_node  # noqa: E402
from youbot_dynamics.ros.qos import RELIABLE_DEEP  # noqa: E402

TRAJECTORY = "trajectory_msgs/msg/JointTrajectory"


def trajectory_cdr(names: list[str], rows: list[list[float]]) -> bytes:
    """A serialized JointTrajectory (rosbags' CDR writer), point k at k + 1 s."""
    types, empty = TYPESTORE.types, np.array([], dtype=float)
    points = [types["trajectory_msgs/msg/JointTrajectoryPoint"](
        positions=np.array(row, dtype=float), velocities=empty, accelerations=empty, effort=empty,
        time_from_start=types["builtin_interfaces/msg/Duration"](sec=k + 1, nanosec=0)) for k, row in enumerate(rows)]
    header = types["std_msgs/msg/Header"](stamp=types["builtin_interfaces/msg/Time"](sec=0, nanosec=0), frame_id="")
    message = types[TRAJECTORY](header=header, joint_names=names, points=points)
    return bytes(TYPESTORE.serialize_cdr(message, TRAJECTORY))


def test_a_40000_point_trajectory_is_refused_before_deserialisation(monkeypatch) -> None:
    deserialised: list[int] = []
    deserialize = dynamics_node.deserialize_message

    def watched(data: bytes, msg_type: type) -> object:
        deserialised.append(len(data))
        return deserialize(data, msg_type)

    monkeypatch.setattr(dynamics_node, "deserialize_message", watched)
    huge = trajectory_cdr([], [[] for _ in range(40_000)])
    limit = next(topic.max_bytes for topic in TOPICS if topic.name == "/joint_trajectory")
    assert len(huge) < limit                       # the byte limit alone lets it through
    good = trajectory_cdr(["arm_joint_1"], [[0.5]])
    with ros_context(25) as (context, _):
        node = dynamics_node.DynamicsNode(context=context, parameter_overrides=[
            Parameter("scene", value="arm_ptp"), Parameter("publish_rate", value=100.0)])
        sender = node.create_publisher(JointTrajectory, "/joint_trajectory", RELIABLE_DEEP)
        counters = node.session.counters
        with spinning(context, node, single_threaded=True):
            wait_until(lambda: sender.get_subscription_count() > 0, what="the node's subscription")
            sender.publish(huge)
            sender.publish(good)
            wait_until(lambda: counters.rejected["too_large"] == 1 and counters.accepted == 1,
                       what="the huge trajectory refused and the good one taken")
        node.session.close()
    assert len(huge) not in deserialised and deserialised == [len(good)]
    assert sum(counters.rejected.values()) == 1
