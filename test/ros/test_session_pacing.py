"""The pacing logic of the simulate-mode node at time_scale 1, on a fake clock (nothing
timed): ticks that come late, jitter and short stalls still give the requested sample
rate within 1 %, samples never run ahead of their schedule, and only a stall longer than
MAX_LAG restarts the pacing."""
from __future__ import annotations

import types

import numpy as np
import pytest

from ros_support import ros_context

rclpy = pytest.importorskip("rclpy")
from rclpy.parameter import Parameter  # noqa: E402

from youbot_dynamics.node import pacing  # noqa: E402
from youbot_dynamics.node.pacing import MAX_LAG  # noqa: E402
from youbot_dynamics.ros import dynamics_node  # noqa: E402
from youbot_dynamics.ros.dynamics_node import DynamicsNode  # noqa: E402

RATE = 500.0


class CountingSession:
    """Stands in for the session: each step is one sample, returns nothing to publish."""

    def __init__(self) -> None:
        self.k, self.paused, self.failure = 0, False, None

    @property
    def t(self) -> float:
        return self.k / RATE

    def step(self) -> list:
        self.k += 1
        return []

    def consumed_by(self, subscribed) -> None:
        pass


@pytest.mark.parametrize("stall", [0.0, 0.05, 2 * MAX_LAG])
def test_pacing_holds_the_rate_within_one_percent(monkeypatch: pytest.MonkeyPatch, stall: float) -> None:
    clock = types.SimpleNamespace(now=0.0)
    fake_time = types.SimpleNamespace(monotonic=lambda: clock.now, perf_counter=lambda: clock.now)
    monkeypatch.setattr(dynamics_node, "time", fake_time)
    monkeypatch.setattr(pacing, "time", fake_time)
    rng = np.random.default_rng(0)
    with ros_context(25) as (context, _):
        node = DynamicsNode(context=context, parameter_overrides=[
            Parameter("scene", value="arm_swing"), Parameter("publish_rate", value=RATE),
            Parameter("time_scale", value=1.0)])
        try:
            node.session = session = CountingSession()
            node._restart_pacing()
            start, ahead, restarts = clock.now, 0, 0
            while clock.now < 10.0:
                clock.now += 1.0 / RATE + rng.uniform(0.0, 0.002)     # every tick late by up to 2 ms
                if stall and abs(clock.now - 5.0) < 1.0 / RATE:
                    clock.now += stall                                # one stall at t = 5 s
                before = node.pacing.start
                node._on_tick()
                restarts += node.pacing.start != before
                ahead = max(ahead, session.k - (clock.now - start) * RATE)
        finally:
            node.destroy_node()
    assert ahead <= 1.0                    # never more samples than wall time allows
    if stall > MAX_LAG:                    # the pacing restarts once; the lost time is not made up
        assert restarts == 1 and session.k < 0.95 * RATE * clock.now
    else:                                  # late ticks and a short stall are caught up
        assert restarts == 0
        assert abs(session.k / (RATE * clock.now) - 1.0) < 0.01
