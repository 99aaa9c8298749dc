"""Inverse mode never wedges: whatever one bad sample does (a stamp of 1e6 s,
an overflowing velocity through the low-pass filter, a velocity jump of 1e6 rad/s), or a
replay that restarts its time base, a pause, or unstamped samples, the acceleration
estimate restarts and torques come back after at most one stencil (three) of good samples;
implausible torques (beyond 10 x the URDF effort limit) are never published, and samples
with velocities beyond 10 x the URDF velocity limit are rejected.

The stream: q_i(t) = c_i + 0.3 sin(2 t + i) rad, v_i = 0.6 cos(2 t + i) rad/s at 500 Hz.
Torques published are compared with tau(q, v, a) at the exact acceleration
a_i = -1.2 sin(2 t + i) rad/s^2 (same dynamics, exact a): the central difference's error
is at most max |a(s) - a(t)| over +-2 ms, 1.2 * 2 * 0.002 = 4.8e-3 rad/s^2 per joint.
"""
from __future__ import annotations

import numpy as np
import pytest

from youbot_dynamics.node.commands import InputRejected
from youbot_dynamics.node.inverse import PLAUSIBLE_FACTOR, AccelerationEstimator
from youbot_dynamics.node.inverse_session import InverseSession
from youbot_dynamics.scene.schema import load_scene

SCENE = load_scene("arm_ptp")
ROBOT = SCENE.robot
NAMES = list(ROBOT.joint_names)
PERIOD_NS = 2_000_000
COUNT = 40
FAULT = 20
T0_NS = 1_000_000_000


def motion(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    phase = 2.0 * t + np.arange(len(NAMES))
    centre = (ROBOT.lower + ROBOT.upper) / 2
    return centre + 0.3 * np.sin(phase), 0.6 * np.cos(phase), -1.2 * np.sin(phase)


def stream(stamps: list[int]) -> list[tuple[list[str], list[float], list[float], int]]:
    return [(NAMES, list(motion(s / 1e9)[0]), list(motion(s / 1e9)[1]), s) for s in stamps]


def feed(session: InverseSession, samples, received: list[int] | None = None) -> dict[int, np.ndarray]:
    """Push every sample; the published torques by stamp (ns)."""
    torques = {}
    for k, (names, q, v, stamp) in enumerate(samples):
        try:
            outputs = session.joint_state(names, q, v, stamp, None if received is None else received[k])
        except InputRejected:
            continue
        for topic, message in outputs:
            if topic == "/computed_torques":
                torques[message.header.stamp.sec * 10**9 + message.header.stamp.nanosec] = np.array(message.effort)
    return torques


def check_torques(session: InverseSession, torques: dict[int, np.ndarray]) -> None:
    """Every published torque within the central-difference bound of the exact one."""
    for stamp, tau in torques.items():
        q, v, a = motion(stamp / 1e9)
        exact = session.dynamics.torque(q, v, a)
        # measured 1.7e-4 N m at most; bound sum_j |M_ij| 4.8e-3 < 1e-2 N m (with |M| row sums < 2 kg m^2)
        assert np.abs(tau - exact).max() < 1e-2, stamp


REGULAR = [T0_NS + k * PERIOD_NS for k in range(COUNT)]


def middles_without(bad: int) -> set[int]:
    """Stamps of the middles of every stencil of three samples that does not hold sample ``bad``."""
    return {REGULAR[m] for m in range(1, COUNT - 1) if bad not in (m - 1, m, m + 1)}


@pytest.mark.parametrize(("fault", "time_constant"), [
    ("stamp_1e6_s", 0.0), ("stamp_1e6_s", 0.05), ("overflowing_velocity", 0.05), ("overflowing_velocity", 0.0),
    ("velocity_jump_1e6", 0.0), ("velocity_jump_1e6", 0.05), ("velocity_step_10", 0.0)])
# (with the 0.05 s low-pass the 10 rad/s step is smoothed to 190 rad/s^2: within the bound)
def test_one_bad_sample_costs_only_its_stencils(fault: str, time_constant: float) -> None:
    session = InverseSession(SCENE, filter_time_constant=time_constant)
    samples = stream(REGULAR)
    names, q, v, stamp = samples[FAULT]
    if fault == "stamp_1e6_s":
        samples[FAULT] = (names, q, v, 10**6 * 10**9)
    elif fault == "overflowing_velocity":
        samples[FAULT] = (names, q, [1e308, *v[1:]], stamp)
    else:   # within the velocity bound (10 x 1.57 rad/s) but a step of 10 rad/s in 2 ms: 5000 rad/s^2
        jump = 1e6 if fault == "velocity_jump_1e6" else 10.0
        samples[FAULT] = (names, q, [v[0] + jump, *v[1:]], stamp)
    torques = feed(session, samples)
    # no torque whose stencil holds the bad sample; all others, right after it too
    assert set(torques) == middles_without(FAULT)
    if time_constant == 0.0:
        check_torques(session, torques)
    assert all(np.isfinite(tau).all() and (np.abs(tau) <= PLAUSIBLE_FACTOR * ROBOT.effort_limit).all()
               for tau in torques.values())
    if fault == "velocity_jump_1e6":      # its stencil would give 3e11 N m
        assert session.counters.rejected["out_of_limits"] == 1
    if fault == "velocity_step_10":       # the torque of the stencil that ends with it is refused
        assert session.counters.rejected["implausible_torque"] == 1
        assert session.estimator.restarts["implausible"] == 1


@pytest.mark.parametrize("jump", ["replay_restart", "pause_1_s"])
def test_a_jump_in_the_time_base_restarts_the_stencil_with_the_jumping_sample(jump: str) -> None:
    """Samples 0..19, then 20..39 either stamped from the stream's start again (a replay that
    restarts) or 1 s later (a pause): the sample after the jump is accepted and starts a new
    stencil, so the torques resume one sample after it."""
    shift = -FAULT * PERIOD_NS if jump == "replay_restart" else 10**9
    stamps = [s if k < FAULT else s + shift for k, s in enumerate(REGULAR)]
    session = InverseSession(SCENE)
    torques = feed(session, stream(stamps))
    expected = {stamps[m] for m in range(1, COUNT - 1) if not m - 1 < FAULT <= m + 1}
    assert set(torques) == expected
    assert sum(session.counters.rejected.values()) == 0 and session.counters.accepted == COUNT
    cause = "backwards" if jump == "replay_restart" else "gap"
    assert session.estimator.restarts[cause] == 1
    check_torques(session, torques)


def test_unstamped_samples_take_the_receive_time() -> None:
    """Stamp 0 = receive time (from the second zero on: the first is taken at 0, where a
    stream in simulated time starts): every sample accepted, the jump from 0 to the node
    clock restarts the estimate once, then a torque for every middle, stamped with its
    receive time (none is rejected as bad_timing)."""
    session = InverseSession(SCENE)
    samples = [(names, q, v, 0) for names, q, v, _ in stream(REGULAR)]
    torques = feed(session, samples, received=REGULAR)
    assert set(torques) == {REGULAR[m] for m in range(2, COUNT - 1)}
    assert session.counters.accepted == COUNT and session.estimator.restarts["gap"] == 1
    check_torques(session, torques)


def test_a_stream_stamped_from_zero_loses_nothing() -> None:
    """Simulated time starts at 0: the first sample stamped 0 is a real stamp."""
    stamps = [k * PERIOD_NS for k in range(COUNT)]
    session = InverseSession(SCENE)
    torques = feed(session, stream(stamps), received=[T0_NS + s for s in stamps])
    assert set(torques) == {stamps[m] for m in range(1, COUNT - 1)}


def test_unstamped_sample_without_a_receive_time_is_rejected() -> None:
    session = InverseSession(SCENE)
    session.joint_state(NAMES, [0.0] * 5, [0.0] * 5, 0)          # taken at 0
    with pytest.raises(InputRejected, match="bad_timing"):
        session.joint_state(NAMES, [0.0] * 5, [0.0] * 5, 0)
    assert session.counters.rejected["bad_timing"] == 1


def test_estimator_clears_on_restart() -> None:
    """A restart forgets the samples and the filter state (``clear``)."""
    estimator = AccelerationEstimator(0.05, max_gap_ns=10)
    from youbot_dynamics.node.commands import JointSample
    for stamp in (1, 2, 3):
        estimator.push(JointSample(stamp, np.zeros(2), np.full(2, float(stamp))))
    assert estimator.filtered is not None and len(estimator.samples) == 3
    estimator.push(JointSample(100, np.zeros(2), np.zeros(2)))
    assert estimator.filtered is None and len(estimator.samples) == 1 and estimator.restarts["gap"] == 1


def central_differences(stamps: list[int], v: np.ndarray, taken: list[bool], time_constant: float,
                        max_gap_ns: int = 100_000_000) -> tuple[list[tuple[int, int, bytes]], dict[str, int]]:
    """The module docstring's estimate written out sample by sample: (middle sample's stamp
    and index, estimate bytes) of each estimate, and the restarts by cause (rows not
    ``taken`` clear the stencil)."""
    window: list[int] = []
    filtered, estimates, restarts = None, [], {"backwards": 0, "gap": 0, "non_finite": 0}
    for k, stamp in enumerate(stamps):
        if not taken[k]:
            window, filtered = [], None
            continue
        if window and not 0 < stamp - stamps[window[-1]] <= max_gap_ns:
            restarts["backwards" if stamp <= stamps[window[-1]] else "gap"] += 1
            window, filtered = [], None
        window = [*window[-2:], k]
        if len(window) < 3:
            continue
        before, middle, after = window
        with np.errstate(over="ignore", invalid="ignore"):
            estimate = (v[after] - v[before]) / ((stamps[after] - stamps[before]) / 1e9)
            if time_constant > 0.0 and filtered is not None:
                dt = (stamps[after] - stamps[middle]) / 1e9
                estimate = filtered + dt / (time_constant + dt) * (estimate - filtered)
        if not np.isfinite(estimate).all():
            restarts["non_finite"] += 1
            window, filtered = [], None
            continue
        filtered = estimate
        estimates.append((stamps[middle], middle, estimate.tobytes()))
    return estimates, restarts


@pytest.mark.parametrize("time_constant", [0.0, 0.01])
def test_estimator_pushes_as_written_out(time_constant: float) -> None:
    """``push`` sample by sample and ``push_rows`` in batches (rejected rows clearing the
    stencil) give the estimates of the rule written out (:func:`central_differences`), to
    the bit, with the same restarts (backwards, gap, and non_finite where a velocity
    difference overflows), whatever the batch boundaries."""
    from youbot_dynamics.node.commands import JointSample
    rng = np.random.default_rng(11)
    count = 120
    steps = rng.choice([PERIOD_NS, -3 * PERIOD_NS, 200_000_000, 1], size=count, p=[0.85, 0.05, 0.05, 0.05])
    stamps = (T0_NS + np.cumsum(steps)).tolist()
    v = rng.normal(size=(count, 3))
    v = np.where(rng.random((count, 1)) < 0.08, np.copysign(1.7e308, v), v)     # differences overflow
    q = rng.normal(size=(count, 3))
    taken = (rng.random(count) > 0.08).tolist()
    estimates, restarts = central_differences(stamps, v, taken, time_constant)
    expected = [(stamp, q[k].tobytes(), v[k].tobytes(), a) for stamp, k, a in estimates]
    assert restarts["non_finite"] > 0 and restarts["backwards"] > 0 and restarts["gap"] > 0
    one_by_one, got, errors = AccelerationEstimator(time_constant), [], 0
    for k in range(count):
        if not taken[k]:
            one_by_one.clear()
            continue
        try:
            result = one_by_one.push(JointSample(stamps[k], q[k], v[k]))
        except InputRejected:
            errors += 1
            continue
        if result is not None:
            middle, a = result
            got.append((middle.stamp_ns, middle.q.tobytes(), middle.v.tobytes(), a.tobytes()))
    assert got == expected and errors == restarts["non_finite"] and one_by_one.restarts == {**restarts, "implausible": 0}
    for size in (2, 7, count):
        estimator, got, errors = AccelerationEstimator(time_constant), [], 0
        for start in range(0, count, size):
            rows = slice(start, start + size)
            middle, mq, mv, a, failed, _ = estimator.push_rows(stamps[rows], q[rows], v[rows], taken[rows])
            got += [(int(middle[i]), mq[i].tobytes(), mv[i].tobytes(), a[i].tobytes()) for i in range(len(middle))]
            errors += len(failed)
        assert got == expected and errors == restarts["non_finite"] and estimator.restarts == one_by_one.restarts
        assert [s.stamp_ns for s in estimator.samples] == [s.stamp_ns for s in one_by_one.samples]
