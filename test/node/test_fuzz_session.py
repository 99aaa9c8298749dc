"""Fuzzing the dynamics node's inputs in-process (no DDS): hypothesis generates the fields of
every subscribed topic (/joint_commands, /joint_trajectory in simulate mode; /joint_states
in inverse mode) with NaN, inf, huge and tiny values, wrong lengths, random and locked joint
names, and stamps that are zero, old, negative or far in the future (any builtin_interfaces
Time: sec int32, nanosec uint32), and feeds them to the session layer, interleaved with
simulation steps, resets and pauses.

Invariants checked after every operation:
- no exception escapes but :class:`InputRejected`;
- every rejection is counted (rejected.total +1, accepted unchanged) and every acceptance
  too (accepted +1);
- every published message is finite in every numeric field and passes rclpy's strict field
  check (``to_rclpy`` under ROS_PYTHON_CHECK_FIELDS=1, when rclpy is installed);
- simulate mode: the state (q, v) stays finite, the session never fails, /clock advances by
  exactly one increment per sample, resets included (node time never goes back);
- inverse mode (with and without the acceleration low-pass): a torque is published only
  for the middle of three consecutive accepted samples (no rejection in between) whose
  stamps increase by at most the estimator's largest gap, stamped with that sample's stamp
  (a zero after a zero: its receive time), and never beyond the effort-limit bound; and
  whatever came before (NaN, overflowing velocities, stamps of 1e6 s, jumps back, gaps),
  three good samples give a torque: the estimate recovers within one stencil.

Examples per test: test/conftest.py's hypothesis profile (``ci``: 40, derandomised;
``HYPOTHESIS_PROFILE=thorough``: 2000).
"""
from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest
from hypothesis import event, given
from hypothesis import strategies as st

from youbot_dynamics.node.commands import InputRejected
from youbot_dynamics.node.inverse import plausible_limit
from youbot_dynamics.node.inverse_session import InverseSession
from youbot_dynamics.node.simulate import SimulationSession
from youbot_dynamics.scene.schema import load_scene

try:
    from youbot_dynamics.ros.conversions import to_rclpy
except ImportError:          # no rclpy: the strict field check is skipped, the rest runs
    to_rclpy = None

SCENE = load_scene("arm_ptp")
ROBOT = SCENE.robot
MOVING = list(ROBOT.joint_names)
LOCKED = list(ROBOT.locked)
STEP_NS = 10_000_000
"""Sample increment of the fuzzed simulation (100 Hz)."""
WALL_NS = 1_763_900_000 * 10**9
"""The wall clock the sessions are told (fixed, so that the examples are reproducible)."""

SPECIAL = [math.nan, math.inf, -math.inf, 0.0, -0.0, 5e-324, -5e-324, 1e-300, 1e300, -1e300,
           1.7976931348623157e308, 1e3, -1e3, 2**53 + 1.0]
numbers = st.one_of(st.sampled_from(SPECIAL), st.floats(), st.floats(-10.0, 10.0))
names = st.one_of(st.sampled_from(MOVING + LOCKED + ["", "arm_joint_9", "ARM_JOINT_1", "arm_joint_1 "]),
                  st.text(max_size=12))
stamps = st.one_of(
    st.just(0), st.integers(1, 2 * 10**9),                                        # unstamped, sim-time sized
    st.builds(lambda sec, nanosec: sec * 10**9 + nanosec,                          # any builtin Time
              st.integers(-2**31, 2**31 - 1), st.integers(0, 2**32 - 1)),
    st.sampled_from([1_700_000_000 * 10**9, (2**31 - 1) * 10**9 + 999_999_999, -2**31 * 10**9]),
    st.integers(WALL_NS - 10**9, WALL_NS + 10**9))                                # wall-clock stamps


valid_joints = st.permutations(MOVING).flatmap(lambda p: st.integers(1, len(p)).map(lambda k: p[:k]))
"""A subset of the moving joints, in any order."""


@st.composite
def joint_names(draw, sometimes_valid: bool = True) -> list[str]:
    """Random names, or (half the time) a subset/permutation of the moving joints."""
    if sometimes_valid and draw(st.booleans()):
        return draw(valid_joints)
    return draw(st.lists(names, max_size=7))


@st.composite
def values_for(draw, count: int) -> list[float]:
    """``count`` values (sometimes a wrong count); within the joint limits or anything."""
    length = draw(st.one_of(st.just(count), st.integers(0, 8)))
    if draw(st.booleans()):
        return [draw(st.floats(float(ROBOT.lower[i % len(MOVING)]), float(ROBOT.upper[i % len(MOVING)])))
                for i in range(length)]
    return draw(st.lists(numbers, min_size=length, max_size=length))


recent_stamps = st.one_of(st.just(0), st.integers(1, 5 * 10**8))
"""Stamps near the fuzzed simulation's time (0 .. 0.5 s): some are stale (timeout 0.02 s)."""


@st.composite
def effort_command(draw) -> tuple:
    if draw(st.booleans()):      # well-formed but for its stamp, and efforts of any size
        joints = draw(valid_joints)
        efforts = draw(st.lists(st.one_of(st.floats(-100.0, 100.0), st.sampled_from([1e300, -1e300, 5e-324])),
                                min_size=len(joints), max_size=len(joints)))
        return ("command", joints, efforts, draw(recent_stamps))
    joints = draw(joint_names())
    return ("command", joints, draw(values_for(len(joints))), draw(stamps))


@st.composite
def trajectory(draw) -> tuple:
    if draw(st.booleans()):      # well-formed: increasing times, positions within the limits
        joints = draw(valid_joints)
        index = [MOVING.index(name) for name in joints]
        times = sorted(draw(st.sets(st.integers(0, 2 * 10**9), min_size=1, max_size=4)))
        with_velocity = draw(st.booleans())
        points = [(t, [draw(st.floats(float(ROBOT.lower[i]), float(ROBOT.upper[i]))) for i in index],
                   draw(st.lists(st.floats(-1e3, 1e3), min_size=len(joints), max_size=len(joints)))
                   if with_velocity else []) for t in times]
        return ("trajectory", joints, points, draw(st.one_of(recent_stamps, stamps)))
    joints = draw(joint_names())
    points = []
    for _ in range(draw(st.integers(0, 4))):
        time_from_start = draw(st.one_of(st.integers(0, 3 * 10**9), stamps))
        velocities = draw(st.one_of(st.just([]), values_for(len(joints))))
        points.append((time_from_start, draw(values_for(len(joints))), velocities))
    return ("trajectory", joints, points, draw(stamps))


simulate_operations = st.lists(st.one_of(
    effort_command(), trajectory(), st.tuples(st.just("step"), st.integers(1, 4)),
    st.just(("reset",)), st.tuples(st.just("pause"), st.booleans())), min_size=1, max_size=8)


def numeric_leaves(message: object, path: str = "") -> Iterator[tuple[str, float]]:
    """(field path, value) of every float in a rosbags message, recursively."""
    if isinstance(message, (float, np.floating)):
        yield path, float(message)
    elif isinstance(message, np.ndarray) and message.dtype.kind == "f":
        yield from ((f"{path}[{i}]", float(v)) for i, v in enumerate(message.ravel()))
    elif isinstance(message, (list, tuple)):
        for i, item in enumerate(message):
            yield from numeric_leaves(item, f"{path}[{i}]")
    elif hasattr(message, "__dataclass_fields__"):
        for field in message.__dataclass_fields__:
            yield from numeric_leaves(getattr(message, field), f"{path}.{field}")


def check_published(outputs: list) -> None:
    """Every message finite in every float and accepted by rclpy's strict field check."""
    for topic, message in outputs:
        bad = [(path, value) for path, value in numeric_leaves(message) if not math.isfinite(value)]
        assert not bad, f"{topic}: non-finite {bad[:3]}"
        if to_rclpy is not None:
            to_rclpy(message)


def counted(session, operation) -> object:
    """Run ``operation``; assert it counted exactly one acceptance or one rejection."""
    counters = session.counters
    before = (counters.accepted, sum(counters.rejected.values()))
    try:
        result = operation()
    except InputRejected as error:
        assert error.kind in counters.rejected
        assert (counters.accepted, sum(counters.rejected.values())) == (before[0], before[1] + 1)
        event(f"rejected: {error.kind}")
        return None
    assert counters.accepted == before[0] + 1
    event("accepted")
    return result


@pytest.fixture(scope="module")
def simulation() -> SimulationSession:
    return SimulationSession(SCENE, 1e9 / STEP_NS, samples_per_solve=2, command_timeout=0.02)


@given(simulate_operations)
def test_fuzzed_commands_and_trajectories_never_break_the_simulation(simulation: SimulationSession,
                                                                     operations: list) -> None:
    session = simulation
    session.reset()
    session.paused = False
    clock: list[int] = []
    for operation in [*operations, ("pause", False), ("step", 1)]:
        kind = operation[0]
        if kind == "command":
            counted(session, lambda: session.effort_command(*operation[1:], wall_ns=WALL_NS))
        elif kind == "trajectory":
            counted(session, lambda: session.trajectory(*operation[1:], wall_ns=WALL_NS))
        elif kind == "reset":
            session.reset()
        elif kind == "pause":
            session.paused = operation[1]
        else:
            for _ in range(operation[1]):
                outputs = session.step()
                check_published(outputs)
                messages = dict(outputs)
                if "/clock" in messages:
                    clock.append(messages["/clock"].clock.sec * 10**9 + messages["/clock"].clock.nanosec)
                else:
                    assert session.paused
        assert session.failure is None
        assert np.isfinite(session.snapshot.q).all() and np.isfinite(session.snapshot.v).all()
        assert clock == [clock[0] + STEP_NS * k for k in range(len(clock))]
    check_published(session.diagnostics(1.0))


@st.composite
def joint_states(draw) -> list[tuple]:
    """A stream of /joint_states samples: mostly well-formed (all moving joints, maybe
    with locked ones, increasing stamps) with fuzzed ones mixed in."""
    stream, stamp = [], draw(st.one_of(st.integers(0, 2 * 10**9), st.integers(0, 2**31 * 10**9 - 1),
                                       st.sampled_from([1_700_000_000 * 10**9, 2**31 * 10**9 - 100])))
    for _ in range(draw(st.integers(1, 12))):
        if draw(st.integers(0, 3)) > 0:
            joints = draw(st.permutations(MOVING + draw(st.lists(st.sampled_from(LOCKED), max_size=2, unique=True))))
            stamp += draw(st.one_of(st.integers(1, 50_000_000), st.sampled_from([0, -1, 1])))
            position = draw(st.lists(st.floats(-3.0, 3.0), min_size=len(joints), max_size=len(joints)))
            velocity = draw(st.lists(st.floats(-5.0, 5.0), min_size=len(joints), max_size=len(joints)))
            stream.append((joints, position, velocity, stamp))
        else:
            joints = draw(joint_names())
            stream.append((joints, draw(values_for(len(joints))), draw(values_for(len(joints))), draw(stamps)))
    return stream


@st.composite
def good_tail(draw) -> list[tuple]:
    """Three good samples 2 ms apart with a smooth motion (|a| <= 0.5 rad/s^2), stamped
    from 0 (the test shifts them after a gap or a jump back)."""
    q = np.array([draw(st.floats(float(ROBOT.lower[i]) + 0.01, float(ROBOT.upper[i]) - 0.01))
                  for i in range(len(MOVING))])
    v = np.array(draw(st.lists(st.floats(-1.0, 1.0), min_size=len(MOVING), max_size=len(MOVING))))
    dv = np.array(draw(st.lists(st.floats(-1e-3, 1e-3), min_size=len(MOVING), max_size=len(MOVING))))
    return [(MOVING, list(q + 0.002 * k * v), list(v + k * dv), 2_000_000 * k) for k in range(3)]


@pytest.fixture(scope="module", params=[0.0, 0.05], ids=["no filter", "filter 0.05 s"])
def inverse(request) -> InverseSession:
    return InverseSession(SCENE, filter_time_constant=request.param)


@given(joint_states(), good_tail())
def test_fuzzed_joint_states_never_break_inverse_mode(inverse: InverseSession, stream: list, tail: list) -> None:
    session = inverse
    session.estimator.clear()
    max_gap, bound = session.estimator.max_gap_ns, plausible_limit(ROBOT)
    accepted_run: list[int] = []        # stamps of the accepted samples since the last rejection
    torque_stamps: list[int] = []
    previous_zero = session.last_unstamped
    def shifted_tail() -> list[tuple]:
        """The tail after a gap longer than the largest, or from 1 ms if that is out of range."""
        last = session.estimator.samples[-1].stamp_ns if session.estimator.samples else 0
        start = last + max_gap + 1 if last + max_gap + 10**8 < 2**31 * 10**9 else 1_000_000
        return [(names_, position, velocity, start + stamp) for names_, position, velocity, stamp in tail]

    for k, sample in enumerate([*stream, None, None, None]):
        if k == len(stream):
            tail = shifted_tail()
        names_, position, velocity, stamp = sample if sample is not None else tail[k - len(stream)]
        received = 10**9 + k * 1_000_000                 # the node clock at receipt (for stamp 0)
        rejected_before = sum(session.counters.rejected.values())
        outputs = counted(session, lambda: session.joint_state(names_, position, velocity, stamp, received))
        effective = received if stamp == 0 and previous_zero else stamp     # two zeros in a row: unstamped
        previous_zero = stamp == 0
        if outputs is None:
            accepted_run = []
            continue
        if accepted_run and not 0 < effective - accepted_run[-1] <= max_gap:
            event("estimator restarted")
            accepted_run = []
        accepted_run.append(effective)
        check_published(outputs)
        torques = [message for topic, message in outputs if topic == "/computed_torques"]
        if sum(session.counters.rejected.values()) > rejected_before:   # non-finite or implausible torque
            assert not outputs
            accepted_run = []
        if torques:
            event("torque published")
            assert len(accepted_run) >= 3, "a torque computed across a rejected sample, a gap or a jump"
            stamp_ns = torques[0].header.stamp.sec * 10**9 + torques[0].header.stamp.nanosec
            assert stamp_ns == accepted_run[-2]
            assert (np.abs(torques[0].effort) <= bound).all()
            torque_stamps.append(stamp_ns)
    assert torque_stamps and torque_stamps[-1] == accepted_run[-2], "no torque after three good samples"
    assert len(accepted_run) == 3
    check_published(session.diagnostics(1.0))
