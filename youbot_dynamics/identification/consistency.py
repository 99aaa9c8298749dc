"""Physical consistency of identified parameters: the pseudo-inertia of every body.

Base parameters do not fix the standard ones. :func:`standard_from_base` picks the standard
vector nearest (Euclidean) to a reference (the URDF's) that reproduces given base values:
theta = theta_ref + K^+ (beta - K theta_ref). Each body's ten parameters are physically
consistent exactly when its 4x4 pseudo-inertia (Wensing, Kim, Slotine 2017)

    J = [[ tr(I)/2 1 - I,  h ],
         [ h^T,            m ]],   h = m c (kg m), I about the body frame origin (kg m^2)

is positive definite; :func:`pseudo_inertia_eigenvalues` gives its smallest eigenvalue.
:func:`nearest_consistent` moves the standard parameters, keeping the base values, until
every pseudo-inertia is positive definite (the projection a corrected URDF needs).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.optimize

from youbot_dynamics.identification.base_parameters import BaseParameters
from youbot_dynamics.identification.regressor import RegressorLayout


def pseudo_inertia(parameters: np.ndarray) -> np.ndarray:
    """The 4x4 pseudo-inertia (kg m^2, kg m, kg) of one body's ten parameters in Pinocchio's
    order (m, mc_x, mc_y, mc_z, Ixx, Ixy, Iyy, Ixz, Iyz, Izz)."""
    m, hx, hy, hz, ixx, ixy, iyy, ixz, iyz, izz = parameters
    inertia = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    pseudo = np.zeros((4, 4))
    pseudo[:3, :3] = 0.5 * np.trace(inertia) * np.eye(3) - inertia
    pseudo[:3, 3] = pseudo[3, :3] = (hx, hy, hz)
    pseudo[3, 3] = m
    return pseudo


def pseudo_inertia_eigenvalues(layout: RegressorLayout, theta: np.ndarray) -> dict[str, float]:
    """Smallest eigenvalue of each body's pseudo-inertia (> 0: consistent), by body name."""
    inertial = theta[:layout.n_inertial].reshape(-1, 10)
    return {body: float(np.linalg.eigvalsh(pseudo_inertia(p))[0]) for body, p in zip(layout.body_names, inertial)}


def standard_from_base(base: BaseParameters, values: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """The standard parameters nearest ``reference`` whose base parameters are ``values``."""
    return reference + np.linalg.pinv(base.matrix) @ (values - base.matrix @ reference)


@dataclass(frozen=True)
class Projection:
    """Standard parameters ``theta`` that keep the base values (to ``base_error``) with every
    body's pseudo-inertia eigenvalues >= ``margin``; ``start`` the minimum-norm solution it
    began from, ``moved`` |theta - start| per body (Euclidean over the ten parameters, mixed
    units kg, kg m, kg m^2), ``success`` whether every constraint holds, the optimiser's
    ``message``."""

    theta: np.ndarray
    start: np.ndarray
    moved: dict[str, float]
    base_error: float
    success: bool
    message: str


def nearest_consistent(layout: RegressorLayout, base: BaseParameters, values: np.ndarray, reference: np.ndarray,
                       margin: float = 1e-6, iterations: int = 300) -> Projection:
    """The standard parameters nearest :func:`standard_from_base`'s (in units of the
    reference's magnitudes, max(|reference|, 1e-3) per parameter) that keep the base
    values and make every pseudo-inertia positive definite (all four eigenvalues >=
    ``margin``): SLSQP on the scaled change, K theta = values as linear equalities."""
    start = standard_from_base(base, values, reference)
    bodies = len(layout.body_names)
    scale = np.maximum(np.abs(reference), 1e-3)

    def eigenvalues(theta: np.ndarray) -> np.ndarray:
        inertial = theta[:10 * bodies].reshape(-1, 10)
        return np.concatenate([np.linalg.eigvalsh(pseudo_inertia(p)) for p in inertial]) - margin

    def consistent(theta: np.ndarray) -> bool:
        return bool(np.all(eigenvalues(theta) >= -1e-12) and np.abs(base.matrix @ theta - values).max() < 1e-9)

    if consistent(start):
        theta, message = start, "already consistent"
    else:
        equality = base.matrix * scale
        result = scipy.optimize.minimize(
            lambda y: 0.5 * float(y @ y), np.zeros_like(start), jac=lambda y: y, method="SLSQP",
            constraints=[{"type": "eq", "fun": lambda y: equality @ y, "jac": lambda y: equality},
                         {"type": "ineq", "fun": lambda y: eigenvalues(start + scale * y) / margin}],
            options={"maxiter": iterations, "ftol": 1e-12})
        theta, message = start + scale * result.x, str(result.message)
    change = (theta - start)[:10 * bodies].reshape(-1, 10)
    return Projection(theta, start, {b: float(np.linalg.norm(c)) for b, c in zip(layout.body_names, change)},
                      float(np.abs(base.matrix @ theta - values).max()), consistent(theta), message)
