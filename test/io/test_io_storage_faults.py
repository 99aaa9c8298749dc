"""Logs at the edges of storage: a full disk under a writer, two writers on one path, a
damaged file recovered.

- A file-size limit (RLIMIT_FSIZE in a child process, with SIGXFSZ ignored, so the
  kernel answers EFBIG where a full disk answers ENOSPC; it runs as any user) is hit under
  an MCAP writer: logging stops with the reason, later calls do nothing, the caller keeps
  going, ``close`` does not raise, and the file reads as it is with mcap's indexed reader
  and rosbags' AnyReader (or, when not even the summary fits, ``log recover`` rebuilds it).
- A second writer on a log path is refused in one line naming the first's pid; the first's
  log stays whole; the lock goes with its holder (close, SIGKILL).
- ``log recover`` names a damaged chunk by its byte offset, skips it, never calls a damaged
  file complete, and exits non-zero when it recovers nothing.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from mcap.reader import make_reader
from rerun.chunk import RrdReader

from youbot_dynamics import default_urdf
from youbot_dynamics.cli import main as cli_main
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.io import messages
from youbot_dynamics.io.log_file import LogPathError, LogPathInUse
from youbot_dynamics.io.mcap_log import McapLogger
from youbot_dynamics.io.mcap_recover import NothingRecovered, recover_mcap
from youbot_dynamics.io.rerun_log import RerunLogger

from test_crash_recovery import DT_NS, SPAN_NS, anyreader_count, raw_messages, rerun_sample_times_ns, write_run

REPO = Path(__file__).resolve().parents[2]

WRITER = textwrap.dedent("""
    import json, resource, signal, sys
    from youbot_dynamics.io import messages
    from youbot_dynamics.io.mcap_log import McapLogger
    path, limit, samples = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)       # the kernel then answers EFBIG
    resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    log = McapLogger(path, chunk_span_ns={span}, chunk_wall_s=float("inf"))
    log.add_topic("/clock", "rosgraph_msgs/msg/Clock")
    log.add_topic("/joint_states", "sensor_msgs/msg/JointState")
    failed_at, ticks = None, 0
    for k in range(samples):
        t = k * {dt}
        log.write_all([("/clock", messages.clock(t)),
                       ("/joint_states", messages.joint_state(t, ["a", "b"], [k / 3, -k / 7], [1.0, 2.0]))], t)
        if log.failure is not None and failed_at is None:
            failed_at = k
            log.add_topic("/tf", "tf2_msgs/msg/TFMessage")           # a no-op now, like write
        ticks += 1
    log.close()
    log.close()
    failure = log.failure
    print(json.dumps({{"ticks": ticks, "failed_at": failed_at, "closed": log.closed, "text": str(failure),
                      **{{k: str(v) for k, v in vars(failure).items()}}}}))
""").format(span=SPAN_NS, dt=DT_NS)


def write_under_limit(path: Path, limit: int, samples: int = 3000) -> dict:
    """Run WRITER in a child with a file-size limit of ``limit`` bytes; its report."""
    run = subprocess.run([sys.executable, "-c", WRITER, str(path), str(limit), str(samples)], cwd=REPO,
                         capture_output=True, text=True, timeout=300, check=False)
    assert run.returncode == 0, run.stderr
    assert run.stderr == "", run.stderr
    return json.loads(run.stdout)


@pytest.mark.parametrize("limit", [30_000, 60_000, 150_000])
def test_a_file_size_limit_stops_the_log_cleanly_and_the_file_reads_as_it_is(tmp_path: Path, limit: int) -> None:
    path = tmp_path / "full.mcap"
    report = write_under_limit(path, limit)
    assert report["ticks"] == 3000 and report["failed_at"] is not None and report["closed"]
    assert report["errno"] == "EFBIG" and "File too large" in report["reason"]
    assert report["finalised"] == "True" and "finalised" in report["text"] and str(path) in report["text"]
    assert path.stat().st_size == int(report["bytes"]) <= limit
    kept = raw_messages(path)                 # mcap's indexed reader, through the summary
    assert len(kept) == int(report["messages"]) > 0 and anyreader_count(path) == len(kept)
    with path.open("rb") as stream:
        assert make_reader(stream).get_summary().statistics.message_count == len(kept)
    assert int(report["lost"]) == 2 * report["failed_at"] - len(kept) > 0     # the failing tick's not taken
    times = [m[1] for m in kept if m[0] == "/clock"]
    assert times == [k * DT_NS for k in range(len(times))]            # a prefix of the run, no gap
    assert recover_mcap(path, tmp_path / "again.mcap").complete


def test_a_file_cut_after_any_chunk_and_finished_there_reads_whole(tmp_path: Path) -> None:
    """What a failed writer falls back on when the summary needs the room of its last chunks:
    the data cut after chunk k plus ``tail_of(k)`` is a complete file of exactly the first k
    chunks' messages, statistics right, for every k."""
    complete = tmp_path / "run.mcap"
    log = McapLogger(complete, chunk_span_ns=SPAN_NS, chunk_wall_s=float("inf"))
    log.add_topic("/clock", "rosgraph_msgs/msg/Clock")
    log.add_topic("/joint_states", "sensor_msgs/msg/JointState")
    for k in range(400):
        t = k * DT_NS
        log.write_all([("/clock", messages.clock(t)), ("/joint_states", messages.joint_state(t, ["a"], [k], [0]))], t)
    writer, data = log._writer, complete.read_bytes()       # the file as written so far: complete chunks only
    assert writer.chunk_count == 7
    for k in range(writer.chunk_count + 1):
        cut = tmp_path / f"cut{k}.mcap"
        cut.write_bytes(data[:writer.chunk_end(k)] + writer.tail_of(k))
        kept = raw_messages(cut)
        assert len(kept) == writer.chunk_messages(k) == 2 * 50 * k
        assert [m[1] for m in kept if m[0] == "/clock"] == [j * DT_NS for j in range(50 * k)]
        with cut.open("rb") as stream:
            statistics = make_reader(stream).get_summary().statistics
        assert statistics.message_count == len(kept) == anyreader_count(cut) and statistics.chunk_count == k
        if k:
            assert recover_mcap(cut, tmp_path / "again.mcap").complete
    log.close()


def test_a_limit_too_small_for_the_summary_leaves_the_file_as_it_was(tmp_path: Path) -> None:
    """Room for the header only: the first chunk fails, the summary does not fit either; the
    file is left cut after its header and says so (there is nothing to recover)."""
    path = tmp_path / "tiny.mcap"
    report = write_under_limit(path, 300)
    assert report["errno"] == "EFBIG" and report["finalised"] == "False" and report["ticks"] == 3000
    assert report["failed_at"] is not None and report["messages"] == "0" and "log recover" in report["text"]
    assert path.stat().st_size == int(report["bytes"]) <= 300
    with pytest.raises(NothingRecovered):
        recover_mcap(path, tmp_path / "fixed.mcap")


def test_an_io_error_on_close_stops_without_raising(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """EIO from the disk when the file is finished: close returns, the failure is kept, the
    complete chunks are left for ``log recover``."""
    path = tmp_path / "eio.mcap"
    log = McapLogger(path, chunk_span_ns=SPAN_NS, chunk_wall_s=float("inf"))
    log.add_topic("/clock", "rosgraph_msgs/msg/Clock")
    for k in range(200):
        log.write("/clock", messages.clock(k * DT_NS), k * DT_NS)

    def broken_disk(*args: object) -> None:
        raise OSError(5, "Input/output error")
    monkeypatch.setattr(os, "ftruncate", broken_disk)
    monkeypatch.setattr(os, "fsync", broken_disk)
    monkeypatch.setattr(log._stream, "write", broken_disk)
    log.close()
    monkeypatch.undo()
    assert log.closed and log.failure is not None and log.failure.errno == "EIO" and not log.failure.finalised
    assert log.failure.key_values()["log.error"] == "EIO"
    log.write("/clock", messages.clock(0), 0)            # a no-op, not an error
    assert recover_mcap(path, tmp_path / "fixed.mcap").messages == log.failure.messages > 0


RERUN_WRITER = textwrap.dedent("""
    import json, resource, signal, sys
    from youbot_dynamics import default_urdf
    from youbot_dynamics.io.rerun_log import RerunLogger
    path, limit = sys.argv[1], int(sys.argv[2])
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    joints = [f"arm_joint_{j}" for j in range(1, 6)]
    log = RerunLogger(path, default_urdf(), recording_name="full")
    failed_at = None
    for k in range(30000):
        q = [1e-4 * k] * 5
        log.log_sample(k * 2_000_000, joints, q, q, q, 1.0, [0.0, 0.0, 1e-4 * k])
        if log.failure is not None and failed_at is None:
            failed_at = k
    log.close()
    print(json.dumps({"failed_at": failed_at, "closed": log.closed, "text": str(log.failure),
                      **{k: str(v) for k, v in vars(log.failure).items()}}))
""")


def test_a_rerun_recording_stops_before_its_file_size_limit_with_its_footer(tmp_path: Path) -> None:
    """Rerun's own writer cannot report a failed write (and then blocks the process's exit):
    the logger stops before the limit, the recording finished with its footer; the process
    exits at once."""
    path, limit = tmp_path / "full.rrd", 4_000_000
    run = subprocess.run([sys.executable, "-c", RERUN_WRITER, str(path), str(limit)], cwd=REPO,
                         capture_output=True, text=True, timeout=300, check=False)
    assert run.returncode == 0 and "Failed to write" not in run.stderr, run.stderr
    report = json.loads(run.stdout)
    assert report["failed_at"] is not None and report["closed"] and report["errno"] == "EFBIG"
    assert "file-size limit" in report["reason"] and report["finalised"] == "True"
    assert path.stat().st_size == int(report["bytes"]) <= limit
    assert len(RrdReader(str(path)).store()) > 0                       # the footer is there
    times = rerun_sample_times_ns(path)
    assert times == [2_000_000 * k for k in range(len(times))] and len(times) == int(report["messages"]) > 0


HOLDER = textwrap.dedent("""
    import sys
    from youbot_dynamics.io import messages
    from youbot_dynamics.io.mcap_log import McapLogger
    log = McapLogger(sys.argv[1], chunk_span_ns=10)          # a chunk every 10 ns of log time
    log.add_topic("/clock", "rosgraph_msgs/msg/Clock")
    for k in range(100):
        log.write("/clock", messages.clock(k), k)
    print("ready", flush=True)
    if sys.stdin.readline().strip() == "finish":
        for k in range(100, 200):
            log.write("/clock", messages.clock(k), k)
        log.close()
        print("closed", flush=True)
""")


def start_holder(path: Path) -> subprocess.Popen:
    holder = subprocess.Popen([sys.executable, "-c", HOLDER, str(path)], cwd=REPO, stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True)
    assert holder.stdout.readline().strip() == "ready"
    return holder


def test_a_second_writer_is_refused_naming_the_first_and_the_first_log_stays_whole(tmp_path: Path,
                                                                                     capsys) -> None:
    path = tmp_path / "shared.mcap"
    holder = start_holder(path)
    try:
        with pytest.raises(LogPathInUse) as refused:
            McapLogger(path)
        text = str(refused.value)
        assert f"pid {holder.pid}" in text and str(path) in text and "\n" not in text
        assert isinstance(refused.value, UserInputError)
        assert cli_main(["log", "recover", str(path)]) == 0       # readers are not writers
        capsys.readouterr()
        holder.stdin.write("finish\n")
        holder.stdin.flush()
        assert holder.stdout.readline().strip() == "closed"
    finally:
        holder.kill()
        holder.wait()
    assert [m[1] for m in raw_messages(path)] == list(range(200)) and anyreader_count(path) == 200
    with McapLogger(path) as again:                  # released on close
        again.add_topic("/clock", "rosgraph_msgs/msg/Clock")


def test_the_lock_goes_with_a_killed_writer(tmp_path: Path) -> None:
    path = tmp_path / "killed.mcap"
    holder = start_holder(path)
    holder.send_signal(signal.SIGKILL)
    holder.wait()
    assert recover_mcap(path, tmp_path / "fixed.mcap").first_log_time_ns == 0
    McapLogger(path).close()


def test_two_loggers_in_one_process_and_rerun_recordings_are_exclusive_too(tmp_path: Path) -> None:
    first = McapLogger(tmp_path / "a.mcap")
    with pytest.raises(LogPathInUse, match=rf"pid {os.getpid()} \(this process\)"):
        McapLogger(tmp_path / "a.mcap")
    first.close()
    recording = RerunLogger(tmp_path / "a.rrd", default_urdf(), recording_name="one")
    with pytest.raises(LogPathInUse, match=rf"Rerun recording .*a\.rrd is being written by pid {os.getpid()}"):
        RerunLogger(tmp_path / "a.rrd", default_urdf(), recording_name="two")
    recording.close()
    RerunLogger(tmp_path / "a.rrd", default_urdf(), recording_name="three").close()


def test_a_log_path_that_cannot_be_written_is_one_line(tmp_path: Path) -> None:
    (tmp_path / "dir.mcap").mkdir()
    with pytest.raises(LogPathError, match=r"dir\.mcap: cannot open it for writing: EISDIR"):
        McapLogger(tmp_path / "dir.mcap")


def damaged_copy(complete: Path, target: Path, chunks: list[int]) -> list[int]:
    """``complete`` with a byte flipped in the compressed data of the chunks numbered
    ``chunks``; their offsets."""
    with complete.open("rb") as stream:
        indexes = make_reader(stream).get_summary().chunk_indexes
    data = bytearray(complete.read_bytes())
    offsets = [indexes[k].chunk_start_offset for k in chunks]
    for k in chunks:
        data[indexes[k].chunk_start_offset + indexes[k].chunk_length - 40] ^= 0xFF
    target.write_bytes(bytes(data))
    return offsets


def test_recover_names_a_damaged_chunk_by_its_offset_and_keeps_the_others(tmp_path: Path, capsys) -> None:
    complete = tmp_path / "run.mcap"
    write_run(complete, samples=300)
    everything = raw_messages(complete)
    broken = tmp_path / "damaged.mcap"
    [offset] = damaged_copy(complete, broken, [1])
    result = recover_mcap(broken, tmp_path / "fixed.mcap")
    assert not result.complete and result.had_footer and [d.offset for d in result.damaged] == [offset]
    assert 0 < result.messages < len(everything) and result.chunks == 5 and result.stopped is None
    assert set(raw_messages(tmp_path / "fixed.mcap")) < set(everything)
    assert cli_main(["log", "recover", str(broken), "-o", str(tmp_path / "cli.mcap")]) == 0
    out = capsys.readouterr().out
    assert f"damaged chunk skipped at byte {offset}" in out and "was complete" not in out


def test_recover_exits_non_zero_when_it_recovers_nothing(tmp_path: Path, capsys) -> None:
    """Every chunk damaged (as two writers on one file leave it): one line naming the
    offsets, exit 2, nothing written."""
    complete = tmp_path / "run.mcap"
    write_run(complete, samples=100)            # two chunks
    broken = tmp_path / "garbled.mcap"
    offsets = damaged_copy(complete, broken, [0, 1])
    assert cli_main(["log", "recover", str(broken)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no message recovered" in err
    assert all(f"at byte {offset}" in err for offset in offsets)
    assert not (tmp_path / "garbled.recovered.mcap").exists()


def test_bytes_after_the_footer_are_not_complete(tmp_path: Path) -> None:
    complete = tmp_path / "run.mcap"
    write_run(complete, samples=100)
    longer = tmp_path / "longer.mcap"
    longer.write_bytes(complete.read_bytes() + complete.read_bytes()[-300:])
    result = recover_mcap(longer, tmp_path / "fixed.mcap")
    assert not result.complete and result.dropped_bytes == 300 and result.messages == 201
