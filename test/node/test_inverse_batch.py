"""Inverse mode on a batch of joint states (``InverseSession.joint_states``: checks,
differences and Pinocchio's batch RNEA as arrays) against the same samples taken one by one
(``joint_state``: batches of one, so a fault restarts the estimate at its own sample whatever
the batch): the same messages in the same order, bit for bit,
the same counters and estimator restarts, whatever the stream holds (gaps, stamps going
back, unstamped samples, NaN, unknown or missing joints, velocity jumps that give
implausible torques)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from youbot_dynamics.node.commands import InputRejected
from youbot_dynamics.node.inverse_session import InverseSession
from youbot_dynamics.ros.conversions import to_cdr
from youbot_dynamics.scene.schema import load_scene

SCENE = load_scene("arm_ptp")
PERIOD_NS = 2_000_000


def stream(rng: np.random.Generator, count: int) -> list[tuple]:
    """(names, position, velocity, stamp_ns, received_ns) of a 500 Hz stream with faults."""
    names = list(SCENE.robot.joint_names)
    q0 = np.array(SCENE.q0)
    samples, stamp = [], 0
    for k in range(count):
        stamp += PERIOD_NS
        t = stamp * 1e-9
        q, v = q0 + 0.2 * np.sin(3 * t + np.arange(5)), 0.6 * np.cos(3 * t + np.arange(5))
        fault = rng.random()
        sample = [names, q.tolist(), v.tolist(), stamp, stamp + 7]
        if fault < 0.03:
            sample[1] = [*q[:4], np.nan]                      # non_finite
        elif fault < 0.05:
            sample[0] = [*names[:4], "no_such_joint"]         # unknown_joint
        elif fault < 0.07:
            sample[3] = stamp - 5 * PERIOD_NS                 # backwards
        elif fault < 0.09:
            stamp += 200_000_000                              # a gap
            sample[3] = stamp
        elif fault < 0.11:
            sample[2] = (v + 3.0).tolist()                    # a velocity step: implausible torque
        elif fault < 0.13:
            sample[3] = 0                                     # unstamped
        elif fault < 0.14:
            sample[0], sample[1], sample[2] = names[:4], q[:4].tolist(), v[:4].tolist()   # missing_joint
        elif fault < 0.15:
            sample[0] = list(reversed(names))                 # another order: matched by name
            sample[1], sample[2] = q[::-1].tolist(), v[::-1].tolist()
        samples.append(tuple(sample))
    return samples


def one_by_one(samples: list[tuple], consumed: set[str] | None, time_constant: float = 0.0
               ) -> tuple[list, InverseSession]:
    session = InverseSession(SCENE, filter_time_constant=time_constant)
    session.consumed_by(consumed)
    outputs = []
    for sample in samples:
        try:
            outputs += session.joint_state(*sample)
        except InputRejected:
            pass
    return outputs, session


def batched(samples: list[tuple], size: int, consumed: set[str] | None, time_constant: float = 0.0
            ) -> tuple[list, InverseSession, int]:
    session = InverseSession(SCENE, filter_time_constant=time_constant)
    session.consumed_by(consumed)
    outputs, rejected = [], 0
    for start in range(0, len(samples), size):
        out, errors = session.joint_states(samples[start:start + size])
        outputs += out
        rejected += len(errors)
    return outputs, session, rejected


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("size", [1, 2, 7, 64])
@pytest.mark.parametrize("consumed", [None, {"/computed_torques"}])     # every topic; the torques alone
def test_a_batch_gives_what_one_by_one_gives(seed: int, size: int, consumed: set[str] | None) -> None:
    samples = stream(np.random.default_rng(seed), 300)
    expected, reference = one_by_one(samples, consumed)
    outputs, session, rejected = batched(samples, size, consumed)
    assert [topic for topic, _ in outputs] == [topic for topic, _ in expected]
    assert [to_cdr(message) for _, message in outputs] == [to_cdr(message) for _, message in expected]
    assert session.counters.as_values() == reference.counters.as_values()
    assert session.estimator.restarts == reference.estimator.restarts
    assert rejected == sum(reference.counters.rejected.values()) - reference.counters.rejected.get(
        "implausible_torque", 0) - reference.estimator.restarts["non_finite"]
    assert reference.samples == session.samples > 100       # the stream did give torques
    assert reference.counters.rejected.get("implausible_torque", 0) > 0   # and the faults happened
    assert reference.estimator.restarts["gap"] > 0 and reference.estimator.restarts["backwards"] > 0


@pytest.mark.parametrize("size", [2, 5, 64])
def test_a_filtered_batch_gives_what_one_by_one_gives(size: int) -> None:
    """With the acceleration low-pass (each estimate filtered from the last) too."""
    samples = stream(np.random.default_rng(3), 300)
    expected, reference = one_by_one(samples, {"/computed_torques"}, 0.02)
    outputs, session, _ = batched(samples, size, {"/computed_torques"}, 0.02)
    assert [to_cdr(message) for _, message in outputs] == [to_cdr(message) for _, message in expected]
    assert session.counters.as_values() == reference.counters.as_values()
    assert session.estimator.restarts == reference.estimator.restarts
    assert reference.samples == session.samples > 100


def driver_stream(rng: np.random.Generator, count: int) -> list[tuple]:
    """A stream as a driver publishes it: every joint of the robot named (wheels and fingers,
    which do not move in the scene, too), not in joint order, with faults in those columns
    and velocities at and beyond the plausible bound (10 x the URDF limit)."""
    arm = list(SCENE.robot.joint_names)
    names = ["wheel_joint_fl", "wheel_joint_fr", *reversed(arm), "gripper_finger_joint_l", "gripper_finger_joint_r"]
    column = {name: names.index(name) for name in arm}
    bound = 10.0 * np.asarray(SCENE.robot.velocity_limit)
    samples, stamp = [], 0
    for k in range(count):
        stamp += PERIOD_NS
        t = stamp * 1e-9
        position, velocity = np.zeros(len(names)), np.full(len(names), 0.01)
        for i, name in enumerate(arm):
            position[column[name]] = SCENE.q0[i] + 0.2 * np.sin(3 * t + i)
            velocity[column[name]] = 0.6 * np.cos(3 * t + i)
        fault = rng.random()
        if fault < 0.03:
            position[0] = np.inf                                  # a wheel: non_finite
        elif fault < 0.06:
            velocity[-1] = np.nan                                 # a finger: non_finite
        elif fault < 0.08:
            velocity[column[arm[1]]] = bound[1]                   # at the bound: taken
        elif fault < 0.10:
            velocity[column[arm[2]]] = -np.nextafter(bound[2], np.inf)   # beyond it: out_of_limits
        samples.append((names, position.tolist(), velocity.tolist(), stamp, stamp + 7))
    return samples


@pytest.mark.parametrize("size", [2, 5, 64])
def test_a_batch_of_a_driver_stream_gives_what_one_by_one_gives(size: int) -> None:
    """Names in another order and of joints that do not move: the array checks (finite on
    every column, the velocity bound on the moving joints') reject what ``joint_state``
    rejects, with the same kind, and the torques are the same to the bit."""
    samples = driver_stream(np.random.default_rng(7), 300)
    expected, reference = one_by_one(samples, {"/computed_torques"})
    outputs, session, rejected = batched(samples, size, {"/computed_torques"})
    assert [to_cdr(message) for _, message in outputs] == [to_cdr(message) for _, message in expected]
    assert session.counters.as_values() == reference.counters.as_values()
    assert session.estimator.restarts == reference.estimator.restarts
    assert reference.counters.rejected["non_finite"] > 0 and reference.counters.rejected["out_of_limits"] > 0
    assert reference.samples == session.samples > 100


@pytest.mark.parametrize("size", [1, 3])
def test_a_position_beyond_a_double_is_rejected_and_a_nan_receive_time_is_now(size: int) -> None:
    """Odd input through the Python API (a topic carries doubles): an int position beyond the
    largest double is a non_finite rejection, as a NaN there is (the same torques after it),
    and a NaN receive time is taken as "received now" (the torques of
    the sample without a receive time); nothing raises."""
    names = list(SCENE.robot.joint_names)
    samples = [s for s in stream(np.random.default_rng(0), 20) if s[0] == names and s[3]
               and np.isfinite(s[1]).all()][:6]
    huge, nan, late, unreceived = (list(samples[4]) for _ in range(4))
    huge[1], nan[1] = [10 ** 400, *huge[1][1:]], [math.nan, *nan[1][1:]]
    late[4], unreceived[4] = float("nan"), None

    def torques(fed: list[tuple]) -> tuple[list[bytes], list[str]]:
        session = InverseSession(SCENE, filter_time_constant=0.0)
        session.consumed_by({"/computed_torques"})
        session.joint_states(samples[:3])
        out, rejected = [], []
        for k in range(0, len(fed), size):
            messages, errors = session.joint_states(fed[k:k + size])
            out += [to_cdr(m[1]) for m in messages if m[0] == "/computed_torques"]
            rejected += [e.kind for e in errors]
        return out, rejected

    assert torques([samples[3], tuple(huge), samples[5]]) == torques([samples[3], tuple(nan), samples[5]])
    assert torques([samples[3], tuple(huge), samples[5]])[1] == ["non_finite"]
    assert torques([samples[3], tuple(late), samples[5]]) == (torques([samples[3], tuple(unreceived), samples[5]])[0],
                                                             [])
