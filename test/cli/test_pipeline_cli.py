"""The `pipeline` command: every stage printed, JSON form, the parameter merge."""
from __future__ import annotations

import json

from youbot_dynamics.cli import main


#: The pendulum released at 0.5 rad from hanging (x = sin 0.5, y = -cos 0.5), as --set.
HANGING = ["--set", "x=0.479425538604203", "--set", "y=-0.8775825618903728"]


def test_pendulum_prints_every_stage_and_the_dummy_selection(capsys):
    assert main(["study", "pipeline", "pendulum", "--integrator", "rk45", *HANGING]) == 0
    out = capsys.readouterr().out
    for heading in ("order lowering", "alias elimination", "matching", "Pantelides",
                    "dummy derivatives", "BLT", "tearing", "generated ODE", "simulation"):
        assert f". {heading}" in out
    assert "dummy derivatives: y'', x'', v', y'" in out
    assert "states: x, u" in out
    assert "|df6/dy'| = |2*y| = 1.755 > |df6/dx'| = |2*x| = 0.9589" in out
    # document 000's start (the default): x = 1, y = 0, so x' is the dummy
    assert main(["study", "pipeline", "pendulum", "--integrator", "rk45"]) == 0
    out = capsys.readouterr().out
    assert "|df6/dx'| = |2*x| = 2 > |df6/dy'| = |2*y| = 0" in out and "states: y, v" in out


def test_modia_pendulum_json_runs_defaults_and_the_documents_merge(capsys):
    assert main(["study", "pipeline", "modia-pendulum", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    runs = report["simulation"]
    assert [run["parameters"]["L"] for run in runs] == [0.8, 0.5]
    assert runs[1]["label"] == "model | L = 0.5"
    assert runs[0]["statistics"]["nStates"] == 2
    assert runs[0]["document_statistics"] == "none printed for this run"
    assert runs[1]["document_statistics"].startswith(
        "Tsit5, tolerance 1e-06: 152 accepted, 0 rejected steps, 913 getDerivatives! calls")
    assert report["code"]["derivatives"] == {"phi'": "w",
                                             "w'": "-g*sin(phi)/L - d*w/(L**2*m)"}


def test_set_overrides_and_rejects_bad_input(capsys):
    assert main(["study", "pipeline", "lag", "--set", "tau=1", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["simulation"][0]["parameters"] == {"tau": 1.0}
    assert main(["study", "pipeline", "lag", "--set", "T=1"]) == 2
    assert "no parameter or variable T" in capsys.readouterr().err
    assert main(["study", "pipeline", "lag", "--set", "tau"]) == 2


def test_fixed_step_budget_and_the_static_selection(capsys):
    assert main(["study", "pipeline", "lag", "--integrator", "rk4", "--dt", "1e-9"]) == 2
    assert "step budget" in capsys.readouterr().err
    # gravity upwards: the pendulum falls through the horizontal, where y -> 0 makes the
    # start's selection (y' dummy, states x, u) fade: refused with the static selection,
    # chosen again (states y, v) otherwise
    assert main(["study", "pipeline", "pendulum", *HANGING, "--set", "g=-9.81",
                 "--static-selection"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "the state selection (x, u) must change" in err
    assert main(["study", "pipeline", "pendulum", *HANGING, "--set", "g=-9.81", "--json"]) == 0
    run = json.loads(capsys.readouterr().out)["simulation"][0]
    assert run["state_selections"][0].endswith("states x, u -> y, v")
    assert run["statistics"]["nRestartEvents"] == len(run["state_selections"])
