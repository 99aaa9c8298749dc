"""``dop853_compiled`` (integrate/dop853.py, the loop in sim/compiled_steps.py) against
scipy's DOP853 on the same compiled derivative (the same steps, rejections and evaluations;
states equal to rounding), against a tight reference and energy conservation on arm_swing,
against the exact period of a large-amplitude pendulum, its failures (bounds, step budget)
at scipy's step, events, and the fallback to scipy's DOP853 where the right-hand side has no
compiled loop."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import ellipk
from test_simulator import G, IYY, LENGTH, MASS, pendulum_scene

from youbot_dynamics.accuracy.work_precision import reference_solution
from youbot_dynamics.integrate.adaptive import ScipyStepper
from youbot_dynamics.integrate.dop853 import CompiledDop853Stepper
from youbot_dynamics.integrate.drive import StateCheck
from youbot_dynamics.integrate.errors import DivergenceError, StepBudgetError
from youbot_dynamics.integrate.integrators import Event, integrate
from youbot_dynamics.integrate.registry import OdeProblem, compiled_dop853_stepper
from youbot_dynamics.scene.schema import IntegratorSpec, load_scene
from youbot_dynamics.sim import engine
from youbot_dynamics.sim.simulator import Simulator

AGREEMENT = {"arm_swing": 1e-10, "arm_friction": 1e-9}
"""rad, rad/s: largest state difference from scipy's DOP853 on the same derivative over
0.5 s at rtol 1e-9 (measured 1.6e-13 on arm_swing, 1.1e-11 on arm_friction with its LuGre
bristles: the same steps, rounding only; the bounds leave a factor of about 100)."""

STEP_AGREEMENT = 1e-4
"""Relative difference of step sizes from scipy's (measured 1.4e-6 at most): the error
estimate is a difference of stages nearly equal, so its rounding (numpy's dot products
against our sums) is about 1e-5 of it and moves the next step by 1/8 of that. A rejection
decided by an error norm within that of 1 could move a step: the counts may differ by one
(measured equal)."""


def same_counts(ours, theirs) -> bool:
    """Steps and rejected steps equal within one (see STEP_AGREEMENT), and the evaluations
    scipy counts: 12 per attempted step more or less for each step of difference."""
    steps, rejected = (getattr(ours.stats, name) - getattr(theirs.stats, name) for name in ("steps", "rejected_steps"))
    return abs(steps) <= 1 and abs(rejected) <= 1 and \
        ours.stats.rhs_evals == theirs.stats.rhs_evals + 12 * (steps + rejected)


def engine_rhs(scene_name: str, command: np.ndarray | None = None):
    """(the engine's rhs, which carries the compiled loop; the loop's own derivative as a
    plain function, which scipy's DOP853 integrates), the initial state."""
    simulator = Simulator(load_scene(scene_name))
    model, state = simulator.model, simulator.state
    _, rhs = engine.right_hand_side(model, state.data, state.reference, command)
    loop = rhs.compiled_steps
    return rhs, (lambda t, x: loop.derivative(x)), state.x.copy()


@pytest.mark.parametrize("scene_name", ["arm_swing", "arm_friction"])
def test_the_steps_of_scipy_dop853_on_the_same_derivative(scene_name: str) -> None:
    compiled, plain, x0 = engine_rhs(scene_name)
    times = np.linspace(0.0, 0.5, 51)
    ours, scipy_run = (integrate(rhs, x0, times, method, rtol=1e-9, atol=1e-11)
                       for rhs, method in ((compiled, "dop853_compiled"), (plain, "dop853")))
    assert same_counts(ours, scipy_run) and ours.stats.rejected_steps > 0
    assert np.abs(np.diff(ours.t) - np.diff(scipy_run.t)).max() == 0.0      # outputs on the grid
    assert np.abs(ours.x - scipy_run.x).max() <= AGREEMENT[scene_name]
    assert np.abs(ours.x[-1] - x0).max() > 1.0             # the arm moved


def test_held_command_and_a_loose_tolerance() -> None:
    """Under a torque command, at rtol 1e-6: scipy's steps again (measured 1e-12 apart)."""
    command = np.array([0.5, -1.0, 0.3, 0.2, -0.1])
    compiled, plain, x0 = engine_rhs("arm_swing", command)
    ours, scipy_run = (integrate(rhs, x0, [0.0, 0.1, 0.3], method, rtol=1e-6, atol=1e-8)
                       for rhs, method in ((compiled, "dop853_compiled"), (plain, "dop853")))
    assert same_counts(ours, scipy_run)
    assert np.abs(ours.x - scipy_run.x).max() <= 1e-10
    free = integrate(engine_rhs("arm_swing")[0], x0, [0.0, 0.1, 0.3], "dop853_compiled", rtol=1e-6, atol=1e-8)
    assert np.abs(free.x[-1] - ours.x[-1]).max() > 1e-3    # the command acts


def test_arm_swing_to_the_reference_and_its_energy() -> None:
    """2 s at rtol 1e-9: the final joint angles within 1e-6 rad of the rtol 1e-12 reference
    (measured 1.69e-7; the reference's own estimate 1.5e-9), the same error as scipy's DOP853
    at that tolerance within 5 % (measured 0.2 %: rounding in ABA grows along the swing), and
    the energy, which the arm conserves, within 1e-7 J (measured 2.0e-8 J)."""
    scene = load_scene("arm_swing")
    reference = reference_solution(scene)
    runs = [Simulator(scene, IntegratorSpec(method, rtol=1e-9, atol=1e-11)).run()
            for method in ("dop853_compiled", "dop853")]
    errors = [np.abs(run.x[-1, :5] - reference.q).max() for run in runs]
    assert reference.error_estimate < 1e-8 and errors[0] <= 1e-6
    assert errors[0] == pytest.approx(errors[1], rel=0.05)
    assert same_counts(*runs)
    assert runs[0].energy_error <= 1e-7


def test_pendulum_half_and_whole_period(tmp_path) -> None:
    """Released at rest from 1.2 rad, a pendulum is at -1.2 rad after half its period and
    back at 1.2 rad after T = 4 sqrt(J / (m g l)) K(sin^2(theta0 / 2)) (the complete
    elliptic integral; J = I_yy + m l^2), at rest both times: within 1e-10 rad and rad/s at
    rtol 1e-11 (measured 5.8e-13 rad, 5.7e-12 rad/s)."""
    theta0, inertia = 1.2, IYY + MASS * LENGTH ** 2
    period = float(4.0 * math.sqrt(inertia / (MASS * G * LENGTH)) * ellipk(math.sin(theta0 / 2.0) ** 2))
    simulator = Simulator(load_scene(pendulum_scene(tmp_path, theta0, period, "dop853_compiled")))
    assert simulator.model.compiled_steps(None) is not None
    result = simulator.run(np.array([0.0, period / 2.0, period]))
    assert np.abs(result.x[1:, 0] - [-theta0, theta0]).max() <= 1e-10
    assert np.abs(result.x[1:, 1]).max() <= 1e-10


def test_divergence_and_step_budget_at_scipy_step() -> None:
    """The same failure at the same step (its time equal to STEP_AGREEMENT)."""
    compiled, plain, x0 = engine_rhs("arm_swing")
    bounds = np.full(x0.size, 4.0)      # the falling arm's joint 2 passes 4 rad/s within 0.3 s
    for options, error in (({"bounds": bounds}, DivergenceError), ({"max_steps": 20}, StepBudgetError)):
        caught = []
        for rhs, method in ((compiled, "dop853_compiled"), (plain, "dop853")):
            with pytest.raises(error) as info:
                integrate(rhs, x0, [0.0, 0.3], method, rtol=1e-9, atol=1e-11, **options)
            caught.append(info.value)
        assert caught[0].reason == caught[1].reason and caught[0].components.keys() == caught[1].components.keys()
        assert caught[0].time == pytest.approx(caught[1].time, rel=STEP_AGREEMENT)


def test_an_event_located_as_scipy_locates_it() -> None:
    """Joint 2 passing 2 rad (one step per advance, the dense output between): the same time
    as scipy's DOP853 to 1e-12 s (measured 2e-16 s)."""
    compiled, plain, x0 = engine_rhs("arm_swing")
    event = Event("joint 2 at 2 rad", lambda t, x: x[1] - 2.0)
    runs = [integrate(rhs, x0, [0.0, 0.5], method, rtol=1e-9, atol=1e-11, events=[event])
            for rhs, method in ((compiled, "dop853_compiled"), (plain, "dop853"))]
    times = [run.events[0].time for run in runs]
    assert runs[0].terminated_by == event.name and 0.0 < times[0] < 0.5
    assert times[0] == pytest.approx(times[1], abs=1e-12)
    assert same_counts(*runs)


def _problem(rhs, x0: np.ndarray) -> OdeProblem:
    return OdeProblem(rhs, 0.0, x0, 1.0, None, 1e-6, 1e-8, None, np.inf, None, 0, (),
                      StateCheck("dop853_compiled", tuple(f"x{i}" for i in range(x0.size)), None, None))


def test_the_compiled_loop_where_there_is_one_else_scipy() -> None:
    compiled, plain, x0 = engine_rhs("arm_swing")
    assert isinstance(compiled_dop853_stepper("dop853_compiled", _problem(compiled, x0)), CompiledDop853Stepper)
    assert isinstance(compiled_dop853_stepper("dop853_compiled", _problem(plain, x0)), ScipyStepper)


def test_a_scene_without_a_compiled_loop_runs_scipy_dop853() -> None:
    """arm_ptp (computed torque: no compiled loop) gives scipy's DOP853's run exactly."""
    scene = load_scene("arm_ptp").with_duration(0.2)
    runs = [Simulator(scene, IntegratorSpec(method, rtol=1e-6, atol=1e-8)).run()
            for method in ("dop853_compiled", "dop853")]
    assert np.array_equal(runs[0].x, runs[1].x)
    assert runs[0].stats.rhs_evals == runs[1].stats.rhs_evals
