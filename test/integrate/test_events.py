"""The hybrid-system loop against analytic switching times: a bouncing ball (impacts that
reset the velocity in the same mode) and a thermostat (two modes with different dynamics)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from youbot_dynamics.integrate.events import Mode, Transition, simulate_hybrid
from youbot_dynamics.integrate.integrators import IntegrationError

G, HEIGHT, RESTITUTION = 9.81, 1.0, 0.8


def bouncing_ball(restitution: float = RESTITUTION, condition=None) -> list[Mode]:
    """x = (height, velocity); at height 0 falling, v -> -e v."""
    def bounce(t, x):
        x[1] = -restitution * x[1]
        return "flight", x
    return [Mode("flight", lambda t, x: np.array([x[1], -G]),
                 (Transition("bounce", lambda t, x: x[0], bounce, -1, condition),),
                 jac=lambda t, x: np.array([[0.0, 1.0], [0.0, 0.0]]))]


def analytic_bounce_times(n: int) -> np.ndarray:
    """t_1 = sqrt(2 h / g); then the flights last 2 e^k v_1 / g."""
    v1 = math.sqrt(2 * G * HEIGHT)
    times = [v1 / G]
    for k in range(1, n):
        times.append(times[-1] + 2 * RESTITUTION ** k * v1 / G)
    return np.array(times)


@pytest.mark.parametrize("integrator", ["dop853", "cvode_adams", "ida"])
def test_bounce_times_match_the_analytic_ones(integrator):
    expected = analytic_bounce_times(8)
    t_end = expected[-1] + RESTITUTION ** 8 * expected[0]  # half-way through flight 9
    solution = simulate_hybrid(bouncing_ball(), "flight", [HEIGHT, 0.0], [0.0, t_end],
                               integrator, rtol=1e-10, atol=1e-12)
    times = np.array([s.time for s in solution.switches])
    assert len(times) == 8
    np.testing.assert_allclose(times, expected, rtol=1e-8)
    for switch in solution.switches:
        assert switch.state_before[0] == pytest.approx(0.0, abs=1e-9)
        assert switch.state_after[1] == pytest.approx(-RESTITUTION * switch.state_before[1])
    assert solution.stats.events == 8
    assert solution.stats.simulated_time == pytest.approx(t_end)
    # both sides of every switch are in the output, at the same time
    for switch in solution.switches:
        at = np.flatnonzero(solution.t == switch.time)
        assert len(at) == 2 and solution.x[at[1], 1] == switch.state_after[1]


def test_thermostat_switches_between_two_modes_at_the_analytic_times():
    """Heating x' = 2 - x until x = 1.5, cooling x' = -x until x = 0.5: each phase lasts
    ln 3 exactly."""
    modes = [Mode("on", lambda t, x: 2.0 - x,
                  (Transition("hot", lambda t, x: x[0] - 1.5, lambda t, x: ("off", x), 1),)),
             Mode("off", lambda t, x: -x,
                  (Transition("cold", lambda t, x: x[0] - 0.5, lambda t, x: ("on", x), -1),))]
    t_eval = np.linspace(0.0, 5.5 * math.log(3.0), 200)
    solution = simulate_hybrid(modes, "on", [0.5], t_eval, "rk45", rtol=1e-10, atol=1e-12)
    times = [s.time for s in solution.switches]
    np.testing.assert_allclose(times, math.log(3.0) * np.arange(1, 6), rtol=1e-8)
    assert [s.kind for s in solution.switches] == ["hot", "cold"] * 2 + ["hot"]
    on = np.array(solution.mode) == "on"
    assert np.all(solution.x[on, 0] <= 1.5 + 1e-9) and np.all(solution.x[~on, 0] >= 0.5 - 1e-9)
    # outputs at every requested time, plus two samples per switch
    assert solution.t.size == t_eval.size + 2 * len(times)


def test_a_false_condition_passes_the_crossing_over():
    solution = simulate_hybrid(bouncing_ball(condition=lambda t, x: x[1] < -100.0), "flight",
                               [HEIGHT, 0.0], np.linspace(0.0, 1.0, 11), "dop853",
                               rtol=1e-10, atol=1e-12)
    assert solution.switches == [] and solution.stats.events == 1
    t = solution.t[-1]
    assert solution.x[-1, 0] == pytest.approx(HEIGHT - 0.5 * G * t ** 2, abs=1e-9)


def test_a_zeno_run_raises_instead_of_looping():
    with pytest.raises(IntegrationError, match="more than 20 guard crossings"):
        simulate_hybrid(bouncing_ball(0.5), "flight", [HEIGHT, 0.0], [0.0, 5.0], "dop853",
                        max_switches=20)


class BiasedStepper:
    """x(t) = t - 0.55 in steps of 0.1 s, whose interpolant is off by -0.1: between 0.5 and
    0.6 the step ends show the crossing and the interpolant shows none (as an implicit
    solver's interpolant can, near a guard)."""

    def __init__(self) -> None:
        self.t, self.h = 0.0, 0.0
        self.x = np.array([-0.55])

    def advance(self, t_target: float) -> None:
        self.h = min(0.1, t_target - self.t)
        self.t += self.h
        self.x = np.array([self.t - 0.55])

    def interpolate(self, t: float) -> np.ndarray:
        return np.array([t - 0.55 - 0.1])

    def finish(self, stats) -> None:
        pass


def test_a_crossing_the_interpolant_does_not_show_falls_back_to_the_step_end():
    from youbot_dynamics.integrate.drive import Event, StateCheck, drive, locate_crossings
    names = ("x",)
    solution = drive(BiasedStepper(), "biased", np.array([0.0, 1.0]),
                     [Event("zero", lambda t, x: x[0], 1)], StateCheck("biased", names, None, None),
                     names)
    assert solution.terminated_by == "zero"
    assert solution.t[-1] == pytest.approx(0.6, abs=1e-15)
    # where the interpolant does bracket the crossing, Brent's method finds it on it
    exact = locate_crossings([Event("zero", lambda t, x: x[0], 1)], [-0.05], [0.05], 0.5, 0.6,
                             lambda t: np.array([t - 0.55]))
    assert exact == [(pytest.approx(0.55, abs=1e-14), 0)]


@pytest.mark.parametrize("integrator", ["cvode_bdf", "ida"])
def test_sundials_locates_the_guard_itself(integrator):
    """CVODE and IDA stop at the root their own rootfinding located (no Brent step after
    them): the first bounce at sqrt(2 h / g) to 1e-8 relative (measured at rtol 1e-10:
    2.7e-14 with IDA, 4.4e-11 with CVODE BDF)."""
    from youbot_dynamics.integrate.drive import Event
    from youbot_dynamics.integrate.sundials import CvodeStepper, IdaStepper
    ball = bouncing_ball()[0]
    guard = (Event("bounce", lambda t, x: x[0], -1),)
    x0 = np.array([HEIGHT, 0.0])
    if integrator == "ida":
        stepper = IdaStepper(lambda t, y, yp: yp - ball.rhs(t, y), 0.0, x0, ball.rhs(0.0, x0),
                             5.0, np.zeros(2, dtype=bool), 1e-10, 1e-12, None, events=guard)
    else:
        stepper = CvodeStepper("BDF", integrator, ball.rhs, 0.0, x0, 5.0, 1e-10, 1e-12, None,
                               np.inf, None, events=guard)
    while not stepper.roots:
        stepper.advance(5.0)
    assert stepper.roots == [0]
    assert stepper.t == pytest.approx(analytic_bounce_times(1)[0], rel=1e-8)
    assert abs(stepper.x[0]) < 1e-9
