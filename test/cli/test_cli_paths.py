"""Command-line output paths are checked before any work, and files that are no bag are
refused before ROS 2 starts: one line on stderr, exit 2.

Covered: ``simulate --output`` to a missing folder, a folder or an unwritable file;
``replay`` of a file that is neither .mcap nor a bag folder; ``main-job --out`` and
``work-precision --out`` naming a file. The runs are replaced by a failing stand-in, so a
check made after the run fails the test instead of taking its time.
"""
from __future__ import annotations

from pathlib import Path

import pytest

from youbot_dynamics.accuracy import work_precision
from youbot_dynamics.cli import main
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.io.bag_reader import bag_topics, read_bag
from youbot_dynamics.sim.simulator import Simulator

UNWRITABLE = Path("/proc/version")  # refuses writing, even to root (the tests may run as root)


@pytest.fixture(autouse=True)
def no_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    def ran(*args, **kwargs):
        pytest.fail("the run started before the output path was checked")
    monkeypatch.setattr(Simulator, "run", ran)
    # the command module first: importing it here must bind the real function, which the
    # undo then restores (after the next line it would bind the stand-in for good)
    monkeypatch.setattr("youbot_dynamics.cli.sim_commands.work_precision", ran)
    monkeypatch.setattr(work_precision, "work_precision", ran)
    monkeypatch.setattr("youbot_dynamics.ros.dynamics_node.run", ran)
    monkeypatch.setattr("youbot_dynamics.ros.replay_node.replay_once", ran)
    monkeypatch.setattr("youbot_dynamics.studies.squeezer.simulate_squeezer", ran)
    monkeypatch.setattr("youbot_dynamics.studies.woodpecker.Woodpecker.simulate", ran)
    monkeypatch.setattr("youbot_dynamics.cli.log_commands.recover_mcap", ran)


def _one_line_error(capsys: pytest.CaptureFixture[str], argv: list[str], *words: str) -> str:
    assert main(argv) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"youbot-dynamics {argv[0]}: error: "), captured.err
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


def _cases(tmp_path: Path) -> dict[str, tuple[str, str]]:
    folder = tmp_path / "folder"
    folder.mkdir()
    return {"missing folder": (str(tmp_path / "absent" / "run.csv"), "does not exist"),
            "a folder": (str(folder), "is a folder"),
            "unwritable": (str(UNWRITABLE), "cannot be written")}


@pytest.mark.parametrize("case", ["missing folder", "a folder", "unwritable"])
def test_simulate_output_is_checked_before_the_run(capsys, tmp_path: Path, case: str) -> None:
    if case == "unwritable" and not UNWRITABLE.exists():
        pytest.skip("no /proc/version on this system")
    path, words = _cases(tmp_path)[case]
    _one_line_error(capsys, ["simulate", "--scene", "arm_swing", "--output", path], "--output", words)
    assert not (tmp_path / "absent").exists()


@pytest.mark.parametrize("argv", [["study", "woodpecker", "--plot"], ["study", "squeezer", "--plot"]])
def test_plot_files_are_checked_before_the_run(capsys, tmp_path: Path, argv: list[str]) -> None:
    _one_line_error(capsys, [*argv, str(tmp_path / "absent" / "plot.png")], "--plot", "does not exist")


def test_log_recover_output_is_checked(capsys, tmp_path: Path) -> None:
    broken = tmp_path / "broken.mcap"
    broken.write_bytes(b"\x89MCAP0\r\n")
    (tmp_path / "fixed.mcap").mkdir()
    _one_line_error(capsys, ["log", "recover", str(broken), "-o", str(tmp_path / "fixed.mcap")], "-o", "is a folder")


def test_an_existing_output_file_is_left_unchanged_and_a_new_one_not_created(tmp_path: Path) -> None:
    from youbot_dynamics.cli.common import output_file
    existing = tmp_path / "old.csv"
    existing.write_text("keep")
    assert output_file(str(existing), "--output") == existing and existing.read_text() == "keep"
    assert output_file(str(tmp_path / "new.csv"), "--output") == tmp_path / "new.csv"
    assert not (tmp_path / "new.csv").exists()


@pytest.mark.parametrize("command", ["main-job", "work-precision"])
def test_output_folder_that_is_a_file_is_refused_before_the_run(capsys, tmp_path: Path, command: str) -> None:
    blocking = tmp_path / "out"
    blocking.write_text("a file")
    scene = ["--scene", "arm_swing"]
    _one_line_error(capsys, [command, *scene, "--out", str(blocking)], "--out", "is a file, not a folder")
    _one_line_error(capsys, [command, *scene, "--out", str(blocking / "sub")], "is a file, not a folder")


def test_main_job_creates_its_output_folder_before_the_run(tmp_path: Path) -> None:
    with pytest.raises(pytest.fail.Exception, match="before the output path"):
        main(["main-job", "--scene", "arm_swing", "--out", str(tmp_path / "a" / "b")])
    assert (tmp_path / "a" / "b").is_dir()


def test_main_job_refuses_an_unbounded_run(capsys) -> None:
    _one_line_error(capsys, ["main-job", "--scene", "arm_swing", "--rate", "1e9"], "output samples")
    _one_line_error(capsys, ["main-job", "--scene", "arm_swing", "--duration", "inf"], "--duration")
    _one_line_error(capsys, ["main-job", "--scene", "arm_swing", "--time-scale", "-1"], "--time-scale")


@pytest.mark.parametrize("name, content", [("scene.yaml", b"duration: 1\n"), ("notes.txt", b""),
                                           ("fake.mcap", b"hello")])
def test_replay_of_a_file_that_is_no_bag_is_one_line(capsys, tmp_path: Path, name: str, content: bytes) -> None:
    path = tmp_path / name
    path.write_bytes(content)
    _one_line_error(capsys, ["replay", str(path)], f"bag {path}: cannot be read")
    for reader in (bag_topics, read_bag):
        with pytest.raises(UserInputError, match="cannot be read"):
            reader(path)


def test_woodpecker_plot_samples_are_bounded_before_the_run(capsys, tmp_path: Path) -> None:
    # Before: int(1e308 * 2000) raised OverflowError (a traceback).
    _one_line_error(capsys, ["study", "woodpecker", "--duration", "1e308", "--plot", str(tmp_path / "w.png")], "output samples")


@pytest.mark.parametrize("budget", ["-5", "0"])
def test_a_step_budget_below_one_is_refused_when_parsed(capsys, budget: str) -> None:
    # Before: accepted, and the run failed on its own budget of -5 steps.
    _one_line_error(capsys, ["simulate", "--scene", "arm_swing", "--max-steps", budget], "--max-steps",
                    "positive integer")
