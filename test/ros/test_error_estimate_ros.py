"""The node with ``error_estimate: true`` on gripping: /diagnostics carries the estimate
per state group (its companion runs in a worker process at dt/2) and the companion's cost.
Its publish rate is timing, measured in bench/bench_node_error_estimate.py, not here."""
from __future__ import annotations

import pytest
from ros_support import Collector, diagnostic_values, ros_context, spinning, wait_until

pytestmark = pytest.mark.ros
rclpy = pytest.importorskip("rclpy")
from rclpy.parameter import Parameter  # noqa: E402

from youbot_dynamics.ros.dynamics_node import DynamicsNode  # noqa: E402

DURATION = 0.4


def test_the_estimate_arrives_in_diagnostics() -> None:
    with ros_context(11) as (context, _):
        node = DynamicsNode(context=context, parameter_overrides=[Parameter(k, value=v) for k, v in dict(
            scene="gripping", publish_rate=500.0, duration=DURATION, time_scale=0.0, error_estimate=True,
            diagnostics_period=0.05).items()])
        collector = Collector(context, {"/diagnostics": "diagnostic_msgs/msg/DiagnosticArray"})
        try:
            with spinning(context, node, collector):
                wait_until(lambda: node.finished, what="the node to finish")
                wait_until(lambda: any("error_estimate.joint_angles (rad)" in diagnostic_values(m)
                                       for m in collector.messages("/diagnostics")),
                           what="an error estimate in /diagnostics")
        finally:
            node.close()
    values = [diagnostic_values(m) for m in collector.messages("/diagnostics")]
    last = next(v for v in reversed(values) if "error_estimate.joint_angles (rad)" in v)
    assert last["error_estimate.rule"].startswith("Richardson: companion at dt/2, order 1")
    assert last["error_estimate.where"].startswith("worker process")
    # pgs at 1 ms against 0.5 ms, x2: the arms' joint angles differ by 1.8e-4 rad over the
    # first second (measured offline, test/accuracy/test_error_estimate.py's companion); a
    # finite, positive figure below 1e-2 rad here
    assert 0.0 < float(last["error_estimate.joint_angles (rad)"]) < 1e-2
    assert float(last["error_estimate.companion_cpu_time (s)"]) > 0.0
    assert last["error_estimate.events"].endswith("(companion 1)")
