"""``dynamics_node --managed``: the node under lifecycle transitions, driven as a lifecycle
manager drives it, through its lifecycle_msgs services from another node. Unconfigured it
has no session and no log; configure loads the scene and opens the MCAP without publishing;
activate publishes; deactivate pauses simulated time; cleanup finalises the MCAP (readable
without recovery) and removes the topics; configure and activate again start a new log;
shutdown ends the node. Waits are hang guards only."""
from __future__ import annotations

import time
from pathlib import Path

import pytest

pytest.importorskip("rclpy")
from ros_support import WAIT, Collector, ros_context, spinning, wait_until  # noqa: E402
from lifecycle_msgs.msg import Transition  # noqa: E402
from lifecycle_msgs.srv import ChangeState, GetState  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402

from youbot_dynamics.io.bag_reader import read_bag  # noqa: E402
from youbot_dynamics.ros.dynamics_node import ManagedDynamicsNode  # noqa: E402

QUIET = 0.5
"""Wall seconds the test watches for something that must not happen (no sample published,
simulated time standing still)."""


class Manager:
    """A lifecycle manager's calls: change_state and get_state of /dynamics_node."""

    def __init__(self, node: Node) -> None:
        self.change = node.create_client(ChangeState, "/dynamics_node/change_state")
        self.get = node.create_client(GetState, "/dynamics_node/get_state")
        assert self.change.wait_for_service(timeout_sec=WAIT) and self.get.wait_for_service(timeout_sec=WAIT)

    @staticmethod
    def _call(client, request):
        future = client.call_async(request)
        wait_until(future.done, what=f"an answer from {client.srv_name}")
        return future.result()

    def transition(self, transition_id: int) -> bool:
        return self._call(self.change, ChangeState.Request(transition=Transition(id=transition_id))).success

    def state(self) -> str:
        return self._call(self.get, GetState.Request()).current_state.label


@pytest.mark.ros
@pytest.mark.timeout(300)
def test_transitions_configure_activate_deactivate_cleanup_shutdown(tmp_path: Path) -> None:
    mcap = tmp_path / "run.mcap"
    with ros_context(24) as (context, _):
        node = ManagedDynamicsNode(context=context, parameter_overrides=[
            Parameter("scene", value="arm_ptp"), Parameter("publish_rate", value=50.0),
            Parameter("mcap_path", value=str(mcap))])
        collector = Collector(context, {"/joint_states": "sensor_msgs/msg/JointState"})
        client = Node("lifecycle_manager", context=context)
        with spinning(context, node, collector, client, single_threaded=True):
            manager = Manager(client)
            assert manager.state() == "unconfigured"
            assert node.session is None and not mcap.exists() and "/joint_states" not in node.publishers_

            assert manager.transition(Transition.TRANSITION_CONFIGURE) and manager.state() == "inactive"
            assert mcap.exists() and node.session is not None
            wait_until(lambda: node.publishers_["/joint_states"].get_subscription_count() > 0,
                       what="the collector to match /joint_states")
            time.sleep(QUIET)
            assert node.session.k == 0 and not collector.messages("/joint_states")

            assert manager.transition(Transition.TRANSITION_ACTIVATE) and manager.state() == "active"
            wait_until(lambda: len(collector.messages("/joint_states")) >= 5, what="samples once active")

            assert manager.transition(Transition.TRANSITION_DEACTIVATE) and manager.state() == "inactive"
            paused_at = node.session.t
            time.sleep(QUIET)
            assert node.session.t == paused_at

            assert manager.transition(Transition.TRANSITION_ACTIVATE)
            wait_until(lambda: node.session.t > paused_at, what="simulated time to go on")
            assert manager.transition(Transition.TRANSITION_DEACTIVATE)
            last = node.session.t

            assert manager.transition(Transition.TRANSITION_CLEANUP) and manager.state() == "unconfigured"
            assert node.session is None and node.publishers_ == {}
            assert not node.get_publishers_info_by_topic("/joint_states")
            logged = [m for m in read_bag(mcap) if m.topic == "/joint_states"]     # finalised: reads as it is
            stamps = [m.message.header.stamp.sec + m.message.header.stamp.nanosec * 1e-9 for m in logged]
            assert stamps[0] == 0.0 and stamps[-1] == pytest.approx(last, abs=1e-9)
            assert {m.topic for m in read_bag(mcap)} >= {"/tf_static", "/robot_description", "/clock"}

            mcap.unlink()
            assert manager.transition(Transition.TRANSITION_CONFIGURE) and mcap.exists()
            assert manager.transition(Transition.TRANSITION_ACTIVATE)
            wait_until(lambda: node.session.t > 0.0, what="the second configuration to run")
            assert manager.transition(Transition.TRANSITION_ACTIVE_SHUTDOWN) and manager.state() == "finalized"
            assert node.finished and node.session is None
        assert any(m.topic == "/joint_states" for m in read_bag(mcap))


@pytest.mark.ros
@pytest.mark.timeout(120)
def test_a_scene_that_cannot_load_fails_configure_and_stays_unconfigured() -> None:
    with ros_context(26) as (context, _):
        node = ManagedDynamicsNode(context=context, parameter_overrides=[Parameter("scene", value="no_such_scene")])
        client = Node("lifecycle_manager", context=context)
        with spinning(context, node, client, single_threaded=True):
            manager = Manager(client)
            assert not manager.transition(Transition.TRANSITION_CONFIGURE)
            assert manager.state() == "unconfigured" and node.session is None
