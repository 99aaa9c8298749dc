"""The equation pipeline against independent references: closed-form solutions, document
000's published Pantelides lists and low-pass blocks (benchmarks.md section 6), a hand-written
angle-form pendulum and the project's hand-written damped pendulum."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
import sympy as sp

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import DivergenceError, integrate
from youbot_dynamics.studies.dummy_derivatives import full_pivot_columns
from youbot_dynamics.studies.equations import (LAG_SECOND_RUN, T, EquationModel,
                                               cartesian_pendulum, der, first_order_lag,
                                               lowpass_filter, modia_pendulum,
                                               second_order_system, unknown)
from youbot_dynamics.studies.pipeline import run_pipeline, simulate
from youbot_dynamics.studies.state_selection import simulate_with_reselection
from youbot_dynamics.studies.structure import LOWPASS_INCIDENCE, structure_report
from youbot_dynamics.studies.uncertain_pendulum import pendulum_rhs


@pytest.fixture(scope="module")
def pendulum():
    return run_pipeline(cartesian_pendulum(angle0=0.5))


def test_lag_document_runs_follow_the_closed_form():
    """Document 000's two runs: defaults tau = 1 s, x(0) = 0 on [0, 5] s, then x(0) = 2,
    tau = 5 s on [0, 10] s; x = 1 + (x(0) - 1) exp(-t / tau)."""
    lag = first_order_lag()
    merge, t_end = LAG_SECOND_RUN
    second = replace(lag | merge, t_end=t_end)
    assert (lag.parameters["tau"], lag.variables["x"], lag.t_end) == (1.0, 0.0, 5.0)
    assert (second.parameters["tau"], second.variables["x"], second.t_end) == (5.0, 2.0, 10.0)
    for model in (lag, second):
        tau, x0 = model.parameters["tau"], model.variables["x"]
        result = run_pipeline(model)
        assert result.aliases == [("RHS", "x'", "f2")]
        solution = simulate(result, "dop853", tol=1e-10, n_outputs=51)
        exact = 1.0 + (x0 - 1.0) * np.exp(-solution.t / tau)
        # measured: 5.6e-11 (first run), 3.7e-10 (second) with dop853 at tol 1e-10; margin 2.7x
        assert np.max(np.abs(solution.x[:, 0] - exact)) < 1e-9
        observed = result.ode.observe(2.0, np.array([0.25]))
        assert observed["RHS"] == pytest.approx((1.0 - 0.25) / tau, rel=1e-15)


def test_second_order_system_lowers_to_four_states_and_matches_by_hand():
    """Document 000's ode_order_lowering example: states x, x' (xd), y, z; the generated
    ODE against the system written by hand, both DOP853 at 1e-12 over [0, 10] s."""
    result = run_pipeline(second_order_system())
    assert result.ode.state_names == ["x", "xd", "y", "z"]
    sigma, rho, beta = 10.0, 10.0, 8.0 / 3.0

    def by_hand(t, s):
        x, xd, y, z = s
        return np.array([xd, sigma * (y - x), x * (rho - z) - y, x * y - beta * z])
    times = np.linspace(0.0, 10.0, 101)
    generated = simulate(result, "dop853", tol=1e-12, t_eval=times)
    reference = integrate(by_hand, [1.0, 0.0, 0.0, 0.0], times, "dop853", rtol=1e-12,
                          atol=1e-12)
    # measured 4.2e-11 apart
    assert np.max(np.abs(generated.x - reference.x)) < 1e-8


def test_merge_overrides_start_values_and_refuses_unknown_names():
    assert (first_order_lag() | {"x": 0.5}).variables["x"] == 0.5
    with pytest.raises(UserInputError, match="no parameter or variable Tau"):
        first_order_lag() | {"Tau": 1.0}


def test_pendulum_pantelides_reproduces_the_seeds_lists(pendulum):
    # benchmarks.md section 6, the seed's result
    reduced = pendulum.pantelides
    assert pendulum.new_variables == ["u = x'", "v = y'"]
    assert reduced.vmap() == {"x": "x'", "y": "y'", "u": "u'", "v": "v'", "x'": "x''",
                              "y'": "y''"}
    assert reduced.eqmap() == {"f5": "f6", "f6": "f7", "f1": "f8", "f2": "f9"}
    assert reduced.assignment_names() == {"x'": "f1", "y'": "f2", "u'": "f8", "v'": "f4",
                                          "lambda": "f3", "x''": "f7", "y''": "f9"}
    assert (len(reduced.equations), len(reduced.variables)) == (9, 11)
    assert reduced.structural_index == 3


def test_pendulum_dummy_derivatives_hanging_start(pendulum):
    # Near hanging |y| > |x|: df6/dy' = 2y is the larger pivot, so y' is the dummy (y is
    # computed from the constraint) and x, u = x' are the states.
    levels = pendulum.dummies.levels
    assert [level.equations for level in levels] == [["f7", "f8", "f9"], ["f6"]]
    assert [level.selected for level in levels] == [["y''", "x''", "v'"], ["y'"]]
    assert pendulum.ode.state_names == ["x", "u"]
    assert pendulum.tearing == [{"tearing_variables": ["lambda"], "residuals": ["f7"],
                                 "causal": ["f3: u' := lambda*x", "f4: v' := -g + lambda*y",
                                            "f8: x'' := u'", "f9: y'' := v'"]}]


def test_pendulum_dummy_derivatives_flip_near_horizontal():
    result = run_pipeline(cartesian_pendulum(angle0=1.3))
    assert [level.selected for level in result.dummies.levels] == [["x''", "y''", "u'"],
                                                                   ["x'"]]
    assert result.ode.state_names == ["y", "v"]


def angle_form_rhs(x: float, u: float, length: float, g: float) -> np.ndarray:
    """(x', u') from theta'' = -(g / l) sin(theta), x = l sin(theta), written by hand."""
    sin, cos = x / length, math.sqrt(1.0 - (x / length) ** 2)
    omega = u / (length * cos)
    return np.array([u, length * (cos * (-g / length * sin) - sin * omega**2)])


def test_generated_pendulum_ode_matches_the_angle_form(pendulum):
    solution = simulate(pendulum, "dop853", tol=1e-10, n_outputs=101)
    length, g = 1.0, pendulum.model.parameters["g"]
    for t, state in zip(solution.t, solution.x):
        generated = pendulum.ode.rhs(t, state)
        # measured: at most 1.8e-15 apart along the 10 s trajectory (rounding only)
        assert np.max(np.abs(generated - angle_form_rhs(*state, length, g))) < 1e-10
    angle = integrate(lambda t, s: np.array([s[1], -g / length * math.sin(s[0])]),
                      [0.5, 0.0], solution.t, "dop853", rtol=1e-12, atol=1e-14)
    # measured: 3.1e-11 between the two trajectories (tol 1e-10 on the generated one)
    assert np.max(np.abs(solution.x[:, 0] - length * np.sin(angle.x[:, 0]))) < 1e-9


def test_lowpass_blocks_and_incidence_are_structure_py_s():
    result = run_pipeline(lowpass_filter())
    seed = structure_report("lowpass")
    assert result.blocks == [[f"f{i}" for i in block] for block in seed["blocks"]]
    numbered = ["uR1", "u0", "uR2", "vn", "vC", "vC'", "i"]      # the seed's 1..7
    rows = [{numbered.index(result.blt_variables[j]) + 1 for j, c in enumerate(row) if c == "x"}
            for row in result.blt_incidence]
    assert rows == [set(vs) for vs in LOWPASS_INCIDENCE]
    assert result.tearing[0]["tearing_variables"] == ["uR1"]
    assert result.tearing[0]["residuals"] == ["f4"]
    solution = simulate(result, "dop853", tol=1e-10, n_outputs=21)
    exact = 1.0 - np.exp(-solution.t / (200.0 * 1e-3))
    assert np.max(np.abs(solution.x[:, 0] - exact)) < 1e-9      # measured 5.2e-11


def test_modia_pendulum_merge_matches_the_hand_written_pendulum():
    base = modia_pendulum()
    merged = run_pipeline(base | {"L": 0.5})
    assert base.parameters["L"] == 0.8
    solution = simulate(merged, "dop853", tol=1e-9, n_outputs=101)
    for t, (phi, w) in zip(solution.t, solution.x):
        reference = pendulum_rhs(phi, w, 0.5, 1.0, 0.5, np.sin)
        # measured: 0 (the same floating-point operations); 1e-12 leaves room for
        # another summation order
        assert np.max(np.abs(merged.ode.rhs(t, np.array([phi, w])) - reference)) < 1e-12
        observed = merged.ode.observe(t, np.array([phi, w]))
        assert observed["rx"] == pytest.approx(0.5 * math.cos(phi), abs=1e-15)
        assert observed["ry"] == pytest.approx(-0.5 * math.sin(phi), abs=1e-15)


def test_third_order_lowering_and_a_negative_alias():
    x, z = unknown("x"), unknown("z")
    model = EquationModel("jerk", {"x": 1.0, "x_t": 0.0, "x_t_t": -1.0, "z": None}, {},
                          (z - x, der(x, 3) + z))         # x''' = -z = -x
    result = run_pipeline(model)
    assert result.new_variables == ["x_t = x'", "x_t_t = x_t'"]
    assert result.aliases == [("z", "x", "f3")]
    assert result.ode.state_names == ["x", "x_t", "x_t_t"]
    solution = simulate(result, "dop853", tol=1e-12, n_outputs=11, t_end=1.0)
    # the closed form of x''' = -x, x(0) = 1, x'(0) = 0, x''(0) = -1 by sympy's dsolve
    x_exact = sp.Function("x")(T)
    exact = sp.dsolve(x_exact.diff(T, 3) + x_exact,
                      ics={x_exact.subs(T, 0): 1, x_exact.diff(T).subs(T, 0): 0,
                           x_exact.diff(T, 2).subs(T, 0): -1}).rhs
    values = sp.lambdify(T, exact, "numpy")(solution.t)
    assert np.max(np.abs(solution.x[:, 0] - values)) < 1e-9      # measured 1.7e-11


def test_negative_alias_is_substituted_with_its_sign():
    x, z = unknown("x"), unknown("z")
    model = EquationModel("decay", {"x": 1.0, "z": None}, {}, (z + x, der(x) - z))
    result = run_pipeline(model)
    assert result.aliases == [("z", "-x", "f1")]
    assert str(result.ode.derivatives["x"]) == "-x"


def test_start_values_that_break_the_constraint_are_refused():
    # x0 = sin(0.5), y0 = -cos(0.5) hold for L = 1 only
    with pytest.raises(UserInputError, match="y = -1.33047.*start value is -0.87758"):
        run_pipeline(cartesian_pendulum(angle0=0.5) | {"L": 2.0})
    with pytest.raises(UserInputError, match="is not real"):
        run_pipeline(cartesian_pendulum(angle0=0.5) | {"L": 0.01})
    consistent = cartesian_pendulum(angle0=0.5) | {"L": 4.0, "x": 2 * math.sin(0.5),
                                                        "y": -2 * math.cos(0.5)}
    assert run_pipeline(consistent).ode.state_names == ["x", "u"]


def test_full_pivoting_prefers_the_larger_pivot_and_refuses_a_singular_jacobian():
    columns, pivots = full_pivot_columns(np.array([[0.3, -1.7]]), [(-1, 0), (-1, 1)])
    assert (columns, pivots) == ([1], [-1.7])
    with pytest.raises(UserInputError, match="singular at the start values"):
        full_pivot_columns(np.array([[1.0, 2.0], [2.0, 4.0]]), [(-1, 0), (-1, 1)])


def test_released_near_horizontal_the_static_selection_breaks_and_reselection_holds():
    # from 1.5 rad x' is the dummy (states y, v); at the bottom x -> 0 and x = sqrt(L - y^2)
    # has no derivative: the static selection diverges (measured: at t = 0.58 s)
    model = replace(cartesian_pendulum(angle0=1.5) | {"g": 9.81}, t_end=5.0)
    with pytest.raises(DivergenceError), np.errstate(all="ignore"):
        simulate(run_pipeline(model), "dop853", tol=1e-10, n_outputs=101)
    run = simulate_with_reselection(model, "dop853", tol=1e-10, n_outputs=101)
    # measured: switches where |chosen pivot| = |other| / 2, i.e. at atan(1/2) = 0.46 rad
    # from the vertical or the horizontal: 8 in 5 s, alternating
    switches = run.switches()
    assert len(switches) == 8
    assert switches[0].endswith("states y, v -> x, u")
    assert switches[1].endswith("states x, u -> y, v")
    t, x = run.values("x")
    angle = integrate(lambda t, s: np.array([s[1], -9.81 * math.sin(s[0])]), [1.5, 0.0], t,
                      "dop853", rtol=1e-12, atol=1e-14)
    # measured: 3.3e-9 from the angle form over 5 s (tol 1e-10, 8 restarts)
    assert np.max(np.abs(x - np.sin(angle.x[:, 0]))) < 1e-7
