"""The error estimate of a run (sim/error_estimate.py): the companion's settings and
Richardson's factor, the estimate against an analytic true error, against a tight reference
on the issue's four cases (a fast subset; the full table is slow), the chunked companion
(the node's) equal to the whole-run one, and the fallback for a controller that cannot be
sent to a worker."""
from __future__ import annotations

import math
import threading

import numpy as np
import pytest

from youbot_dynamics.accuracy.estimate_check import FACTOR, markdown, ode_rows
from youbot_dynamics.scene.schema import IntegratorSpec, Scene, load_scene
from youbot_dynamics.sim import companion
from youbot_dynamics.sim.build import compile
from youbot_dynamics.sim.companion import CompanionStream
from youbot_dynamics.sim.error_estimate import companion_spec, estimate_factor, rotation_angle
from youbot_dynamics.sim.simulator import Simulator
from youbot_dynamics.studies.estimate_table import CASES, FAST, table


def test_companion_settings_and_richardson_factor() -> None:
    assert companion_spec(IntegratorSpec("rk4", dt=2e-3)).dt == 1e-3
    adaptive = companion_spec(IntegratorSpec("dop853", rtol=1e-8, atol=1e-10))
    assert math.isclose(adaptive.rtol, 5e-10) and math.isclose(adaptive.atol, 5e-12)
    by_tol = companion_spec(IntegratorSpec("rk45", rtol=1e-6, atol=None, tol=1e-6))  # atol_i = tol * scale_i
    assert math.isclose(by_tol.tol, 5e-8) and math.isclose(by_tol.rtol, 5e-8) and by_tol.atol is None
    # 2^p / (2^p - 1): p = 1 for Euler and the constraint steppers, 4 for RK4; 1 for adaptive
    assert estimate_factor("euler") == 2.0 and estimate_factor("pgs") == 2.0
    assert math.isclose(estimate_factor("rk4"), 16 / 15) and estimate_factor("cvode_bdf") == 1.0


def test_rotation_angle_of_a_known_turn() -> None:
    turn = 0.3
    c, s = math.cos(turn), math.sin(turn)
    rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    assert math.isclose(float(rotation_angle(np.eye(3), rz)), turn, rel_tol=1e-12)


@pytest.mark.parametrize("method, dt", [("euler", 1e-3), ("rk4", 5e-2)])
def test_richardson_estimate_meets_the_analytic_error(method: str, dt: float) -> None:
    """x' = -x from 1 over 2 s: the true error is |x_h - exp(-t)|; Richardson's estimate with
    the method's order lies within 5 % of it (measured: euler ratio 0.9995, rk4 1.003)."""
    times = np.linspace(0.0, 2.0, 21)
    exact = np.exp(-times)[:, None]
    [row] = ode_rows("decay", lambda t, x: -x, np.array([1.0]), times, method, (dt,), exact, 0.0,
                     {"x": (slice(0, 1), "m")})
    assert row.resolved and abs(row.ratio - 1.0) < 0.05, row


def test_fast_subset_of_the_table_within_a_factor_3() -> None:
    """One to three integrators per case (the full table: the slow test below); measured
    ratios 0.83 to 1.05 but ball_drop's positions, 2.9 (its companion's error at tol/20 is
    not much below the run's through the contact), so the bound is the acceptance factor 3."""
    rows = table(FAST)
    judged = [r for r in rows if r.failure is None and r.resolved]
    assert len(judged) >= 12, markdown(rows)
    assert {r.case for r in judged} == set(FAST)
    assert all(r.within for r in judged), markdown(rows)


@pytest.mark.slow
def test_full_table_within_a_factor_3() -> None:
    """Every registry integrator at three settings on the four cases (docs/accuracy.md):
    measured 207 of 211 resolved rows within a factor 3, all within 0.58 to 6.0 (the four
    beyond are over-estimates: symplectic Euler on the 2 s arm_swing, whose error is the size
    of the motion, and ball_drop at rtol 1e-5). Bounds: 95 % within 3, every row within 9."""
    rows = table(CASES)
    judged = [r for r in rows if r.failure is None and r.resolved]
    inside = [r for r in judged if r.within]
    assert len(inside) >= 0.95 * len(judged), markdown(rows)
    assert all(1 / (3 * FACTOR) <= r.ratio <= 3 * FACTOR for r in judged), markdown(rows)


@pytest.mark.parametrize("name", ["arm_swing", "gripping"])
def test_the_chunked_companion_is_the_same_run_at_the_companion_settings(name: str) -> None:
    """The node's companion (in a worker, fed chunk by chunk) gives the differences of the
    main run against the same chunks run here at tol/20 or dt/2 (times Richardson's factor),
    to rounding, counting from the last reset; the contact events of both are counted."""
    scene = load_scene(name).with_duration(0.4)
    simulator = Simulator(scene)
    here = Simulator(scene, companion_spec(simulator.integrator))
    stream = CompanionStream(simulator.model)
    largest = 0.0
    try:
        push = np.full(len(simulator.joint_names), 5.0)   # the companion told of a torque the run did not take:
        for k in range(10):   # a first run far apart, forgotten at the reset (the node's reset)
            times = (5 * k + 1 + np.arange(5)) * 0.002
            stream.submit(times, push, simulator.state.reference, simulator.advance_through(times))
        simulator.reset()
        stream.reset()
        for k in range(40):
            times = (5 * k + 1 + np.arange(5)) * 0.002
            mine = simulator.advance_through(times)
            stream.submit(times, None, simulator.state.reference, mine)
            theirs = here.advance_through(times)
            largest = max(largest, max(float(np.max(np.abs(a.q - b.q))) for a, b in zip(mine, theirs)))
        estimate = stream.estimate(simulator.events if simulator.model.contact else None, wait=True)
    finally:
        stream.close()
    expected = estimate_factor(simulator.integrator.method) * largest
    assert largest > 0 and math.isclose(estimate.largest["joint_angles"], expected, rel_tol=1e-9)
    if simulator.model.contact:
        assert (estimate.events, estimate.companion_events) == (len(simulator.events), len(here.events))


def test_a_controller_that_cannot_travel_runs_its_companion_here() -> None:
    """A Python controller holding a lock cannot be sent to a worker: the companion runs
    in this process after the run, and ``where`` says so; the estimate is the same kind."""
    lock = threading.Lock()
    scene = Scene.from_dict({"moving": ["arm_joint_2"], "initial": {"q": {"arm_joint_2": 1.0}},
                             "integrator": {"method": "rk45", "tol": 1e-6}, "duration": 0.3})

    def damping(t, q, v):
        with lock:
            return -2.0 * v

    result = companion.run(compile(scene, controller=damping, control_rate=100.0), error_estimate=True)
    estimate = result.error_estimate
    assert estimate.where.startswith("this process") and "lock" in estimate.where
    assert 0 < estimate.largest["joint_angles"] < 1e-3
