"""The integrator registry: one table answers every question about a name (kind, step
control, options, factory), and every consumer (integrate, the scene validator) agrees
with it."""
from __future__ import annotations

import numpy as np
import pytest

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import integrate
from youbot_dynamics.integrate.registry import (FIXED_STEP, INTEGRATORS, REGISTRY, STEPPERS,
                                                integrator_entry, integrator_kind, integrator_names,
                                                is_fixed_step)
from youbot_dynamics.scene.schema import Scene, SceneError


def test_every_name_has_one_kind_and_the_lists_derive_from_the_table():
    assert integrator_kind("rk45") == "ode" and integrator_kind("ida") == "dae"
    assert integrator_kind("pgs") == "stepper" and integrator_kind("lsoda") == "ode"
    assert STEPPERS == ("pgs", "admm") and FIXED_STEP == ("euler", "symplectic_euler", "rk4")
    assert set(INTEGRATORS) | set(STEPPERS) == set(REGISTRY)
    assert integrator_names("ode", stiff=True) == ("radau", "bdf", "lsoda", "cvode_bdf")
    for name, entry in REGISTRY.items():
        assert entry.options == (("dt",) if is_fixed_step(name) else ("tol", "rtol", "atol"))
        assert (entry.factory is not None) == (entry.kind == "ode")


def test_unknown_name_lists_the_known_ones():
    with pytest.raises(UserInputError, match="unknown integrator 'rk99'.*lsoda"):
        integrator_entry("rk99")
    with pytest.raises(UserInputError, match="constraint-contact stepper"):
        integrate(lambda t, x: -x, [1.0], [0.0, 1.0], "pgs", dt=1e-3)


@pytest.mark.parametrize("name", integrator_names("ode"))
def test_every_ode_factory_solves_the_oscillator(name):
    """q'' = -q from (1, 0): q(1) = cos 1 (fixed steps at dt = 1e-4: measured errors 2.7e-5
    and 4.2e-5 for Euler and symplectic Euler; at rtol 1e-8 at most 5.8e-8 (CVODE))."""
    solution = integrate(lambda t, x: np.array([x[1], -x[0]]), [1.0, 0.0], [0.0, 1.0], name,
                         dt=1e-4, rtol=1e-8, atol=1e-10, n_positions=1)
    assert abs(solution.x[-1, 0] - np.cos(1.0)) < (1e-4 if name in ("euler", "symplectic_euler") else 5e-7)
    assert solution.stats.integrator == name and solution.stats.steps > 0


def _scene_with(method: dict) -> dict:
    return {"name": "registry", "robot": "none", "integrator": method, "duration": 0.1,
            "free_bodies": [{"name": "ball", "shape": {"type": "sphere", "radius": 0.05},
                             "density": 700, "position": [0, 0, 1]}]}


@pytest.mark.parametrize("name", integrator_names("ode"))
def test_scene_validator_takes_every_ode_name_with_its_options(name):
    options = {"dt": 1e-3} if is_fixed_step(name) else {"tol": 1e-6}
    spec = Scene.from_dict(_scene_with({"method": name, **options})).integrator
    assert spec.method == name
    wrong = {"tol": 1e-6} if is_fixed_step(name) else {"dt": 1e-3}
    with pytest.raises(SceneError) as caught:
        Scene.from_dict(_scene_with({"method": name, **wrong}))
    assert caught.value.key.startswith("integrator.")


def test_scene_validator_names_the_known_integrators():
    with pytest.raises(SceneError, match="lsoda") as caught:
        Scene.from_dict(_scene_with({"method": "rk99"}), source="notebook")
    assert caught.value.key == "integrator.method" and str(caught.value).startswith("notebook: ")
