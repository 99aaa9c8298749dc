"""Inverse mode's compiled checks against what they stand for: a batch that
``clean_rows`` passes skips the per-sample checks (``InverseSession._clean_rows``), so the
session with that path taken and with it switched off must give the same messages bit for
bit, the same counters, restarts, rejections and input times on streams full of what the
per-sample checks reject (NaN, unknown and missing joints, stamps 0, going back, repeated,
beyond a builtin_interfaces/Time, not ints, values at and beyond the plausible bounds);
``plausible_rows`` against numpy's comparison of the effort bound."""
from __future__ import annotations

import numpy as np
import pytest
from test_inverse_batch import SCENE, batched, driver_stream, stream

from youbot_dynamics.io.stamps import STAMP_LIMIT_NS
from youbot_dynamics.node.inverse import (
    clean_rows,
    plausible_limit,
    plausible_rows,
    position_bounds,
)
from youbot_dynamics.node.inverse_session import InverseSession
from youbot_dynamics.ros.conversions import to_cdr


def edge_stream(rng: np.random.Generator, count: int) -> list[tuple]:
    """A driver's stream (:func:`driver_stream`) with what only the clean check may let
    through wrongly: repeated stamps, stamps 0, at and beyond the last Time, floats and
    numpy ints, receive times missing, positions at and just beyond the plausible bounds."""
    low, high = position_bounds(SCENE.robot)
    samples = [list(sample) for sample in driver_stream(rng, count)]
    column = samples[0][0].index(SCENE.robot.joint_names[0])
    for k, sample in enumerate(samples):
        fault = rng.random()
        if fault < 0.05:
            sample[3] = samples[k - 1][3]                              # a duplicate
        elif fault < 0.07:
            sample[3] = 0                                              # unstamped
        elif fault < 0.08:
            sample[3] = STAMP_LIMIT_NS - 1 if fault < 0.075 else STAMP_LIMIT_NS   # the last Time, and beyond
        elif fault < 0.10:
            sample[3] = float(sample[3]) if fault < 0.09 else np.int64(sample[3])  # not an int
        elif fault < 0.12:
            sample[4] = None                                           # received now
        elif fault < 0.14:
            position = list(sample[1])
            position[column] = high[0] if fault < 0.13 else np.nextafter(low[0], -np.inf)
            sample[1] = position
    return [tuple(sample) for sample in samples]


def state_of(session: InverseSession) -> tuple:
    """What a batch changes besides the messages: counters, restarts, input and log times."""
    return (session.counters.as_values(), session.estimator.restarts, session.samples, session.silent_ns,
            session._last_taken_ns, session.last_unstamped, session.stamp_ns)


@pytest.mark.parametrize("make, size", [(stream, 5), (driver_stream, 5), (edge_stream, 1), (edge_stream, 2),
                                        (edge_stream, 5)])
def test_the_clean_check_takes_what_the_sample_checks_take(monkeypatch: pytest.MonkeyPatch, make, size: int) -> None:
    samples = make(np.random.default_rng(11), 400)
    clean_calls = []
    original = InverseSession._clean_rows
    monkeypatch.setattr(InverseSession, "_clean_rows",
                        lambda self, batch: clean_calls.append(original(self, batch)) or clean_calls[-1])
    outputs, session, rejected = batched(samples, size, None)
    monkeypatch.setattr(InverseSession, "_clean_rows", lambda self, batch: None)
    expected, reference, expected_rejected = batched(samples, size, None)
    assert [topic for topic, _ in outputs] == [topic for topic, _ in expected]
    assert [to_cdr(message) for _, message in outputs] == [to_cdr(message) for _, message in expected]
    assert state_of(session) == state_of(reference) and rejected == expected_rejected
    taken = sum(call is not None for call in clean_calls)
    assert 0 < taken < len(clean_calls)         # both paths ran
    assert reference.samples > 100 and sum(reference.counters.rejected.values()) > 10


def test_clean_rows_refuses_each_fault_alone() -> None:
    """Each condition of ``clean_rows`` on its own: a stamp 0, at the Time limit, repeated
    (from the batch before, or within), a value beyond its bound by one ulp or NaN; a value
    on its bound and the last Time pass."""
    bounds = np.array([[[[-1.0, -2.0]], [[-3.0, -4.0]]], [[[1.0, 2.0]], [[3.0, 4.0]]]])   # (2, 2, 1, 2)
    stamps = np.array([10, 20, 30], dtype=np.int64)
    values = np.array([[1.0, -2.0], [0.0, 0.0], [-1.0, 2.0], [3.0, -4.0], [0.0, 0.0], [-3.0, 4.0]])
    assert clean_rows(stamps, values, bounds, 5)
    assert clean_rows(np.array([STAMP_LIMIT_NS - 1], dtype=np.int64), values[[0, 3]], bounds, -1)
    for stamp in (0, STAMP_LIMIT_NS):
        assert not clean_rows(np.array([stamp], dtype=np.int64), values[[1, 4]], bounds, -1)
    assert not clean_rows(stamps, values, bounds, 10)                       # as the last one taken
    assert not clean_rows(np.array([10, 20, 20], dtype=np.int64), values, bounds, 5)
    for row, column, side in [(0, 0, 1), (2, 1, 1), (3, 1, 0), (5, 0, 0)]:  # positions then velocities
        beyond = values.copy()
        beyond[row, column] = np.nextafter(bounds[side, row // 3, 0, column], np.inf if side else -np.inf)
        assert not clean_rows(stamps, beyond, bounds, 5), (row, column)
        beyond[row, column] = np.nan
        assert not clean_rows(stamps, beyond, bounds, 5), (row, column)


def test_plausible_rows_counts_the_rows_before_the_first_implausible() -> None:
    """Against numpy's comparison (NaN and inf implausible, a torque on the bound not)."""
    bound = plausible_limit(SCENE.robot)
    rng = np.random.default_rng(5)
    for _ in range(200):
        torques = rng.uniform(-1.2, 1.2, (6, len(bound))) * bound
        row, column = rng.integers(6), rng.integers(len(bound))
        torques[row, column] = rng.choice([np.nan, np.inf, -np.inf, bound[column], -bound[column],
                                           torques[row, column]])
        plausible = (np.abs(torques) <= bound).all(axis=1)
        assert plausible_rows(torques, bound) == (len(torques) if plausible.all() else int(np.argmin(plausible)))
    with pytest.raises(ValueError, match="plausible_rows"):
        plausible_rows(np.zeros((2, len(bound) + 1)), bound)
