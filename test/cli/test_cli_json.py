"""--json on the commands that printed only text before: ``main-job`` (its summary, from a
ROS-free session), ``replay`` (the ROS run replaced by a stand-in), ``log recover``; and
the renamed options ``replay --time-scale`` and ``mecanum --duration``."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from youbot_dynamics.cli import main
from youbot_dynamics.cli.ros_commands import _summary_record, _summary_rows
from youbot_dynamics.io import messages
from youbot_dynamics.io.mcap_log import McapLogger
from youbot_dynamics.node.simulate import SimulationSession
from youbot_dynamics.scene.schema import load_scene


def test_main_job_summary_as_json_has_the_table_figures(tmp_path: Path) -> None:
    session = SimulationSession(load_scene("gripping"), 100.0, mcap_path=tmp_path / "g.mcap")
    while session.t < 0.05:
        session.step()
    session.close()
    record = json.loads(json.dumps(_summary_record(session, 100.0, 0.5), allow_nan=False))
    rows = dict(_summary_rows(session, 100.0, 0.5))
    assert record["scene"] == "gripping" and record["status"] == rows["status"] == "ok"
    assert record["samples_per_topic"] == session.k + 1 and f"({session.k + 1} samples per topic)" in \
        rows["simulated time"]
    assert record["real_time_factor"] == pytest.approx(session.t / 0.5)
    assert record["logs"] == [str(tmp_path / "g.mcap")] and rows["log (mcap)"] == str(tmp_path / "g.mcap")
    assert record["contact"]["contact.events"] == int(rows["contact events"].split(";")[0].split()[0])
    assert (record["energy_error"] is None) == (not record["conservative"])
    assert record["integrator"] == session.simulator.stats.as_dict()


def test_replay_json_and_time_scale(monkeypatch: pytest.MonkeyPatch, capsys, tmp_path: Path) -> None:
    calls = []

    def replay_once(args, **options):
        calls.append(options)
        return 3, Path(options["bag"]), ["/clock", "/joint_states"]
    monkeypatch.setattr("youbot_dynamics.io.bag_reader.bag_topics", lambda bag: ["/clock", "/joint_states"])
    monkeypatch.setattr("youbot_dynamics.ros.replay_node.replay_once", replay_once)
    assert main(["replay", "run.mcap", "--time-scale", "0", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["messages"] == 3 and record["bag"] == "run.mcap" and record["topics"] == ["/clock", "/joint_states"]
    assert main(["replay", "run.mcap"]) == 0
    assert capsys.readouterr().out.startswith("replay: 3 messages from run.mcap in ")
    assert [call["time_scale"] for call in calls] == [0.0, 1.0]  # 0: as fast as possible; default: as recorded
    assert main(["replay", "run.mcap", "--time-scale", "-1"]) == 2
    error = capsys.readouterr().err.strip().splitlines()
    assert len(error) == 1 and "--time-scale" in error[0] and "as fast as possible" in error[0]


def test_log_recover_json(tmp_path: Path, capsys) -> None:
    complete = tmp_path / "run.mcap"
    with McapLogger(complete, chunk_span_ns=10**8, chunk_wall_s=float("inf")) as log:
        log.add_topic("/clock", "rosgraph_msgs/msg/Clock")
        for k in range(300):
            log.write("/clock", messages.clock(k * 2 * 10**6), k * 2 * 10**6)
    broken = tmp_path / "cut.mcap"
    broken.write_bytes(complete.read_bytes()[: complete.stat().st_size // 2])
    assert main(["log", "recover", str(broken), "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["kind"] == "mcap" and record["source"] == str(broken) and not record["complete"]
    assert record["target"] == str(tmp_path / "cut.recovered.mcap") and record["topics"] == ["/clock"]
    assert 0 < record["messages"] < 300 and record["first_log_time_ns"] == 0


def test_mecanum_duration(capsys) -> None:
    assert main(["mecanum", "--twist", "0.5,0,0", "--duration", "2", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["duration"] == 2.0 and record["pose"]["x"] == pytest.approx(1.0, abs=1e-12)
    assert main(["mecanum", "--duration", "-1"]) == 2
    assert "--duration must be a time in [0, " in capsys.readouterr().err
