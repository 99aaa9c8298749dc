"""MCAP logs in rosbag2 form, checked with independent readers.

A log with every topic the node writes is read back with rosbags' AnyReader, with the MCAP
reference reader plus mcap_ros2's CDR decoder, and with Rerun's MCAP reader; values must
come back exactly, schemas, QoS metadata and summary statistics must be as rosbag2 writes
them, and type hashes must equal those shipped with the ROS 2 interface packages.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader
from mcap.writer import Writer
from mcap_ros2.decoder import DecoderFactory
from rosbags.highlevel import AnyReader
from rosbags.interfaces import QosDurability

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.io import messages
from youbot_dynamics.io.mcap_log import McapLogger
from youbot_dynamics.io.mcap_writer import ChunkedWriter
from youbot_dynamics.io.qos import DEFAULT
from youbot_dynamics.node.interface import QOS

JOINTS = ["arm_joint_1", "arm_joint_2", "arm_joint_3"]
LINKS = [("base_link", "arm_link_1"), ("arm_link_1", "arm_link_2"), ("arm_link_2", "arm_link_3")]
N_SAMPLES = 40
DT_NS = 2_000_000  # 500 Hz
DIAGNOSTICS_EVERY = 10
TOPICS = {
    "/joint_states": "sensor_msgs/msg/JointState",
    "/ee_pose": "geometry_msgs/msg/PoseStamped",
    "/tf": "tf2_msgs/msg/TFMessage",
    "/tf_static": "tf2_msgs/msg/TFMessage",
    "/clock": "rosgraph_msgs/msg/Clock",
    "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray",
}
EXPECTED_COUNTS = {
    "/joint_states": N_SAMPLES,
    "/ee_pose": N_SAMPLES,
    "/tf": N_SAMPLES,
    "/tf_static": 1,
    "/clock": N_SAMPLES,
    "/diagnostics": N_SAMPLES // DIAGNOSTICS_EVERY,
}
PUBLISH_LAG_NS = 17  # publish time = log time - 17 ns, to tell the two apart


def sample(k: int) -> dict:
    """Plain reference data of sample k (irrational-looking values, exactly reproducible)."""
    t = k * DT_NS
    q = np.array([math.sin(0.1 * k + j) for j in range(3)])
    half = 0.05 * k
    return {
        "t": t,
        "q": q,
        "v": np.cos(q) / 3.0,
        "tau": q * 7.25 - 1.0 / 3.0,
        "ee": np.array([0.1 * k, -0.2, 1.0 / 7.0]),
        "quat": np.array([0.0, 0.0, math.sin(half), math.cos(half)]),
        "energy": 1.0 / (k + 3),
    }


def write_log(path: Path) -> None:
    with McapLogger(path) as log:
        for topic, msgtype in TOPICS.items():
            log.add_topic(topic, msgtype, qos=QOS["latched"] if topic == "/tf_static" else DEFAULT)
        log.write(
            "/tf_static",
            messages.tf_message(
                [messages.transform_stamped(0, "base_footprint", "base_link", [0, 0, 0.084], [0, 0, 0, 1])]
            ),
            0,
        )
        for k in range(N_SAMPLES):
            s = sample(k)
            t = s["t"]
            log.write("/clock", messages.clock(t), t, t - PUBLISH_LAG_NS if t else 0)
            log.write("/joint_states", messages.joint_state(t, JOINTS, s["q"], s["v"], s["tau"]), t)
            log.write("/ee_pose", messages.pose_stamped(t, "base_link", s["ee"], s["quat"]), t)
            transforms = [
                messages.transform_stamped(t, parent, child, [0.0, 0.0, 0.1 * (j + 1)], s["quat"])
                for j, (parent, child) in enumerate(LINKS)
            ]
            log.write("/tf", messages.tf_message(transforms), t)
            if k % DIAGNOSTICS_EVERY == 0:
                status = messages.diagnostic_status(
                    "youbot_dynamics: simulator", "OK", "running", "sim",
                    {"energy": s["energy"], "steps": k},
                )
                log.write("/diagnostics", messages.diagnostic_array(t, [status]), t)


@pytest.fixture(scope="module")
def log_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("mcap") / "run.mcap"
    write_log(path)
    return path


def stamp_ns(stamp) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def check_sample_messages(by_topic: dict[str, list], as_list) -> None:
    """Compare decoded messages (rosbags or mcap_ros2 objects) with the reference exactly."""
    for k, msg in enumerate(by_topic["/joint_states"]):
        s = sample(k)
        assert stamp_ns(msg.header.stamp) == s["t"]
        assert list(msg.name) == JOINTS
        assert as_list(msg.position) == s["q"].tolist()
        assert as_list(msg.velocity) == s["v"].tolist()
        assert as_list(msg.effort) == s["tau"].tolist()
    for k, msg in enumerate(by_topic["/ee_pose"]):
        s = sample(k)
        p, o = msg.pose.position, msg.pose.orientation
        assert msg.header.frame_id == "base_link"
        assert [p.x, p.y, p.z] == s["ee"].tolist()
        assert [o.x, o.y, o.z, o.w] == s["quat"].tolist()
    for k, msg in enumerate(by_topic["/tf"]):
        assert [(tf.header.frame_id, tf.child_frame_id) for tf in msg.transforms] == LINKS
        assert [tf.transform.translation.z for tf in msg.transforms] == [0.1, 0.2, 0.1 * 3]
        assert msg.transforms[2].transform.rotation.w == sample(k)["quat"][3]
    for k, msg in enumerate(by_topic["/clock"]):
        assert stamp_ns(msg.clock) == sample(k)["t"]
    (static,) = by_topic["/tf_static"]
    assert static.transforms[0].child_frame_id == "base_link"
    assert static.transforms[0].transform.translation.z == 0.084
    for i, msg in enumerate(by_topic["/diagnostics"]):
        k = i * DIAGNOSTICS_EVERY
        (status,) = msg.status
        assert status.name == "youbot_dynamics: simulator"
        assert status.level in (0, b"\x00")
        values = {kv.key: kv.value for kv in status.values}
        assert float(values["energy"]) == sample(k)["energy"]
        assert values["steps"] == str(k)
    assert {topic: len(msgs) for topic, msgs in by_topic.items()} == EXPECTED_COUNTS


def test_reads_back_with_rosbags_anyreader(log_path: Path) -> None:
    by_topic: dict[str, list] = {topic: [] for topic in TOPICS}
    with AnyReader([log_path]) as reader:
        assert {c.topic: c.msgtype for c in reader.connections} == TOPICS
        qos = {c.topic: c.ext.offered_qos_profiles for c in reader.connections}
        for connection, log_time, raw in reader.messages():
            by_topic[connection.topic].append(reader.deserialize(raw, connection.msgtype))
    assert [p.durability for p in qos["/tf_static"]] == [QosDurability.TRANSIENT_LOCAL]
    assert [p.durability for p in qos["/joint_states"]] == [QosDurability.VOLATILE]
    check_sample_messages(by_topic, lambda a: np.asarray(a).tolist())


def test_reads_back_with_mcap_ros2_decoder(log_path: Path) -> None:
    by_topic: dict[str, list] = {topic: [] for topic in TOPICS}
    clock_times = []
    with log_path.open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        for _, channel, message, decoded in reader.iter_decoded_messages(log_time_order=True):
            by_topic[channel.topic].append(decoded)
            if channel.topic == "/clock":
                clock_times.append((message.log_time, message.publish_time))
    check_sample_messages(by_topic, list)
    assert clock_times[1:] == [(s, s - PUBLISH_LAG_NS) for s in range(DT_NS, N_SAMPLES * DT_NS, DT_NS)]


def test_schemas_channels_and_statistics_are_rosbag2_form(log_path: Path) -> None:
    with log_path.open("rb") as stream:
        reader = make_reader(stream)
        header = reader.get_header()
        summary = reader.get_summary()
    assert header.profile == "ros2"
    schemas = {s.id: s for s in summary.schemas.values()}
    assert sorted(s.name for s in schemas.values()) == sorted(set(TOPICS.values()))
    for schema in schemas.values():
        assert schema.encoding == "ros2msg"
    tf_text = next(s for s in schemas.values() if s.name == "tf2_msgs/msg/TFMessage").data.decode()
    assert tf_text.startswith("geometry_msgs/TransformStamped[] transforms\n")
    assert "\n" + "=" * 80 + "\nMSG: geometry_msgs/TransformStamped\n" in tf_text
    assert "\n" + "=" * 80 + "\nMSG: std_msgs/Header\n" in tf_text
    channels = {c.topic: c for c in summary.channels.values()}
    assert set(channels) == set(TOPICS)
    for topic, channel in channels.items():
        assert channel.message_encoding == "cdr"
        assert schemas[channel.schema_id].name == TOPICS[topic]
        (profile,) = yaml.safe_load(channel.metadata["offered_qos_profiles"])
        assert profile["reliability"] == "reliable"
        assert profile["durability"] == ("transient_local" if topic == "/tf_static" else "volatile")
    stats = summary.statistics
    counts = {summary.channels[cid].topic: n for cid, n in stats.channel_message_counts.items()}
    assert counts == EXPECTED_COUNTS
    assert stats.message_count == sum(EXPECTED_COUNTS.values())
    assert (stats.message_start_time, stats.message_end_time) == (0, (N_SAMPLES - 1) * DT_NS)


def test_topic_type_hashes_match_the_ros_interface_packages(log_path: Path) -> None:
    """The RIHS01 hash of each type equals the one in share/<pkg>/msg/<Type>.json."""
    with log_path.open("rb") as stream:
        channels = make_reader(stream).get_summary().channels.values()
    checked = 0
    for channel in channels:
        package, _, name = TOPICS[channel.topic].split("/")
        reference = Path(sys.prefix, "share", package, "msg", f"{name}.json")
        if not reference.is_file():  # tf2_msgs is not shipped on PyPI
            continue
        hashes = {h["type_name"]: h["hash_string"] for h in json.loads(reference.read_text())["type_hashes"]}
        assert channel.metadata["topic_type_hash"] == hashes[TOPICS[channel.topic]]
        checked += 1
    if checked == 0:
        pytest.skip("no ROS 2 interface type descriptions under sys.prefix/share")
    assert checked >= 4


def test_reads_back_with_rerun_mcap_reader(log_path: Path) -> None:
    mcap_reader = pytest.importorskip("rerun.chunk").McapReader(log_path)
    info = mcap_reader.info()
    assert info.profile == "ros2"
    assert {c.topic: c.message_count for c in info.channels} == EXPECTED_COUNTS
    rows: dict[str, int] = {}
    for chunk in mcap_reader.stream():
        rows[chunk.entity_path] = rows.get(chunk.entity_path, 0) + chunk.num_rows
    assert rows["/joint_states/position"] == N_SAMPLES


def test_close_is_idempotent_and_finalises(tmp_path: Path) -> None:
    log = McapLogger(tmp_path / "sub" / "a.mcap")
    log.add_topic("/clock", "rosgraph_msgs/msg/Clock")
    log.write("/clock", messages.clock(5), 5)
    log.close()
    log.close()
    assert log.closed
    with pytest.raises(RuntimeError, match="closed"):
        log.write("/clock", messages.clock(6), 6)
    with (tmp_path / "sub" / "a.mcap").open("rb") as stream:
        assert make_reader(stream).get_summary().statistics.message_count == 1



@pytest.mark.parametrize("chunk_size", [1024 * 1024, 300])
def test_chunked_writer_writes_what_mcap_writer_writes(tmp_path: Path, chunk_size: int) -> None:
    """The same calls through mcap's Writer and ChunkedWriter give the same file, byte for
    byte: chunks closed by flush, by size (300 bytes: every few messages) and at the end,
    log times going back within a chunk (a reset), a schema registered mid-run, a flush
    with nothing pending, a channel without messages."""
    def calls(writer, add) -> None:
        writer.start(profile="ros2", library="test")
        clock = writer.register_schema(name="rosgraph_msgs/msg/Clock", encoding="ros2msg", data=b"clock")
        channels = [writer.register_channel(topic=f"/c{k}", message_encoding="cdr", schema_id=clock,
                                            metadata={"k": str(k)}) for k in range(3)]
        for k in range(60):
            log_time = (k if k < 40 else k - 25) * 1_000_000
            add(writer, [(channels[j], bytes([k, j]) * (k % 7)) for j in range(2 if k % 3 else 1)],
                log_time, log_time + 5)
            if k in (10, 11, 50):
                writer.flush()
            if k == 20:
                string = writer.register_schema(name="std_msgs/msg/String", encoding="ros2msg", data=b"string")
                channels.append(writer.register_channel(topic="/s", message_encoding="cdr", schema_id=string))
        writer.finish()

    sequences: dict[int, int] = {}

    def mcap_add(writer: Writer, records, log_time: int, publish_time: int) -> None:
        for channel, data in records:
            sequences[channel] = sequences.get(channel, 0) + 1
            writer.add_message(channel_id=channel, log_time=log_time, data=data, publish_time=publish_time,
                               sequence=sequences[channel])

    with (tmp_path / "mcap.mcap").open("wb") as stream:
        calls(Writer(stream, chunk_size=chunk_size), mcap_add)
    with (tmp_path / "ours.mcap").open("wb") as stream:
        calls(ChunkedWriter(stream, chunk_size=chunk_size),
              lambda writer, records, log_time, publish_time: writer.add_messages(records, log_time, publish_time))
    assert (tmp_path / "ours.mcap").read_bytes() == (tmp_path / "mcap.mcap").read_bytes()

@pytest.mark.parametrize(
    ("topic", "msgtype", "message", "match"),
    [
        ("/nope", None, messages.clock(1), "was not added"),
        ("/clock", "rosgraph_msgs/msg/Clock", messages.joint_state(0, ["a"], [0.0]), "carries"),
    ],
)
def test_write_refuses_unknown_topics_and_wrong_types(tmp_path, topic, msgtype, message, match) -> None:
    with McapLogger(tmp_path / "b.mcap") as log:
        if msgtype:
            log.add_topic(topic, msgtype)
        with pytest.raises(UserInputError, match=match):
            log.write(topic, message, 1)


def test_add_topic_refuses_unknown_type_and_retyping(tmp_path: Path) -> None:
    with McapLogger(tmp_path / "c.mcap") as log:
        with pytest.raises(UserInputError, match="unknown message type"):
            log.add_topic("/x", "nope_msgs/msg/Nothing")
        log.add_topic("/x", "rosgraph_msgs/msg/Clock")
        with pytest.raises(UserInputError, match="already has type"):
            log.add_topic("/x", "sensor_msgs/msg/JointState")


NAN, INF = float("nan"), float("inf")


@pytest.mark.parametrize(
    ("build", "field"),
    [
        (lambda: messages.joint_state(0, JOINTS, [0, 0, 0], [0, NAN, 0], []), "JointState.velocity[1]"),
        (lambda: messages.joint_state(0, JOINTS, [0, 0, INF]), "JointState.position[2]"),
        (lambda: messages.joint_state(0, JOINTS, [0, 0, 0], [], [-INF, 0, 0]), "JointState.effort[0]"),
        (lambda: messages.joint_state(0, JOINTS, [0, 0]), "JointState.position"),
        (lambda: messages.joint_state(0, ["a", "a"], [0, 0]), "JointState.name"),
        (lambda: messages.pose_stamped(0, "w", [0, NAN, 0], [0, 0, 0, 1]), "PoseStamped.pose.position[1]"),
        (lambda: messages.pose_stamped(0, "w", [0, 0, 0], [0, 0, 0, 2]), "PoseStamped.pose.orientation"),
        (lambda: messages.transform_stamped(0, "a", "b", [0, 0, 0], [NAN, 0, 0, 1]),
         "TransformStamped[b].rotation[0]"),
        (lambda: messages.diagnostic_status("sim", "OK", values={"energy": NAN}),
         "DiagnosticStatus[sim].values[energy]"),
        (lambda: messages.diagnostic_status("sim", "BAD"), "DiagnosticStatus[sim].level"),
        (lambda: messages.clock(-1), "stamp"),
        (lambda: messages.clock(1.5), "stamp"),
    ],
)
def test_builders_reject_invalid_fields_naming_them(build, field: str) -> None:
    with pytest.raises(ValueError) as caught:
        build()
    assert str(caught.value).startswith(field + ":")
    assert caught.value.field == field


def test_stamp_splits_into_seconds_and_nanoseconds() -> None:
    msg = messages.clock(12_345_678_901)
    assert (msg.clock.sec, msg.clock.nanosec) == (12, 345_678_901)
