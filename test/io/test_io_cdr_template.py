"""CDR templates (io/cdr_template.py): a refilled message is byte for byte the one
io.messages builds and rosbags serializes from the same numbers, it is checked as a built
one is (nothing non-finite, unit quaternions), and a Serialized message reads as the
rosbags message."""
from __future__ import annotations

import numpy as np
import pytest

from youbot_dynamics.dynamics.collision import Shape
from youbot_dynamics.io import messages
from youbot_dynamics.io.cdr_template import CdrTemplate, Refilled, Serialized
from youbot_dynamics.model.lie import matrix_from_quaternion
from youbot_dynamics.node.frame_messages import marker_stamped

RNG = np.random.default_rng(3)
STAMPS = [0, 1, 999_999_999, 1_700_000_000_123_456_789]


def poses(count: int) -> np.ndarray:
    """(count, 7) random translations and unit quaternions (x, y, z, w)."""
    rows = RNG.normal(size=(count, 7))
    rows[:, 3:] /= np.linalg.norm(rows[:, 3:], axis=1, keepdims=True)
    return rows


def cdr(message) -> bytes:
    return bytes(messages.TYPESTORE.serialize_cdr(message, message.__msgtype__))


def tf(stamp: int, rows: np.ndarray):
    return messages.tf_message(messages.transform_stamped(stamp, f"parent_{k}", f"child_{k}", row[:3], row[3:])
                               for k, row in enumerate(rows))


def markers(stamp: int, rows: np.ndarray):
    shape = Shape("capsule", radius=0.02, length=0.1)
    out = []
    for k, row in enumerate(rows):
        pose = np.eye(4)
        pose[:3, :3] = matrix_from_quaternion(row[3:])
        pose[:3, 3] = row[:3]
        out += messages.shape_markers(stamp, "world", f"body_{k}", shape, pose, (1.0, 0.5, 0.2, 1.0))
    return messages.marker_array(out)


@pytest.mark.parametrize("stamp", STAMPS)
def test_a_refilled_tf_is_the_built_one(stamp: int) -> None:
    template = CdrTemplate(tf(5, poses(15)), lambda path: ".transform." in path)
    rows = poses(15)
    refilled = template.fill(stamp, rows)
    assert refilled.cdr == cdr(tf(stamp, rows))
    assert refilled.transforms[3].child_frame_id == "child_3"          # reads as the message
    assert refilled.transforms[3].transform.rotation.w == rows[3, 6]


def test_a_refilled_joint_state_and_pose_array_are_the_built_ones() -> None:
    names = [f"joint_{k}" for k in range(7)]
    values = RNG.normal(size=(4, 21))
    built = [messages.joint_state(s, names, *np.split(row, 3)) for s, row in zip(STAMPS, values)]
    template = CdrTemplate(messages.joint_state(0, names, *np.split(np.zeros(21), 3)), lambda path: True)
    assert [m.cdr for m in template.fill_many(STAMPS, values)] == [cdr(m) for m in built]
    rows = poses(3)
    array = CdrTemplate(messages.pose_array(0, "world", [(r[:3], r[3:]) for r in poses(3)]), lambda path: True)
    assert array.fill(7, rows).cdr == cdr(messages.pose_array(7, "world", [(r[:3], r[3:]) for r in rows]))


def test_markers_refill_their_poses_only() -> None:
    first, rows = poses(2), poses(2)
    template = CdrTemplate(markers(0, first), lambda path: ".pose." in path, marker_stamped)
    built = markers(11, rows)
    values = np.concatenate([[m.pose.position.x, m.pose.position.y, m.pose.position.z, m.pose.orientation.x,
                              m.pose.orientation.y, m.pose.orientation.z, m.pose.orientation.w]
                             for m in built.markers])
    assert template.fill(11, values).cdr == cdr(built)


def test_refilled_values_are_checked_like_built_ones() -> None:
    template = CdrTemplate(tf(0, poses(3)), lambda path: ".transform." in path)
    rows = poses(3)
    rows[1, 2] = np.nan
    with pytest.raises(messages.MessageFieldError, match=r"transforms\[1\]\.transform\.translation\.z"):
        template.fill(1, rows)
    rows = poses(3)
    rows[2, 3:] *= 1.01
    with pytest.raises(messages.MessageFieldError, match=r"transforms\[2\]\.transform\.rotation: has norm 1\.01"):
        template.fill(1, rows)
    with pytest.raises(messages.MessageFieldError, match="stamp"):
        template.fill(-1, poses(3))
    with pytest.raises(messages.MessageFieldError, match="stamp"):
        template.fill(2**31 * 10**9, poses(3))
    with pytest.raises(messages.MessageFieldError, match="stamp"):
        template.fill_many([1, -1], np.array([poses(3).reshape(-1)] * 2))
    with pytest.raises(messages.MessageFieldError, match="stamp"):
        template.fill_many([1, 2.0], np.array([poses(3).reshape(-1)] * 2))


def test_refilled_builds_the_first_message_and_refills_the_next() -> None:
    refilled, built = Refilled(), []

    def build(stamp, row):
        built.append(stamp)
        return messages.pose_stamped(stamp, "world", row[:3], row[3:])

    rows = poses(3)
    first = refilled(1, rows[0], build)
    later = refilled.many([2, 3], rows[1:], build)
    assert built == [1] and not isinstance(first, Serialized) and all(isinstance(m, Serialized) for m in later)
    assert [m.cdr for m in later] == [cdr(messages.pose_stamped(s, "world", r[:3], r[3:]))
                                      for s, r in zip([2, 3], rows[1:])]
    assert cdr(first) == cdr(messages.pose_stamped(1, "world", rows[0, :3], rows[0, 3:]))
