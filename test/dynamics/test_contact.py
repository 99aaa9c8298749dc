"""Contact laws against independent references: the restitution a Hunt-Crossley impact
actually produces (its ODE integrated by scipy), Coulomb's law, Newton's impact law on
known impacts, and the law specifications' errors."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from youbot_dynamics.dynamics.contact import (ContactLawError, HuntCrossley, NewtonImpact, contact_law_from_spec,
                                              hunt_crossley_force, hysteresis_factor, newton_impulse,
                                              regularised_coulomb)


def restitution_of_impact(e: float, model: str, v0: float = 2.0, k: float = 1e6, n: float = 1.5,
                          m: float = 0.05) -> float:
    """Rebound / approach speed of a mass m hitting a Hunt-Crossley wall at v0 (no gravity),
    integrated with scipy's DOP853 to separation."""
    chi = hysteresis_factor(e, v0, model)

    def rhs(t, y):
        return [y[1], -hunt_crossley_force(y[0], y[1], k, n, chi) / m]

    def separated(t, y):
        return y[0]
    separated.terminal, separated.direction = True, -1
    solution = solve_ivp(rhs, (0, 1.0), [1e-12, v0], method="DOP853", rtol=1e-12, atol=1e-15, events=separated)
    return -solution.y_events[0][0][1] / v0


@pytest.mark.parametrize("e", [0.3, 0.6, 0.8, 0.95])
def test_exact_damping_returns_the_restitution(e):
    assert restitution_of_impact(e, "exact") == pytest.approx(e, rel=1e-6)


@pytest.mark.parametrize("e", [0.001, 0.01, 0.02])
def test_exact_damping_returns_small_restitutions(e):
    """Below e ~ 0.027 the root of the energy balance lies within rounding of 1/e (it used
    to fail with a bracketing error)."""
    assert restitution_of_impact(e, "exact") == pytest.approx(e, rel=1e-6)


@pytest.mark.parametrize("model", ["exact", "flores"])
def test_zero_restitution_is_refused_where_damping_would_be_infinite(model):
    with pytest.raises(ContactLawError, match="needs restitution > 0"):
        hysteresis_factor(0.0, 1.0, model)
    spec = {"law": "hunt_crossley", "stiffness": 1e6, "restitution": 0, "friction": 0.2, "damping_model": model}
    with pytest.raises(ContactLawError, match="pair x/y: .*needs restitution > 0"):
        contact_law_from_spec(spec, "pair x/y")
    assert hysteresis_factor(0.0, 2.0, "lankarani_nikravesh") == pytest.approx(0.375)


@pytest.mark.parametrize("v0", [0.1, 1.0, 5.0])
def test_exact_damping_is_independent_of_speed_stiffness_and_mass(v0):
    assert restitution_of_impact(0.6, "exact", v0=v0, k=1e8, m=2.0) == pytest.approx(0.6, rel=1e-6)


def test_approximate_damping_models_miss_wood_restitution():
    """At e = 0.6 (dry wood) Flores is within 4 % and Lankarani-Nikravesh far off; near e = 1
    both approach the exact value: which is why the scenes use ``exact``."""
    flores, ln = restitution_of_impact(0.6, "flores"), restitution_of_impact(0.6, "lankarani_nikravesh")
    assert abs(flores / 0.6 - 1) > 0.01 and abs(flores / 0.6 - 1) < 0.04
    assert abs(ln / 0.6 - 1) > 0.1
    assert restitution_of_impact(0.99, "lankarani_nikravesh") == pytest.approx(0.99, rel=1e-3)


def test_hunt_crossley_force_is_hertz_when_quasi_static_and_never_pulls():
    assert hunt_crossley_force(1e-3, 0.0, 1e7, 1.5, 1.0) == pytest.approx(1e7 * 1e-3 ** 1.5)
    assert hunt_crossley_force(-1e-3, -1.0, 1e7, 1.5, 1.0) == 0.0
    assert hunt_crossley_force(1e-3, -2.0, 1e7, 1.5, 1.0) == 0.0


def test_regularised_coulomb_opposes_sliding_and_saturates():
    v = np.array([0.3, -0.4, 0.0])
    force = regularised_coulomb(v, 10.0, 0.5, 1e-4)
    assert np.linalg.norm(force) == pytest.approx(5.0, rel=1e-6)
    assert np.allclose(np.cross(force, v), 0) and force @ v < 0
    assert np.linalg.norm(regularised_coulomb(np.array([1e-6, 0, 0]), 10.0, 0.5, 1e-4)) < 0.06


def sphere_inverse_mass(m: float, r: float) -> np.ndarray:
    """W at the contact point of a solid sphere touching a plane below it (normal +z)."""
    arm = np.array([0.0, 0.0, -r])
    skew = np.array([[0, -arm[2], arm[1]], [arm[2], 0, -arm[0]], [-arm[1], arm[0], 0]])
    inertia_inv = np.eye(3) / (0.4 * m * r * r)
    return np.eye(3) / m - skew @ inertia_inv @ skew


def test_newton_impulse_reverses_normal_velocity_by_e():
    w, n = sphere_inverse_mass(0.1, 0.05), np.array([0.0, 0.0, 1.0])
    impulse, sticking = newton_impulse(w, np.array([0.0, 0.0, -2.0]), n, 0.6, 0.3)
    assert sticking
    assert impulse == pytest.approx([0.0, 0.0, 0.1 * 3.2])
    assert (np.array([0, 0, -2.0]) + w @ impulse)[2] == pytest.approx(1.2)


def test_newton_impulse_slides_with_coulomb_impulse_and_sticks_with_high_friction():
    w, n = sphere_inverse_mass(0.1, 0.05), np.array([0.0, 0.0, 1.0])
    u = np.array([3.0, 0.0, -2.0])
    impulse, sticking = newton_impulse(w, u, n, 0.5, 0.1)
    assert not sticking
    assert impulse[2] == pytest.approx(0.1 * 3.0)                 # normal: m (1 + e) v
    assert impulse[0] == pytest.approx(-0.1 * impulse[2])         # slides: |P_t| = mu P_n
    impulse, sticking = newton_impulse(w, u, n, 0.5, 10.0)
    assert sticking and (u + w @ impulse)[0] == pytest.approx(0.0, abs=1e-12)
    # a sphere's contact point stops when |P_t| = m |u_t| 2/7 (rolling, Routh)
    assert abs(impulse[0]) == pytest.approx(0.1 * 3.0 * 2 / 7)


def test_law_specs_and_their_errors():
    law = contact_law_from_spec({"law": "hunt_crossley", "stiffness": "1e6", "restitution": 0.5, "friction": 0.2},
                                "pair a/b")
    assert isinstance(law, HuntCrossley) and law.stiffness == 1e6 and law.exponent == 1.5
    assert isinstance(contact_law_from_spec({"law": "newton", "restitution": 1, "friction": 0}, "p"), NewtonImpact)
    for spec, words in [({"law": "magnet"}, "unknown contact law"),
                        ({"law": "newton", "restitution": 0.5}, "missing parameter(s) friction"),
                        ({"law": "newton", "restitution": 1.5, "friction": 0}, "restitution must lie"),
                        ({"law": "newton", "restitution": 0.5, "friction": 0, "glue": 1}, "no parameter 'glue'"),
                        ({"law": "hunt_crossley", "stiffness": 1, "restitution": 0.5, "friction": 0,
                          "damping_model": "magic"}, "damping_model")]:
        with pytest.raises(ContactLawError, match="pair x/y") as error:
            contact_law_from_spec(spec, "pair x/y")
        assert words in str(error.value)
