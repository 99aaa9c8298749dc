"""Divergence is seen in every scene and no run hangs: the energy ledger of
passive scenes (with contact and friction), free-body velocity and penetration bounds, a
fixed step larger than the output spacing or too small to move the clock refused, step
budgets (up front for fixed steps, when spent for adaptive ones), non-finite values inside
an adaptive step (1e308) ending in a DivergenceError instead of an endless loop."""
from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
import yaml

from youbot_dynamics.cli import main
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import DivergenceError, StepBudgetError, integrate
from youbot_dynamics.node.simulate import SimulationSession
from youbot_dynamics.scene.schema import load_scene, scene_dir
from youbot_dynamics.sim.divergence import DivergenceLimits
from youbot_dynamics.sim.simulator import Simulator


def ball_drop(tmp_path, **changes):
    """The packaged ball_drop scene with top-level keys replaced, as a file."""
    data = yaml.safe_load((scene_dir() / "ball_drop.yaml").read_text())
    data.update(changes)
    path = tmp_path / "ball_variant.yaml"
    path.write_text(yaml.safe_dump(data))
    return load_scene(path)


def ball_mass(scene) -> float:
    return scene.free_bodies[0].body.mass


# ---- 1. the energy ledger ---------------------------------------------------------------
def test_rk4_ball_drop_at_half_a_millisecond_is_divergence_not_a_bounce_to_364_m():
    # before: exit 0, 807 J, the ball 364 m up; now the first contact step is seen
    scene = load_scene("ball_drop").with_integrator("rk4", dt=5e-4)
    with pytest.raises(DivergenceError) as caught:
        Simulator(scene).run()
    # the ball touches the floor at sqrt(2 h / g) = 0.4515 s; the divergence is that step's
    assert caught.value.time == pytest.approx(math.sqrt(2 * 1.0 / 9.81), abs=2e-3)


def test_the_energy_ledger_alone_sees_the_rk4_bounce(tmp_path):
    scene = load_scene("ball_drop").with_integrator("rk4", dt=5e-4)
    limits = DivergenceLimits(body_speed=math.inf, penetration_fraction=math.inf)
    with pytest.raises(DivergenceError, match="energy grew by .* in a passive scene"):
        Simulator(scene, limits=limits).run()


def test_the_ledger_of_one_bounce_is_the_restitution_loss(tmp_path):
    # touch and separation happen at zero overlap and the same height, so what one bounce
    # dissipates is m (v_touch^2 - v_separation^2) / 2, from the located events' speeds
    scene = ball_drop(tmp_path, duration=0.8)
    result = Simulator(scene).run()
    m = ball_mass(scene)
    speeds = {e.kind: e.value for e in result.contact_events}
    assert set(speeds) == {"touch", "compression", "separation"}
    # measured relative difference 2.2e-5; bound 1e-4
    assert result.energy_dissipated == pytest.approx(
        0.5 * m * (speeds["touch"] ** 2 - speeds["separation"] ** 2), rel=1e-4)
    # and the restitution law keeps e^2 of the 1 m fall's energy: (1 - e^2) m g h; gravity
    # acting during the 1 ms contact moves it (measured 1.7e-3); bound 5e-3
    g = float(np.linalg.norm(scene.gravity))
    assert result.energy_dissipated == pytest.approx((1 - 0.8 ** 2) * m * g * 1.0, rel=5e-3)


def test_friction_scene_loses_energy_and_passes_the_ledger():
    # arm_friction: no controller, Stribeck and LuGre joints; the ledger must not complain
    result = Simulator(load_scene("arm_friction").with_duration(0.5)).run()
    assert result.energy_dissipated > 0.0


# ---- 2. free-body bounds ----------------------------------------------------------------
def test_a_free_body_faster_than_its_speed_limit_is_divergence():
    # the ball falls freely without turning (body frame = world frame): |v_z| = g t reaches
    # 3 m/s at t = 3 / 9.81 = 0.306 s
    limits = DivergenceLimits(body_speed=3.0)
    with pytest.raises(DivergenceError, match=r"outside its bounds: twist\[ball.vz\]") as caught:
        Simulator(load_scene("ball_drop"), limits=limits).run()
    # the check runs after each step; rk45 integrates free fall exactly and takes 0.12 s
    # steps there (error estimate 0), so it stops at the first step end past 0.306 s with the
    # exact velocity there (measured relative error 1e-15; bound 1e-9)
    error = caught.value
    assert 3.0 / 9.81 <= error.time < 3.0 / 9.81 + error.step_size
    assert error.components["twist[ball.vz]"] == pytest.approx(-9.81 * error.time, rel=1e-9)


def test_a_ball_sinking_deeper_than_half_its_radius_is_divergence(tmp_path):
    # stiffness 1e3 N/m^1.5: the 0.45 J of the fall compress it by (2.5 E / k)^0.4 = 66 mm,
    # beyond half the 25 mm radius
    data = yaml.safe_load((scene_dir() / "ball_drop.yaml").read_text())
    data["contacts"][0]["stiffness"] = 1.0e3
    path = tmp_path / "soft.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(DivergenceError, match=r"penetration limit: floor/ball .* > 0.0125 m"):
        Simulator(load_scene(path)).run()


# ---- 3. step sizes -----------------------------------------------------------------------
def test_a_fixed_step_larger_than_the_output_spacing_is_refused():
    # ball_drop writes at 200 Hz (5 ms); the 10 ms step was silently cut to 5 ms before
    scene = load_scene("ball_drop").with_integrator("rk4", dt=1e-2)
    with pytest.raises(UserInputError, match=r"integrator.dt \(outputs.rate 200 Hz\): fixed step "
                                             r"dt=0.01 s is larger than the output spacing 0.005 s"):
        Simulator(scene).run()


def test_simulate_refuses_the_large_step_in_one_line(capsys):
    assert main(["simulate", "--scene", "ball_drop", "--integrator", "rk4", "--dt", "0.01"]) == 2
    err = capsys.readouterr().err.strip()
    assert "output spacing" in err and len(err.splitlines()) == 1


def test_a_node_session_refuses_a_fixed_step_longer_than_its_publish_period():
    # gripping steps its constraint solver at 1 ms: published at 2 kHz, every step would be
    # cut to 0.5 ms without a word
    with pytest.raises(UserInputError, match=r"integrator.dt \(publish_rate 2000 Hz\): fixed step "
                                             r"dt=0.001 s is larger than the output spacing 0.0005 s"):
        SimulationSession(load_scene("gripping"), publish_rate=2000.0)
    SimulationSession(load_scene("gripping"), publish_rate=1000.0).close()


def test_a_step_that_cannot_move_the_clock_is_refused_up_front():
    rhs = lambda t, x: -x  # noqa: E731
    with pytest.raises(UserInputError, match=r"t \+ dt == t"):
        integrate(rhs, [1.0], [0.0, 2.5], "euler", dt=1e-18)
    # a scene's dt of 1e-18 s: before, a run that could never finish
    scene = load_scene("ball_drop").with_integrator("rk4", dt=1e-18)
    with pytest.raises(UserInputError, match=r"dt=1e-18 s is below the time resolution at t=2.5 s"):
        Simulator(scene).run()


# ---- 4. step budgets and progress --------------------------------------------------------
def test_pendulum_for_1e18_euler_steps_is_refused_in_one_line(capsys):
    # before: a hang; now refused before the first step: near t = 1e9 s a step of 1e-9 s
    # does not move the clock (the spacing of doubles there is 1.2e-7 s)
    code = main(["study", "pendulum", "--duration", "1e9", "--integrator", "euler", "--dt", "1e-9"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert "dt=1e-09 s is below the time resolution at t=1e+09 s (t + dt == t)" in err
    # 1e10 steps that do move the clock are over the default budget of 1e7
    assert main(["study", "pendulum", "--duration", "1e4", "--integrator", "euler", "--dt", "1e-6"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "euler: 1e+10 steps of dt=1e-06 s over 10000 s exceed the step budget of 10000000 " \
           "steps: raise --max-steps or dt" in err


def test_the_fixed_step_budget_is_a_flag():
    rhs = lambda t, x: -x  # noqa: E731
    with pytest.raises(StepBudgetError):
        integrate(rhs, [1.0], [0.0, 1.0], "rk4", dt=1e-3, max_steps=999)
    # 1000 steps fit a budget of 1000
    assert integrate(rhs, [1.0], [0.0, 1.0], "rk4", dt=1e-3, max_steps=1000).stats.steps == 1000


def test_an_adaptive_run_stops_when_its_budget_is_spent():
    # rk45 needs about 60 steps on the decay at rtol 1e-10 over 10 s (measured 59)
    with pytest.raises(StepBudgetError, match="over its step budget of 20 steps"):
        integrate(lambda t, x: -x, [1.0], [0.0, 10.0], "rk45", rtol=1e-10, atol=1e-12,
                  max_steps=20)


def test_progress_reports_the_time_reached_at_every_output():
    reached = []
    integrate(lambda t, x: -x, [1.0], np.linspace(0.0, 1.0, 11), "euler", dt=1e-2,
              progress=reached.append)
    assert reached == pytest.approx(np.linspace(0.1, 1.0, 10), abs=1e-12)


# ---- 5. no hangs on non-finite values ----------------------------------------------------
HANG = """
import numpy as np
from youbot_dynamics.integrate.integrators import DivergenceError, integrate
try:
    integrate(lambda t, x: np.array([x[1], {g}]), [0.0, {v0}], [0.0, 1.0], "{method}")
except DivergenceError as error:
    print("DivergenceError", error)
"""


@pytest.mark.parametrize("method", ["rk45", "dop853", "radau", "bdf"])
@pytest.mark.parametrize("g, v0", [(1e308, 0.0), (-9.81, 1e308)])
def test_gravity_or_velocity_of_1e308_is_divergence_not_a_hang(method, g, v0):
    # before: scipy's RK step size turned NaN and step() never returned; the subprocess
    # bound is a hang guard (the run takes well under a second), not a timing assertion
    done = subprocess.run([sys.executable, "-c", HANG.format(g=g, v0=v0, method=method)],
                          capture_output=True, text=True, timeout=120)
    assert done.stdout.startswith("DivergenceError"), done.stderr[-2000:]
    assert "non-finite" in done.stdout


def test_one_step_wise_call_is_bounded_by_its_step_budget():
    # a node's callback calls advance_through: dop853 needs more than 3 steps for 1 s of
    # arm_swing (measured 149), so a budget of 3 stops it with a typed error
    simulator = Simulator(load_scene("arm_swing"), limits=DivergenceLimits(max_steps_per_call=3))
    with pytest.raises(StepBudgetError, match="over its step budget of 3 steps"):
        simulator.advance(1.0)
    # a fixed step is refused before the first step: 1 s at 1 ms is 1000 steps
    fixed = Simulator(load_scene("arm_swing").with_integrator("rk4", dt=1e-3),
                      limits=DivergenceLimits(max_steps_per_call=999))
    with pytest.raises(StepBudgetError, match="1000 steps of dt=0.001 s"):
        fixed.advance(1.0)
    assert fixed.t == 0.0


def test_simulate_refuses_a_run_over_max_steps_in_one_line(capsys):
    # ball_drop: 2.5 s at 0.5 ms is 5000 steps
    code = main(["simulate", "--scene", "ball_drop", "--integrator", "rk4", "--dt", "5e-4",
                 "--max-steps", "4999"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert err.endswith("simulate: error: rk4: 5000 steps of dt=0.0005 s over 2.5 s exceed the step budget "
                        "of 4999 steps: raise --max-steps or dt")


def test_simulate_reports_the_ball_drop_divergence_with_a_non_zero_exit(capsys):
    assert main(["simulate", "--scene", "ball_drop", "--integrator", "rk4", "--dt", "5e-4"]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "rk4 diverged at t=0.45" in err


def test_long_fixed_step_runs_show_progress(capsys):
    from youbot_dynamics.cli.sim_commands import progress_bar
    from youbot_dynamics.sim.divergence import PROGRESS_STEPS

    with progress_bar("pendulum", PROGRESS_STEPS, 0.0, 10.0, True) as short:
        assert short is None                     # short runs: no bar, no callback
    with progress_bar("pendulum", PROGRESS_STEPS + 1, 0.0, 10.0, True) as long:
        long(5.0)
        long(10.0)
    assert "pendulum: 100%" in capsys.readouterr().err


def test_the_ledger_spans_the_calls_of_a_passive_stretch():
    # arm_swing is conservative: dop853 keeps its energy to 1e-6 J over 60 s (measured
    # 9.8e-7 J; energy_tolerance 1e-3 J). Energy put in between two calls (the velocities
    # scaled by 1.5) passes a ledger that restarts every call, not one from the reset.
    simulator = Simulator(load_scene("arm_swing"))
    simulator.advance(0.05)
    before = simulator.energy
    simulator.x[simulator.layout.slice("v")] *= 1.5
    assert simulator.energy - before > 1e-3
    with pytest.raises(DivergenceError, match="energy grew"):
        simulator.advance(0.1)
    # a command that feeds energy in restarts the ledger at the next passive call
    simulator.advance(0.1, tau_command=[0.1, 0.0, 0.0, 0.0, 0.0])
    simulator.advance(0.15)
