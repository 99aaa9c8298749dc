"""Identification's bag input: the joint states read back exactly, and every kind of bad
bag refused with one line naming the bag, the topic and the sample."""
from __future__ import annotations

import numpy as np
import pytest

from youbot_dynamics.cli import main
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.identification.measurements import low_pass, preprocess, read_joint_samples
from youbot_dynamics.io import messages
from youbot_dynamics.io.mcap_log import McapLogger

JOINTS = ("arm_joint_1", "arm_joint_2")
COUNT = 200


def write_bag(path, count=COUNT, *, stamps=None, efforts=True, names=JOINTS, nan_at=None):
    """/joint_states at 100 Hz: q = sin(t), v = cos(t), effort = 2 sin(t), per joint j
    scaled by (j + 1); ``nan_at`` puts a NaN velocity into that sample."""
    stamps = np.arange(count) * 10_000_000 if stamps is None else np.asarray(stamps)
    with McapLogger(path) as log:
        log.add_topic("/joint_states", "sensor_msgs/msg/JointState")
        for k, stamp in enumerate(stamps):
            t, scale = stamp * 1e-9, np.arange(1, len(names) + 1)
            v = scale * np.cos(t)
            if k == nan_at:
                v[-1] = np.nan
            message = messages.joint_state(0, names, scale * np.sin(t), [], 2 * scale * np.sin(t) if efforts else [])
            message.header.stamp.sec, message.header.stamp.nanosec = divmod(int(stamp), 1_000_000_000)
            message.velocity = v
            log.write("/joint_states", message, log_time_ns=int(stamp))
    return path


def test_samples_read_back_by_name(tmp_path):
    bag = write_bag(tmp_path / "ok.mcap")
    samples = read_joint_samples(bag, ("arm_joint_2", "arm_joint_1"))
    t = np.arange(COUNT) * 10_000_000 * 1e-9    # as the writer computed it
    np.testing.assert_allclose(samples.t, t, atol=1e-12)
    np.testing.assert_array_equal(samples.q[:, 0], 2 * np.sin(t))
    np.testing.assert_array_equal(samples.v[:, 1], np.cos(t))
    np.testing.assert_array_equal(samples.effort[:, 0], 4 * np.sin(t))
    assert samples.rate == pytest.approx(100.0, rel=1e-9)


def test_preprocess_differentiates_a_slow_sine(tmp_path):
    """a = d/dt cos(t) = -sin(t) after a 5 Hz low-pass of 100 Hz samples."""
    samples = read_joint_samples(write_bag(tmp_path / "ok.mcap", 1000), JOINTS)
    motion = preprocess(samples, cutoff=5.0)
    inner = slice(motion.kept.start, motion.kept.stop)
    # measured 6.2e-5 rad/s^2 (central differences: h^2/6 = 1.7e-5, plus the filter); bound 1e-3
    np.testing.assert_allclose(motion.a[inner, 0], -np.sin(samples.t[inner]), atol=1e-3)
    assert motion.kept.step == 10 and motion.kept.start == 60      # to 2 x 5 Hz; three cut-off periods of edge
    # the filter passes a 0.16 Hz sine: measured 4.8e-6; bound 2e-5
    np.testing.assert_allclose(low_pass(samples.q, 100.0, 5.0)[inner], samples.q[inner], atol=2e-5)
    # measured states: q and v exactly as recorded, a by central differences of the recorded v
    measured = preprocess(samples, cutoff=5.0, states="measured")
    np.testing.assert_array_equal(measured.q, samples.q)
    np.testing.assert_array_equal(measured.a, np.gradient(samples.v, samples.t, axis=0))
    np.testing.assert_allclose(measured.a[inner, 0], -np.sin(samples.t[inner]), atol=1e-3)   # measured 1.7e-5
    with pytest.raises(UserInputError, match="states 'smoothed': choose from filtered, measured"):
        preprocess(samples, states="smoothed")


@pytest.mark.parametrize("defect, match", [
    (dict(efforts=False), r"/joint_states sample 0 \(stamp 0 ns\): 0 effort entries for 2 joints"),
    (dict(count=20), r"/joint_states: 20 samples, identification needs at least 50"),
    (dict(names=("arm_joint_1", "arm_joint_3")), r"sample 0 .*joint\(s\) arm_joint_2 missing"),
    (dict(nan_at=57), r"/joint_states sample 57 \(stamp 570000000 ns\): velocity of arm_joint_2 is nan"),
    (dict(stamps=np.r_[np.arange(100), 99, np.arange(100, 199)] * 10_000_000),
     r"/joint_states sample 100: stamp 990000000 ns is not after the previous sample's 990000000 ns"),
])
def test_bad_bags_are_one_line_errors(tmp_path, defect, match):
    bag = write_bag(tmp_path / "bad.mcap", **defect)
    with pytest.raises(UserInputError, match=match) as error:
        read_joint_samples(bag, JOINTS)
    assert "\n" not in str(error.value) and str(bag) in str(error.value)


def test_cli_reports_a_bad_bag_on_one_line(tmp_path, capsys):
    bag = write_bag(tmp_path / "bad.mcap", efforts=False)
    assert main(["identify", str(bag), "--joints", ",".join(JOINTS), "--json"]) == 2
    error = capsys.readouterr().err.strip()
    assert error.startswith("youbot-dynamics identify: error: bag ") and "effort" in error
    assert len(error.splitlines()) == 1


def test_a_motion_that_cannot_see_some_parameters_names_them(tmp_path):
    """Joint 2 at rest: its inertia and friction are invisible, and the error says which."""
    from youbot_dynamics import default_urdf
    from youbot_dynamics.identification.identify import identify_motion, layout_for
    from youbot_dynamics.model.robot import load_robot
    samples = read_joint_samples(write_bag(tmp_path / "ok.mcap", 1000), JOINTS)
    still = type(samples)(samples.joint_names, samples.t, samples.q * [1, 0], samples.v * [1, 0], samples.effort)
    layout = layout_for(load_robot(default_urdf()), JOINTS)
    with pytest.raises(UserInputError, match=r"excites only \d+ of \d+ base parameters; it cannot see: .*arm_joint_2"):
        identify_motion(layout, preprocess(still, cutoff=5.0))
