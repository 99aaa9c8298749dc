"""simulate --error-estimate: the estimate per state group in the text summary and in the
JSON (with the companion's cost), here on ball_drop (positions, orientations, events)."""
from __future__ import annotations

import json

from youbot_dynamics.cli import main


def test_simulate_reports_the_estimate_in_json_and_text(capsys) -> None:
    args = ["simulate", "--scene", "ball_drop", "--duration", "0.6", "--error-estimate"]
    assert main(args + ["--json"]) == 0
    estimate = json.loads(capsys.readouterr().out)["error_estimate"]
    assert estimate["rule"] == "companion at tol/20, estimate |y - y_c|" and estimate["where"] == "worker process"
    assert set(estimate["groups"]) == {"positions", "orientations"}
    positions = estimate["groups"]["positions"]
    # rk45 at rtol 1e-8 against 5e-10 over one bounce: measured 2.5e-7 m; the bound is
    # a decade either side
    assert positions["unit"] == "m" and 4e-8 < positions["max_over_grid"] < 4e-6
    assert positions["at_end"] <= positions["max_over_grid"]
    assert estimate["events"]["count"] == estimate["events"]["companion_count"] == 3
    assert estimate["companion_cost"]["rhs_evals"] > 0 and estimate["companion_cost"]["cpu_time"] > 0
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "error estimate (companion at tol/20" in text and "positions      max over the grid" in text
