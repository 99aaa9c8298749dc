"""The compiled fixed-step loops (sim/compiled_steps.py) against the Python loops of
integrate/fixed_step.py on pin.aba: the same run to rounding (no friction, and LuGre plus
Stribeck friction with its bristle states), under a held torque command, and divergence
caught at the same step with the same message."""
from __future__ import annotations

import numpy as np
import pytest

from youbot_dynamics.integrate.errors import DivergenceError
from youbot_dynamics.integrate.integrators import integrate
from youbot_dynamics.scene.schema import IntegratorSpec, load_scene
from youbot_dynamics.sim import engine
from youbot_dynamics.sim.simulator import Simulator

AGREEMENT = 1e-11
"""rad, rad/s, rad: largest difference after 0.3 s (measured 1.7e-14 for rk4 on arm_swing,
from ABA's rounding, which the steps carry; the bound leaves a factor of 500)."""


def both_rhs(scene_name: str, command: np.ndarray | None = None):
    """(the engine's rhs, which carries the compiled loop; the same function without it,
    which the Python loop calls), the initial state and the state names."""
    simulator = Simulator(load_scene(scene_name))
    model, state = simulator.model, simulator.state
    _, rhs = engine.right_hand_side(model, state.data, state.reference, command)
    assert getattr(rhs, "compiled_steps", None) is not None
    return rhs, (lambda t, x: rhs(t, x)), state.x.copy(), model.layout.names, model.nv


@pytest.mark.parametrize("scene_name", ["arm_swing", "arm_friction"])
@pytest.mark.parametrize("method", ["euler", "symplectic_euler", "rk4"])
def test_compiled_loop_matches_the_python_loop(scene_name: str, method: str) -> None:
    compiled, python, x0, names, nv = both_rhs(scene_name)
    times = np.linspace(0.0, 0.3, 31)
    runs = [integrate(rhs, x0, times, method, dt=2.5e-4 if method == "rk4" else 1e-4, n_positions=nv)
            for rhs in (compiled, python)]
    assert runs[0].stats.steps == runs[1].stats.steps
    assert np.array_equal(runs[0].t, runs[1].t)
    assert np.abs(runs[0].x - runs[1].x).max() <= AGREEMENT
    assert np.abs(runs[0].x[-1] - x0).max() > 0.1     # the arm moved


def test_held_command() -> None:
    command = np.array([0.5, -1.0, 0.3, 0.2, -0.1])
    compiled, python, x0, _, nv = both_rhs("arm_swing", command)
    runs = [integrate(rhs, x0, [0.0, 0.1], "rk4", dt=1e-3, n_positions=nv) for rhs in (compiled, python)]
    assert np.abs(runs[0].x - runs[1].x).max() <= AGREEMENT
    free = integrate(both_rhs("arm_swing")[0], x0, [0.0, 0.1], "rk4", dt=1e-3, n_positions=nv)
    assert np.abs(free.x[-1] - runs[0].x[-1]).max() > 1e-3     # the command acts


def test_divergence_at_the_same_step() -> None:
    compiled, python, x0, names, nv = both_rhs("arm_swing")
    bounds = np.full(x0.size, 4.0)      # the falling arm's joint 2 passes 4 rad/s within 0.3 s
    messages = []
    for rhs in (compiled, python):
        with pytest.raises(DivergenceError) as caught:
            integrate(rhs, x0, [0.0, 0.3], "rk4", dt=1e-3, n_positions=nv, bounds=bounds, state_names=names)
        messages.append(str(caught.value))
    assert messages[0] == messages[1]
    assert "outside its bounds" in messages[0]


def test_simulator_run_uses_it_and_agrees() -> None:
    scene = load_scene("arm_swing").with_duration(0.2)
    result = Simulator(scene, IntegratorSpec(method="rk4", dt=1e-3)).run()
    compiled, python, x0, _, nv = both_rhs("arm_swing")
    reference = integrate(python, x0, result.t, "rk4", dt=1e-3, n_positions=nv)
    assert np.abs(result.x - reference.x).max() <= AGREEMENT
