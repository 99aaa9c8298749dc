"""Every bench script in its smoke form (BENCH_SMOKE=1: tiny sizes, bench/timing.py), run
in this process as ``python bench/<script>`` would run it: it must run through and print
well-formed tables of finite numbers, so that no script rots between measuring runs.
Figures are not judged here (they are timings of a few calls); bench/summary.py's rows
are checked for their keys and types. The node benches start ROS processes (marker ros)."""
from __future__ import annotations

import math
import re
import runpy
import sys
from pathlib import Path

import pytest
from ros_support import domain_id

BENCH = Path(__file__).resolve().parents[2] / "bench"
#: script -> its command line in the smoke form (the others read BENCH_SMOKE alone)
ARGV = {
    "bench_base.py": [], "bench_contact.py": [], "bench_contact_mujoco.py": [], "bench_identification.py": [],
    "bench_pipeline.py": [], "bench_simulation.py": [], "bench_squeezer.py": [], "bench_sweeps.py": [],
    "bench_woodpecker.py": [], "bench_complexity.py": [],
    "bench_batch.py": ["--samples", "20", "--repeat", "1"],
    "bench_dynamics.py": ["--calls", "5", "--repeat", "1"],
    "bench_kinematics.py": ["--calls", "5", "--repeat", "1"],
    "bench_scaling.py": ["--calls", "5", "--repeat", "1", "--dofs", "5,10"],
    "bench_error_estimate.py": ["--fast", "--case", "elastic_pendulum"],
    "bench_node_error_estimate.py": ["--seconds", "0.05"],
}
#: the scripts whose smoke form is a test of its own below
OWN_TEST = ("bench_node.py", "bench_node_inputs.py")
NUMBER = re.compile(r"(?<![\w.])[-+]?(?:nan|inf|\d+(?:\.\d*)?(?:e[-+]?\d+)?)(?![\w.])", re.IGNORECASE)


@pytest.fixture
def smoke(monkeypatch):
    """BENCH_SMOKE=1, bench/ importable, and no bench module left from an earlier import
    (their module-level sizes are read at import)."""
    monkeypatch.setenv("BENCH_SMOKE", "1")
    monkeypatch.syspath_prepend(str(BENCH))
    for name, module in list(sys.modules.items()):
        if Path(getattr(module, "__file__", None) or "/").parent == BENCH:
            monkeypatch.delitem(sys.modules, name)


def well_formed(text: str) -> None:
    """Every Markdown table has as many cells per row as its header, and every number
    printed anywhere is finite."""
    table: list[str] = []
    for line in text.splitlines() + [""]:
        if line.startswith("|"):
            table.append(line)
            continue
        if table:
            widths = {line.count("|") for line in table}
            assert len(widths) == 1, f"ragged table:\n" + "\n".join(table)
            assert set(table[1].replace("|", "")) <= {"-", " "}, f"no header separator:\n{table[1]}"
            assert len(table) > 2, f"a table without rows:\n" + "\n".join(table)
        table = []
    numbers = [float(m) for m in NUMBER.findall(text)]
    assert numbers, "no figures printed"
    bad = [m.group() for m in NUMBER.finditer(text) if not math.isfinite(float(m.group()))]
    assert not bad, f"non-finite figures printed: {bad}"


def test_every_script_has_a_smoke_form():
    scripts = {path.name for path in BENCH.glob("bench_*.py")}
    assert scripts == set(ARGV) | set(OWN_TEST), "a bench script without a smoke test (add it to ARGV)"


@pytest.mark.parametrize("script", sorted(ARGV))
def test_script_runs_in_its_smoke_form(script, smoke, monkeypatch, capsys):
    monkeypatch.setattr(sys, "argv", [str(BENCH / script), *ARGV[script]])
    try:
        runpy.run_path(str(BENCH / script), run_name="__main__")
    except SystemExit as exit_:
        assert exit_.code in (None, 0), f"{script} exited with {exit_.code}"
    well_formed(capsys.readouterr().out)


def test_summary_rows_in_the_smoke_form(smoke, capsys):
    import summary
    from benchmarks_page import markdown

    results = summary.measure(quick=True)
    kinds = {"ours": (float, type(None)), "peer": (float, type(None)), "ratio": (float, type(None)),
             "met": (bool, str, type(None)), "ours_wall": (float, type(None)), "peer_wall": (float, type(None)),
             "figure": str, "unit": str, "goal": str}
    figures = [r["figure"] for r in results["rows"]]
    assert len(set(figures)) == len(figures), "two rows of one name"
    for r in results["rows"]:
        assert set(r) == set(kinds), r
        for key, kind in kinds.items():
            assert isinstance(r[key], kind), (key, r)
    # every row of the table is there (MuJoCo is a test requirement)
    for needle in ("main job: mobile_pick", "main job: gripping", "inverse mode", "free arm, rk4 dt=0.25 ms both",
                   "ball_drop: CPU time at matched accuracy", "grasp: CPU time at matched accuracy",
                   "N youBots: cost per robot-second", "PoE space Jacobian", "RNEA + URDF friction",
                   "ABA + URDF friction", "inverse_dynamics_batch", "free arm to", "vs pin.rnea"):
        assert any(needle in f for f in figures), needle
    # the timed rows are finite (rows without a figure are the settings a tiny sweep misses)
    assert all(math.isfinite(r[k]) for r in results["rows"] if "growth" not in r["figure"]
               for k in ("ours", "peer", "ratio") if r[k] is not None)
    assert results["load"]["before"] and results["load"]["after"]
    markdown(results["rows"])


@pytest.mark.ros
def test_bench_node_in_its_smoke_form(smoke, monkeypatch):
    """The session alone (no ROS process) and inverse mode's cost, at tiny sizes; the node
    process at 500 Hz for 0.2 s as fast as it can, every sample received (in a test domain:
    the script's own, 201, may carry a measuring run of the script)."""
    import bench_node

    monkeypatch.setattr(bench_node, "DOMAIN", domain_id(6))
    assert bench_node.session_run(500.0, 0.02, None) > 0.0
    mode, whole = bench_node.inverse_cost(samples=40, batch=20)
    assert math.isfinite(mode) and math.isfinite(whole) and mode > 0.0 and whole > 0.0
    run = bench_node.node_run(500.0, 0.0, 0.2, None)
    assert run["received"] == run["expected"] and math.isfinite(run["rtf"]) and run["rtf"] > 0.0


@pytest.mark.ros
def test_bench_node_inputs_in_its_smoke_form(smoke, monkeypatch):
    """A burst against the node with the waits cut to 0.5 s: the figures are there and finite."""
    import bench_node_inputs

    monkeypatch.setattr(bench_node_inputs, "SETTLE_S", 0.5)
    monkeypatch.setattr(bench_node_inputs, "FLOOD_S", 0.5)
    result = bench_node_inputs.run("burst", domain_id(7), 3.0)
    assert result["samples"] > 0 and math.isfinite(result["worst gap ms"]) and result["window rate Hz"] > 0.0


def test_a_figure_within_the_scatter_of_its_bound_is_near_the_goal(smoke):
    from goal_rows import NEAR, verdict

    assert verdict("ratio <= 1.1", 2.0, 1.1 * (1 + 0.9 * NEAR), False) == "near"
    assert verdict("ratio <= 1.1", 2.0, 1.1 * (1 - 0.9 * NEAR), True) == "near"
    assert verdict("ratio <= 1.1", 2.0, 1.1 * (1 + 1.1 * NEAR), False) is False
    assert verdict("ours >= 15", 15 * (1 - 1.1 * NEAR), None, False) is False
    assert verdict("ours <= 150 us", 150 * (1 + 0.5 * NEAR), None, False) == "near"
    assert verdict("ours <= max(1.1, peer + 0.1)", 1.1, 1.0, True) is True  # no plain bound: as measured
    assert verdict("ratio <= 3", None, None, None) is None
