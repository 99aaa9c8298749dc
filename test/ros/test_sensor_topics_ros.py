"""The sensor topics on the ROS graph: one publisher per contact pair, under the pair's
relative name, carrying geometry_msgs/WrenchStamped; the IMU of a moving base."""
from __future__ import annotations

import pytest

from ros_support import Collector, ros_context, spinning, wait_until

pytestmark = [pytest.mark.ros, pytest.mark.timeout(240)]

from rclpy.parameter import Parameter  # noqa: E402

from youbot_dynamics.ros.dynamics_node import DynamicsNode  # noqa: E402

WRENCH = "geometry_msgs/msg/WrenchStamped"


def test_each_contact_pair_and_the_imu_are_heard_on_the_graph() -> None:
    """ball_drop's floor/ball pair on /contacts/floor/ball (frame: the ball), base_square's
    /imu (frame base_link, gravity up) and /wrist_wrench."""
    with ros_context(23) as (context, _):
        nodes = [DynamicsNode(context=context, parameter_overrides=[
            Parameter("scene", value=scene), Parameter("publish_rate", value=50.0),
            Parameter("time_scale", value=0.0)], namespace=namespace)
            for scene, namespace in (("ball_drop", "/drop"), ("base_square", "/square"))]
        topics = {"/drop/contacts/floor/ball": WRENCH, "/square/imu": "sensor_msgs/msg/Imu",
                  "/square/wrist_wrench": WRENCH}
        collector = Collector(context, topics)
        with spinning(context, *nodes, collector):
            wait_until(lambda: all(collector.count(topic) > 0 for topic in topics),
                       what=f"a message on each of {sorted(topics)}")
        assert "/contacts/floor/ball" in nodes[0].publishers_
        pair = collector.messages("/drop/contacts/floor/ball")[0]
        assert pair.header.frame_id == "drop/ball"
        imu = collector.messages("/square/imu")[0]
        assert imu.header.frame_id == "square/base_link" and imu.linear_acceleration.z == pytest.approx(9.81)
        assert collector.messages("/square/wrist_wrench")[0].header.frame_id == "square/gripper_palm_link"
