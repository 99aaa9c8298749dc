"""Reading bags for replay: bags from another writer, broken bags, and replay pacing."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.io import messages
from youbot_dynamics.io.bag_reader import BagMessage, BagTopic, bag_topics, paced, read_bag
from youbot_dynamics.io.mcap_log import McapLogger
from youbot_dynamics.node.interface import QOS

JOINTS = ["arm_joint_1", "arm_joint_2"]


def qos(durability: QosDurability) -> Qos:
    never = QosTime(0, 0)
    return Qos(
        QosHistory.KEEP_LAST, 1, QosReliability.RELIABLE, durability,
        never, never, QosLiveliness.AUTOMATIC, never, False,
    )


@pytest.fixture(scope="module")
def rosbags_bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A rosbag2 folder (MCAP storage, metadata.yaml) written by rosbags' own Writer.

    Messages are built with a fresh typestore and classes of rosbags, not ``io.messages``.
    """
    store = get_typestore(Stores.ROS2_JAZZY)
    JointState = store.types["sensor_msgs/msg/JointState"]
    Header = store.types["std_msgs/msg/Header"]
    Time = store.types["builtin_interfaces/msg/Time"]
    Clock = store.types["rosgraph_msgs/msg/Clock"]
    path = tmp_path_factory.mktemp("bags") / "recorded"
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        states = writer.add_connection(
            "/joint_states", JointState.__msgtype__, typestore=store,
            offered_qos_profiles=[qos(QosDurability.VOLATILE)],
        )
        clock = writer.add_connection(
            "/clock", Clock.__msgtype__, typestore=store,
            offered_qos_profiles=[qos(QosDurability.TRANSIENT_LOCAL)],
        )
        for k in range(5):
            t = 1_000_000_000 + k * 10_000_000
            stamp = Time(sec=t // 10**9, nanosec=t % 10**9)
            msg = JointState(
                header=Header(stamp=stamp, frame_id=""), name=JOINTS,
                position=np.array([0.5 * k, -0.25 * k]), velocity=np.array([1.0, 2.0]),
                effort=np.array([], dtype=np.float64),
            )
            writer.write(states, t, store.serialize_cdr(msg, msg.__msgtype__))
            writer.write(clock, t, store.serialize_cdr(Clock(clock=stamp), Clock.__msgtype__))
    return path


def test_reads_a_rosbag2_folder_from_rosbags_writer(rosbags_bag: Path) -> None:
    assert (rosbags_bag / "metadata.yaml").is_file()
    got = list(read_bag(rosbags_bag))
    states = [m for m in got if m.topic == "/joint_states"]
    assert [m.log_time_ns for m in got] == sorted(m.log_time_ns for m in got)
    assert len(states) == 5 and sum(m.topic == "/clock" for m in got) == 5
    for k, m in enumerate(states):
        assert isinstance(m, BagMessage)
        assert m.msgtype == "sensor_msgs/msg/JointState"
        assert m.log_time_ns == 1_000_000_000 + k * 10_000_000
        assert list(m.message.name) == JOINTS
        assert m.message.position.tolist() == [0.5 * k, -0.25 * k]
        assert m.message.effort.size == 0


def test_lists_topics_with_counts_and_latching(rosbags_bag: Path) -> None:
    assert sorted(bag_topics(rosbags_bag)) == [
        BagTopic("/clock", "rosgraph_msgs/msg/Clock", 5, True),
        BagTopic("/joint_states", "sensor_msgs/msg/JointState", 5, False),
    ]


def test_reads_a_single_mcap_file_from_mcap_logger(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    with McapLogger(path) as log:
        log.add_topic("/joint_states", "sensor_msgs/msg/JointState")
        log.add_topic("/tf_static", "tf2_msgs/msg/TFMessage", qos=QOS["latched"])
        log.write("/tf_static", messages.tf_message([]), 0)
        for k in range(3):
            log.write("/joint_states", messages.joint_state(k, JOINTS, [k / 3, 1.0]), 10 + k)
    got = list(read_bag(path))
    assert [(m.topic, m.log_time_ns) for m in got] == [
        ("/tf_static", 0), ("/joint_states", 10), ("/joint_states", 11), ("/joint_states", 12)
    ]
    assert got[3].message.position.tolist() == [2 / 3, 1.0]
    assert BagTopic("/tf_static", "tf2_msgs/msg/TFMessage", 1, True) in bag_topics(path)


@pytest.fixture
def broken_bags(tmp_path: Path, rosbags_bag: Path) -> dict[str, Path]:
    mcap = next(rosbags_bag.glob("*.mcap")).read_bytes()
    truncated = tmp_path / "truncated.mcap"
    truncated.write_bytes(mcap[: len(mcap) // 2])
    garbage = tmp_path / "garbage.mcap"
    garbage.write_bytes(b"this is not a bag\n" * 10)
    empty_folder = tmp_path / "folder"
    empty_folder.mkdir()
    return {
        "missing": tmp_path / "missing.mcap",
        "truncated": truncated,
        "garbage": garbage,
        "folder without metadata.yaml": empty_folder,
    }


@pytest.mark.parametrize("kind", ["missing", "truncated", "garbage", "folder without metadata.yaml"])
def test_broken_bags_raise_user_input_error_naming_the_file(broken_bags, kind: str) -> None:
    path = broken_bags[kind]
    with pytest.raises(UserInputError, match=str(path)):
        list(read_bag(path))
    with pytest.raises(UserInputError, match=str(path)):
        bag_topics(path)


class FakeClock:
    """A clock that only moves when someone sleeps or works; records the sleeps."""

    def __init__(self) -> None:
        self.now = 100.0
        self.sleeps: list[float] = []

    def __call__(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        self.sleeps.append(seconds)
        self.now += seconds


def stamped(*times_s: float) -> list[BagMessage]:
    return [BagMessage("/t", "x/msg/Y", round(t * 1e9), None) for t in times_s]


def test_paced_keeps_recorded_spacing_scaled_by_rate() -> None:
    clock = FakeClock()
    yielded = [
        (clock.now, m.log_time_ns)
        for m in paced(stamped(5.0, 6.0, 6.5, 8.0), rate=2.0, clock=clock, sleep=clock.sleep)
    ]
    assert [when for when, _ in yielded] == pytest.approx([100.0, 100.5, 100.75, 101.5], abs=1e-12)
    assert clock.sleeps == pytest.approx([0.5, 0.25, 0.75], abs=1e-12)


def test_paced_does_not_sleep_when_the_consumer_is_late() -> None:
    clock = FakeClock()
    yielded = []
    for m in paced(stamped(0.0, 1.0, 2.0, 3.0), rate=1.0, clock=clock, sleep=clock.sleep):
        yielded.append(clock.now)
        clock.now += 1.5 if len(yielded) == 1 else 0.1  # the first message takes 1.5 s to handle
    assert yielded == pytest.approx([100.0, 101.5, 102.0, 103.0], abs=1e-12)
    assert clock.sleeps == pytest.approx([0.4, 0.9], abs=1e-12)


def test_paced_as_fast_as_possible_never_sleeps() -> None:
    clock = FakeClock()
    items = stamped(0.0, 10.0, 20.0)
    assert list(paced(items, rate=None, clock=clock, sleep=clock.sleep)) == items
    assert clock.sleeps == []


@pytest.mark.parametrize("rate", [0.0, -1.0, float("nan"), float("inf")])
def test_paced_rejects_bad_rates(rate: float) -> None:
    with pytest.raises(UserInputError, match="rate"):
        paced(stamped(0.0), rate=rate)
