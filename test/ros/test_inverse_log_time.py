"""An inverse-mode node logs at its own receive times: sender stamps that jump (1015 s,
1 001 015 s, 1016 s, 1.7958e9 s, 1019 s, five samples 2 ms apart each) give an MCAP whose
log times, in file order, never go back and lie within the run's wall-clock span, while the
logged torques keep the sender's stamps."""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

from ros_support import ros_context, spinning, wait_until

pytestmark = [pytest.mark.ros, pytest.mark.timeout(240)]

from mcap.reader import make_reader  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402

from youbot_dynamics.io.messages import TYPESTORE  # noqa: E402
from youbot_dynamics.ros.dynamics_node import DynamicsNode  # noqa: E402
from youbot_dynamics.ros.qos import RELIABLE_DEEP  # noqa: E402
from youbot_dynamics.scene.schema import load_scene  # noqa: E402

STARTS_S = (1015, 1_001_015, 1016, 1_795_800_000, 1019)
PERIOD_NS = 2_000_000


def test_log_time_follows_the_receive_clock_not_the_sender(tmp_path: Path) -> None:
    robot = load_scene("arm_ptp").robot
    centre = (robot.lower + robot.upper) / 2
    stamps = [start * 10**9 + k * PERIOD_NS for start in STARTS_S for k in range(5)]
    path = tmp_path / "inverse.mcap"
    begin = time.time_ns()
    with ros_context(26) as (context, _):
        node = DynamicsNode(context=context, parameter_overrides=[
            Parameter("scene", value="arm_ptp"), Parameter("mode", value="inverse"),
            Parameter("mcap_path", value=str(path))])
        sender = node.create_publisher(JointState, "/joint_states", RELIABLE_DEEP)
        with spinning(context, node, single_threaded=True):
            wait_until(lambda: sender.get_subscription_count() > 0, what="the node's subscription")
            for k, stamp in enumerate(stamps):
                message = JointState(name=list(robot.joint_names), position=list(centre + 1e-3 * k),
                                     velocity=[1e-3] * len(centre))
                message.header.stamp.sec, message.header.stamp.nanosec = divmod(stamp, 10**9)
                sender.publish(message)
            wait_until(lambda: node.session.counters.accepted == len(stamps), what="every sample taken")
        node.close()
    end = time.time_ns()
    with path.open("rb") as file:
        records = [(channel.topic, message.log_time, message.data)
                   for _, channel, message in make_reader(file).iter_messages(log_time_order=False)]
    log_times = [log_time for topic, log_time, _ in records if topic not in ("/tf_static", "/robot_description")]
    assert log_times == sorted(log_times) and log_times
    slack = 10**9      # the receive clock is the monotonic clock started at the wall clock's time
    assert begin - slack <= log_times[0] and log_times[-1] <= end + slack
    torque_stamps = []
    for topic, _, data in records:
        if topic == "/computed_torques":
            header = TYPESTORE.deserialize_cdr(data, "sensor_msgs/msg/JointState").header
            torque_stamps.append(header.stamp.sec * 10**9 + header.stamp.nanosec)
    assert torque_stamps == [stamps[run * 5 + k] for run in range(len(STARTS_S)) for k in (1, 2, 3)]
    assert np.all(np.diff(torque_stamps[:3]) == PERIOD_NS)
