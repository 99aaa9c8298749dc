"""Work-precision on a short arm_swing: files written, reference trustworthy, error falls
with tolerance for the adaptive methods and with step size for RK4, the recommendation
meets its target, and `integrator: auto` is cached per scene content."""
from __future__ import annotations

import csv
import json

import numpy as np
import pytest
import yaml

from youbot_dynamics.analysis import work_precision as wp
from youbot_dynamics.cli import main
from youbot_dynamics.ros.session import SimulationSession
from youbot_dynamics.sim.scene import load_scene, scene_dir

GRID = {"rk4": (1e-2, 2e-3, 4e-4),
        **{name: (1e-4, 1e-6, 1e-8) for name in ("rk45", "dop853", "radau", "cvode_adams", "cvode_bdf")}}


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    scene = load_scene("arm_swing").with_duration(0.5)
    out = tmp_path_factory.mktemp("wp")
    return scene, wp.work_precision(scene, out, target_error=1e-6, grid=GRID, progress=False)


def test_files_written(study):
    scene, result = study
    csv_path, md_path, png_path = result.files
    rows = list(csv.DictReader(csv_path.open()))
    assert len(rows) == sum(len(v) for v in GRID.values())
    assert set(rows[0]) >= {"integrator", "value", "q_error", "ee_error", "energy_drift", "wall_time", "rhs_evals"}
    text = md_path.read_text()
    assert text.count("\n| ") == len(rows) + 1 and "cheapest is" in text
    assert png_path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_reference_is_checked(study):
    _, result = study
    assert result.reference.error_estimate < 1e-8  # far below every target swept
    assert result.reference.state_dim == 10


@pytest.mark.parametrize("method", ["rk45", "dop853", "radau", "cvode_adams", "cvode_bdf", "rk4"])
def test_error_decreases_with_tolerance(study, method):
    _, result = study
    points = [p for p in result.points if p.integrator == method]
    assert all(p.failure is None for p in points)
    errors = [p.q_error for p in points]  # grid from loose to tight
    assert all(b < a for a, b in zip(errors, errors[1:])), errors
    assert errors[-1] < 1e-3 * errors[0]
    ee = [p.ee_error for p in points]
    assert ee[-1] < ee[0]
    drift = [p.energy_drift for p in points]
    assert drift[-1] < drift[0]  # conservative scene: drift reported and falling


def test_recommendation_is_cheapest_meeting_target(study):
    _, result = study
    best = result.best
    meeting = [p for p in result.points if p.q_error <= 1e-6]
    assert best in meeting and best.wall_time == min(p.wall_time for p in meeting)
    assert wp.recommend(result.points, 1e-30) is None


def test_auto_integrator_cached_per_scene_content(tmp_path, monkeypatch):
    monkeypatch.setenv("YOUBOT_DYNAMICS_CACHE", str(tmp_path / "cache"))
    data = yaml.safe_load((scene_dir() / "arm_swing.yaml").read_text())
    data["integrator"] = {"method": "auto", "target_error": 1e-5}
    data["duration"] = 0.2
    path = tmp_path / "auto.yaml"
    path.write_text(yaml.safe_dump(data))
    small = {"rk4": (5e-3, 1e-3), "dop853": (1e-6, 1e-9)}
    chosen = wp.resolve_integrator(load_scene(path), grid=small, progress=False)
    assert chosen.method in small and chosen.method != "auto"
    cached = list((tmp_path / "cache" / "auto_integrator").glob("*.json"))
    assert len(cached) == 1 and json.loads(cached[0].read_text())["method"] == chosen.method

    def no_sweep(*args, **kwargs):
        raise AssertionError("swept again although the scene did not change")

    monkeypatch.setattr(wp, "sweep", no_sweep)
    assert wp.resolve_integrator(load_scene(path), grid=small, progress=False) == chosen
    with SimulationSession(load_scene(path), publish_rate=100.0) as session:  # the node's way in
        assert session.simulator.integrator == chosen
    data["duration"] = 0.25  # the scene changes: its hash, so the cache entry, changes
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(AssertionError, match="swept again"):
        wp.resolve_integrator(load_scene(path), grid=small, progress=False)


def test_work_precision_cli(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(wp, "DEFAULT_GRID", {"rk4": (5e-3, 1e-3), "rk45": (1e-5, 1e-8)})
    assert main(["work-precision", "--scene", "arm_swing", "--duration", "0.2", "--target-error", "1e-4",
                 "--out", str(tmp_path), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert len(report["points"]) == 4 and report["recommendation"]
    assert all(np.isfinite(p["q_error"]) for p in report["points"])
    assert main(["work-precision", "--scene", "arm_swing", "--target-error", "-1", "--out", str(tmp_path)]) == 2
