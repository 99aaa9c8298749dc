"""Contact laws, each written once: compliant Hunt-Crossley with regularised Coulomb
friction, Newton's impact law with a Coulomb friction impulse, and the parameters of the
constraint-based law solved by :mod:`youbot_dynamics.dynamics.contact_stepper`.

Conventions: a contact has a unit normal ``n`` pointing from body 1 to body 2 (coal's
convention), a penetration depth ``delta = -signed distance`` (m, > 0 when the shapes
overlap) and the relative velocity ``u = v2 - v1`` of body 2's contact point with respect
to body 1's (m/s, world frame). ``u . n < 0`` means approach. Forces and impulses returned
here act on body 2 (N or N s, world frame); body 1 receives the opposite.

Hunt-Crossley (1975): F_n = k delta^n (1 + chi d delta/dt), clipped at 0, with the
hysteresis factor chi (s/m) derived from the coefficient of restitution e and the normal
approach speed v0 at first touch. ``damping_model`` names the derivation:

- ``exact``: the root x = chi v0 of (1 - e x) = (1 + x) exp(-(1 + e) x), the energy
  balance of the undamped-by-gravity impact m d2delta/dt2 = -k delta^n (1 + chi ddelta/dt)
  integrated in closed form (independent of k, n and m): returns exactly e.
- ``flores``: chi = 8 (1 - e) / (5 e v0) (Flores, Machado, Silva, Martins 2011).
- ``lankarani_nikravesh``: chi = 3 (1 - e^2) / (4 v0) (1990; meant for e near 1).

Regularised Coulomb friction: F_t = -mu F_n u_t / sqrt(|u_t|^2 + v_s^2) with the velocity
scale v_s (m/s): a body under a tangential load below mu F_n creeps at a speed of order v_s
instead of sticking.
"""
from __future__ import annotations

import functools
import math
from dataclasses import MISSING, dataclass, fields
from typing import Any, Mapping

import numpy as np
from scipy.optimize import brentq

from youbot_dynamics.errors import UserInputError

DAMPING_MODELS = ("exact", "flores", "lankarani_nikravesh")


class ContactLawError(UserInputError):
    """A contact law that cannot be built: unknown name, missing or bad parameter."""


def hysteresis_factor(restitution: float, approach_speed: float, model: str = "exact") -> float:
    """Hunt-Crossley hysteresis factor chi (s/m) for restitution e at approach speed v0 (m/s)."""
    e, v0 = float(restitution), abs(float(approach_speed))
    if model not in DAMPING_MODELS:
        raise ContactLawError(f"unknown Hunt-Crossley damping model {model!r}; known: {', '.join(DAMPING_MODELS)}")
    if model != "lankarani_nikravesh" and e <= 0.0:
        raise ContactLawError(f"Hunt-Crossley damping model {model!r} needs restitution > 0, got {e} "
                              "(chi grows as 1/e: a perfectly plastic impact needs infinite damping); "
                              "give a small positive restitution")
    if v0 == 0.0 or e >= 1.0:
        return 0.0
    if model == "flores":
        return 8.0 * (1.0 - e) / (5.0 * e * v0)
    if model == "lankarani_nikravesh":
        return 3.0 * (1.0 - e * e) / (4.0 * v0)
    return exact_hysteresis_product(e) / v0


@functools.lru_cache(maxsize=64)  # a root solve that depends on e alone, asked for at every force evaluation
def exact_hysteresis_product(restitution: float) -> float:
    """x = chi v0 > 0 solving ln(1 - e x) - ln(1 + x) + (1 + e) x = 0, 0 < e < 1 (x < 1/e,
    and x -> 1/e as e -> 0)."""
    e = restitution

    def balance(x: float) -> float:
        return math.log1p(-e * x) - math.log1p(x) + (1.0 + e) * x

    upper = (1.0 - 1e-15) / e
    if balance(upper) >= 0.0:  # e < ~0.027: the root lies within rounding of 1 / e
        return 1.0 / e
    lower = 1e-6 * min(1.0, upper)
    while balance(lower) <= 0.0:
        lower *= 1e-3
    return brentq(balance, lower, upper, xtol=1e-15, rtol=1e-14)


def hunt_crossley_force(depth: float, depth_rate: float, stiffness: float, exponent: float,
                        chi: float) -> float:
    """Normal force magnitude (N, >= 0): k delta^n (1 + chi d delta/dt) for delta > 0."""
    if depth <= 0.0:
        return 0.0
    return max(0.0, stiffness * depth ** exponent * (1.0 + chi * depth_rate))


def hunt_crossley_potential(depth: float, stiffness: float, exponent: float) -> float:
    """Elastic energy (J) stored in the spring part of the law, k delta^(n+1) / (n+1) for
    delta > 0: the work of k delta^n along the overlap (the damping part only dissipates)."""
    if depth <= 0.0:
        return 0.0
    return stiffness * depth ** (exponent + 1.0) / (exponent + 1.0)


def regularised_coulomb(tangential_velocity: np.ndarray, normal_force: float, mu: float,
                        velocity_scale: float) -> np.ndarray:
    """Friction force (N, on body 2): -mu F_n u_t / sqrt(|u_t|^2 + v_s^2)."""
    speed2 = float(tangential_velocity @ tangential_velocity)
    return (-mu * normal_force / math.sqrt(speed2 + velocity_scale * velocity_scale)) * tangential_velocity


def newton_impulse(inverse_mass: np.ndarray, velocity: np.ndarray, normal: np.ndarray,
                   restitution: float, mu: float) -> tuple[np.ndarray, bool]:
    """Newton's impact law with a Coulomb friction impulse, for one contact point.

    ``inverse_mass`` W (3x3, world frame, m/(N s)) maps an impulse P on body 2 (and -P on
    body 1) to the change of the relative contact velocity: u+ = u- + W P. The sticking
    impulse makes u+ = -e (u-.n) n; if its tangential part leaves the cone |P_t| <= mu P_n
    the impulse slides: P = P_n (n + mu t), t the unit direction of the sticking impulse's
    tangential part, with P_n from the normal restitution condition alone.
    Returns (P (N s, world frame, on body 2), sticking).
    """
    un = float(velocity @ normal)
    target = -restitution * un * normal
    sticking = np.linalg.solve(inverse_mass, target - velocity)
    pn = float(sticking @ normal)
    pt = sticking - pn * normal
    pt_norm = np.linalg.norm(pt)
    if pt_norm <= mu * pn:
        return sticking, True
    direction = normal + (mu / pt_norm) * pt
    pn = -(1.0 + restitution) * un / float(normal @ inverse_mass @ direction)
    return pn * direction, False


# ---------------------------------------------------------------------------------------
# Law parameters, as a scene names them
# ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class HuntCrossley:
    """Compliant law: stiffness k (N/m^n), exponent n (1.5 Hertz), restitution e, friction
    mu, velocity scale v_s (m/s) of the regularised Coulomb law, damping model (see module)."""

    stiffness: float
    restitution: float
    friction: float
    exponent: float = 1.5
    velocity_scale: float = 1e-3
    damping_model: str = "exact"

    law = "hunt_crossley"


@dataclass(frozen=True)
class NewtonImpact:
    """Impulsive law: restitution e and Coulomb friction mu of the impact impulse; contacts
    slower than ``rest_speed`` (m/s) at impact are a resting contact the law cannot carry
    (an error: the run would chatter towards a Zeno point)."""

    restitution: float
    friction: float
    rest_speed: float = 0.05

    law = "newton"


@dataclass(frozen=True)
class ConstraintContact:
    """Constraint-based law (Pinocchio's PointContactConstraintModel + PGS or ADMM):
    restitution e (Newton's law on the normal velocity target) and Coulomb friction mu."""

    restitution: float
    friction: float

    law = "constraint"


CONTACT_LAWS: dict[str, type] = {cls.law: cls for cls in (HuntCrossley, NewtonImpact, ConstraintContact)}
ContactLaw = HuntCrossley | NewtonImpact | ConstraintContact


def contact_law_from_spec(spec: Mapping[str, Any], where: str) -> ContactLaw:
    """A law from ``{law: name, parameter: value, ...}``; errors name ``where``."""
    name = spec.get("law")
    if name not in CONTACT_LAWS:
        raise ContactLawError(f"{where}: unknown contact law {name!r}; known: {', '.join(CONTACT_LAWS)}")
    cls = CONTACT_LAWS[name]
    known = {f.name: f for f in fields(cls)}
    values: dict[str, Any] = {}
    for key, value in spec.items():
        if key == "law":
            continue
        if key not in known:
            raise ContactLawError(f"{where}: law {name!r} has no parameter {key!r}; parameters: {', '.join(known)}")
        if key == "damping_model":
            if value not in DAMPING_MODELS:
                raise ContactLawError(f"{where}: damping_model {value!r} unknown; known: {', '.join(DAMPING_MODELS)}")
            values[key] = value
            continue
        try:
            values[key] = float(value)
        except (TypeError, ValueError):
            raise ContactLawError(f"{where}: {key} must be a number, got {value!r}") from None
        if not math.isfinite(values[key]) or values[key] < 0:
            raise ContactLawError(f"{where}: {key} must be finite and >= 0, got {value!r}")
    missing = [key for key, f in known.items() if key not in values and f.default is MISSING]
    if missing:
        raise ContactLawError(f"{where}: law {name!r} is missing parameter(s) {', '.join(missing)}")
    if not 0.0 <= values["restitution"] <= 1.0:
        raise ContactLawError(f"{where}: restitution must lie in [0, 1], got {values['restitution']}")
    if name == "hunt_crossley":
        if values["stiffness"] <= 0 or values.get("velocity_scale", 1.0) <= 0:
            raise ContactLawError(f"{where}: stiffness and velocity_scale must be positive")
        try:
            hysteresis_factor(values["restitution"], 1.0, values.get("damping_model", "exact"))
        except ContactLawError as error:
            raise ContactLawError(f"{where}: {error}") from None
    return cls(**values)
