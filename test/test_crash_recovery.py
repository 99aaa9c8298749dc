"""Logs that survive a crash: truncated MCAP files recovered, a logging node killed.

Without ROS: an MCAP file cut at many points is recovered by ``recover_mcap``; the result
must hold exactly the messages of the chunks that lay wholly before the cut (the reference:
the complete file's chunk index, read by mcap's indexed reader), with schemas, channels and
their metadata intact, and be accepted by rosbags' AnyReader and mcap's indexed reader.

With ROS: the dynamics node process, logging MCAP and Rerun, is killed with SIGKILL when
its /joint_states reaches a random simulated time; the recovered MCAP must hold every
sample from t = 0 on without a gap, and lose at most 1 s of simulated time before the last
sample a subscriber received. SIGHUP must leave a complete log, like SIGTERM.
"""
from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import threading
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap.writer import Writer
from rosbags.highlevel import AnyReader

from youbot_dynamics.cli import main as cli_main
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.io import messages
from youbot_dynamics.io.mcap_log import McapLogger
from youbot_dynamics.io.mcap_recover import default_recovered_path, recover_mcap
from youbot_dynamics.io.messages import TYPESTORE

REPO = Path(__file__).resolve().parent.parent
SPAN_NS = 100_000_000        # 0.1 s chunks in the file-level tests: many chunks in a small file
DT_NS = 2_000_000            # 500 Hz


def write_run(path: Path, samples: int = 600) -> None:
    """A small log: /tf_static at 0, then /clock and /joint_states at 500 Hz, chunks closed
    every 0.1 s of log time (never on the wall clock: the file is the same on every run)."""
    with McapLogger(path, chunk_span_ns=SPAN_NS, chunk_wall_s=float("inf")) as log:
        log.add_topic("/clock", "rosgraph_msgs/msg/Clock")
        log.add_topic("/joint_states", "sensor_msgs/msg/JointState")
        log.add_topic("/tf_static", "tf2_msgs/msg/TFMessage", latched=True)
        log.write("/tf_static", messages.tf_message(
            [messages.transform_stamped(0, "base_footprint", "base_link", [0, 0, 0.084], [0, 0, 0, 1])]), 0)
        for k in range(samples):
            t = k * DT_NS
            log.write("/clock", messages.clock(t), t, max(0, t - 7))
            log.write("/joint_states", messages.joint_state(t, ["a", "b"], [k / 3, -k / 7], [1.0, 2.0]), t)


def raw_messages(path: Path) -> list[tuple[str, int, int, int, bytes]]:
    """(topic, log time, publish time, sequence, CDR) of every message, by mcap's indexed reader."""
    with path.open("rb") as stream:
        return [(channel.topic, m.log_time, m.publish_time, m.sequence, bytes(m.data))
                for _, channel, m in make_reader(stream).iter_messages(log_time_order=False)]


def anyreader_count(path: Path) -> int:
    """Messages rosbags' AnyReader decodes from the file (it needs the summary)."""
    with AnyReader([path], default_typestore=TYPESTORE) as reader:
        return sum(1 for connection, _, data in reader.messages()
                   if reader.deserialize(data, connection.msgtype) is not None)


@pytest.fixture(scope="module")
def complete(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("crash") / "run.mcap"
    write_run(path)
    return path


def test_chunks_close_on_the_log_time_bound(complete: Path) -> None:
    """Every chunk spans less than 0.1 s of log time and the next starts one sample later:
    chunks [0, 98 ms], [100 ms, 198 ms], ..."""
    with complete.open("rb") as stream:
        chunks = make_reader(stream).get_summary().chunk_indexes
    spans = [(c.message_start_time, c.message_end_time) for c in chunks]
    assert spans == [(k * SPAN_NS, k * SPAN_NS + SPAN_NS - DT_NS) for k in range(12)]


def test_chunks_close_on_the_wall_clock_bound(tmp_path: Path) -> None:
    """With a wall bound of 0 s every message closes the chunk before it: one per chunk."""
    path = tmp_path / "wall.mcap"
    with McapLogger(path, chunk_wall_s=0.0) as log:
        log.add_topic("/clock", "rosgraph_msgs/msg/Clock")
        for k in range(5):
            log.write("/clock", messages.clock(k), k)
    assert log.chunks_closed == 4
    with path.open("rb") as stream:
        assert len(make_reader(stream).get_summary().chunk_indexes) == 5


def test_recovering_a_complete_file_keeps_everything(complete: Path, tmp_path: Path) -> None:
    result = recover_mcap(complete, tmp_path / "same.mcap")
    assert result.complete and result.dropped_bytes == 0 and result.chunks == 12
    assert raw_messages(tmp_path / "same.mcap") == raw_messages(complete)
    assert result.messages == 1201 and result.topics == ("/clock", "/joint_states", "/tf_static")


def test_every_cut_keeps_exactly_the_chunks_before_it(complete: Path, tmp_path: Path) -> None:
    """Cuts at 40 random offsets, plus just before, at and after the end of every chunk
    record: the recovered file holds the messages of the chunks that end at or before the
    cut, bit for bit, in an indexed file that AnyReader and mcap's reader accept."""
    with complete.open("rb") as stream:
        summary = make_reader(stream).get_summary()
    ends = [c.chunk_start_offset + c.chunk_length for c in summary.chunk_indexes]
    data = complete.read_bytes()
    everything = raw_messages(complete)
    rng = random.Random(15)
    cuts = sorted({*(rng.randrange(9, len(data)) for _ in range(40)), *(e + d for e in ends for d in (-1, 0, 1))})
    broken, fixed = tmp_path / "broken.mcap", tmp_path / "fixed.mcap"
    for cut in cuts:
        broken.write_bytes(data[:cut])
        kept_chunks = [c for c, end in zip(summary.chunk_indexes, ends) if end <= cut]
        expected = [m for m in everything if any(c.message_start_time <= m[1] <= c.message_end_time
                                                 for c in kept_chunks)]
        result = recover_mcap(broken, fixed)
        assert not result.complete and result.chunks == len(kept_chunks), cut
        assert result.messages == len(expected) and raw_messages(fixed) == expected, cut
        assert 0 <= result.dropped_bytes < cut
    assert anyreader_count(fixed) == len(expected) > 0


def test_schemas_channels_metadata_and_attachments_survive(tmp_path: Path) -> None:
    """Channel metadata (QoS profiles, type hashes), schemas, the header's profile, metadata
    and attachment records come through unchanged."""
    source = tmp_path / "meta.mcap"
    write_run(source, samples=60)
    with source.open("rb") as stream:
        original = make_reader(stream)
        header, summary = original.get_header(), original.get_summary()
    with (tmp_path / "extra.mcap").open("wb") as stream:
        writer = Writer(stream)
        writer.start(profile=header.profile, library=header.library)
        writer.add_metadata("rosbag2", {"ros_distro": "jazzy"})
        writer.add_attachment(create_time=5, log_time=6, name="robot.urdf", media_type="text/xml", data=b"<robot/>")
        schema_ids = {sid: writer.register_schema(s.name, s.encoding, s.data) for sid, s in summary.schemas.items()}
        for channel in summary.channels.values():
            writer.register_channel(channel.topic, channel.message_encoding, schema_ids[channel.schema_id],
                                    channel.metadata)
        writer.finish()
    recover_mcap(tmp_path / "extra.mcap", tmp_path / "extra_fixed.mcap")
    with (tmp_path / "extra_fixed.mcap").open("rb") as stream:
        reader = make_reader(stream)
        got_header, got = reader.get_header(), reader.get_summary()
        metadata = [(m.name, m.metadata) for m in reader.iter_metadata()]
        attachments = [(a.name, a.media_type, a.log_time, a.create_time, a.data) for a in reader.iter_attachments()]
    assert (got_header.profile, got_header.library) == (header.profile, header.library) == \
        ("ros2", "youbot_dynamics (mcap-python)")
    assert sorted((c.topic, c.message_encoding, tuple(sorted(c.metadata.items()))) for c in got.channels.values()) == \
        sorted((c.topic, c.message_encoding, tuple(sorted(c.metadata.items()))) for c in summary.channels.values())
    assert sorted((s.name, s.encoding, s.data) for s in got.schemas.values()) == \
        sorted((s.name, s.encoding, s.data) for s in summary.schemas.values())
    assert metadata == [("rosbag2", {"ros_distro": "jazzy"})]
    assert attachments == [("robot.urdf", "text/xml", 6, 5, b"<robot/>")]


def test_cli_recovers_and_names_the_output(complete: Path, tmp_path: Path, capsys) -> None:
    broken = tmp_path / "cut.mcap"
    broken.write_bytes(complete.read_bytes()[: len(complete.read_bytes()) // 2])
    assert cli_main(["log", "recover", str(broken)]) == 0
    out = capsys.readouterr().out
    assert default_recovered_path(broken) == tmp_path / "cut.recovered.mcap"
    assert str(tmp_path / "cut.recovered.mcap") in out and "no summary" in out
    assert anyreader_count(tmp_path / "cut.recovered.mcap") > 0


@pytest.mark.parametrize(("content", "match"), [
    (b"", "ends before its header"),
    (b"\x89MCA", "ends before its header"),
    (b"import os\n", "is not an MCAP file"),
])
def test_cli_refuses_what_is_not_an_mcap_file_in_one_line(tmp_path: Path, capsys, content: bytes,
                                                           match: str) -> None:
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(content)
    assert cli_main(["log", "recover", str(bad)]) == 2
    err = capsys.readouterr().err
    assert match in err and str(bad) in err and err.count("\n") == 1


def test_recover_refuses_a_missing_file_and_overwriting_its_input(complete: Path, tmp_path: Path) -> None:
    with pytest.raises(UserInputError, match="no such file"):
        recover_mcap(tmp_path / "missing.mcap")
    with pytest.raises(UserInputError, match="would overwrite"):
        recover_mcap(complete, complete)
