"""Topics refilled together (io/cdr_group.py): each message is byte for byte the one
io.messages builds and rosbags serializes from the same numbers (so the one its own
template refills), and a batch with a value that does not pass falls back to the topics one
by one, which name the field."""
from __future__ import annotations

import numpy as np
import pytest

from youbot_dynamics.io import messages
from youbot_dynamics.io.cdr_group import TopicBatches
from youbot_dynamics.io.cdr_template import Refilled

RNG = np.random.default_rng(5)
STAMPS = [1, 999_999_999, 1_700_000_000_123_456_789, 2_000_000_000_000_000_000]
NAMES = [f"joint_{k}" for k in range(5)]


def cdr(message) -> bytes:
    return bytes(messages.TYPESTORE.serialize_cdr(message, message.__msgtype__))


def poses(count: int) -> np.ndarray:
    rows = RNG.normal(size=(count, 7))
    rows[:, 3:] /= np.linalg.norm(rows[:, 3:], axis=1, keepdims=True)
    return rows


def joint_state(stamp: int, values: np.ndarray):
    return messages.joint_state(stamp, NAMES, *np.split(values, 3))


def tf(stamp: int, values: np.ndarray):
    return messages.tf_message(messages.transform_stamped(stamp, "base", f"link_{k}", row[:3], row[3:])
                               for k, row in enumerate(values.reshape(-1, 7)))


def pose(stamp: int, row: np.ndarray):
    return messages.pose_stamped(stamp, "base", row[:3], row[3:])


BUILDERS = {"/joints": joint_state, "/tf": tf, "/pose": pose}


def entries(refilled: dict, count: int) -> list[tuple]:
    values = {"/joints": RNG.normal(size=(count, 15)), "/tf": poses(3 * count).reshape(count, -1),
              "/pose": poses(count)}
    return [(topic, refilled[topic], values[topic], BUILDERS[topic]) for topic in BUILDERS]


def test_topics_filled_together_are_the_built_messages() -> None:
    """Batches of several sizes in turn, and the same templates under other topic names, are
    each cut into the messages built from their own numbers, named by their own topics."""
    refilled, batches = {topic: Refilled() for topic in BUILDERS}, TopicBatches()
    batches.fill(STAMPS[:1], entries(refilled, 1))                   # the first: built, templates made
    for count, suffix in ((4, ""), (2, ""), (2, "_renamed"), (4, "")):
        batch = [(topic + suffix, *rest) for topic, *rest in entries(refilled, count)]
        filled = batches.fill(STAMPS[:count], batch)
        assert len(batches._groups) == 1                             # filled together
        assert [[topic for topic, _ in sample] for sample in filled] == [[t + suffix for t in BUILDERS]] * count
        for k, (topic, _, values, build) in enumerate(batch):
            assert [sample[k][1].cdr for sample in filled] == [cdr(build(s, row))
                                                               for s, row in zip(STAMPS[:count], values)]


@pytest.mark.parametrize("topic, field", [("/joints", "effort[2]"), ("/pose", "pose.orientation")])
def test_a_value_that_does_not_pass_is_named_by_its_topic(topic: str, field: str) -> None:
    refilled, batches = {topic: Refilled() for topic in BUILDERS}, TopicBatches()
    batches.fill(STAMPS[:1], entries(refilled, 1))
    batch = entries(refilled, 2)
    values = dict((t, v) for t, _, v, _ in batch)[topic]
    values[1, 12 if topic == "/joints" else 5] = np.nan if topic == "/joints" else 3.0
    with pytest.raises(messages.MessageFieldError, match=field.replace("[", r"\[").replace("]", r"\]")):
        batches.fill(STAMPS[:2], batch)
