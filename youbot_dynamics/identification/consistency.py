"""Physical consistency of identified parameters: the pseudo-inertia of every body, and a
fit that is consistent by construction.

Each body's ten parameters (m, h = m c, I about the body frame origin) are physically
consistent exactly when its 4x4 pseudo-inertia (Wensing, Kim, Slotine 2017)

    J = [[ Sigma, h ],        Sigma = tr(I)/2 1 - I   (kg m^2),  h (kg m),  m (kg)
         [ h^T,   m ]]

is positive definite; :func:`pseudo_inertia_eigenvalues` gives the smallest eigenvalue of
each. Base parameters do not fix the standard ones: :func:`standard_from_base` picks the
standard vector nearest (Euclidean) a reference that reproduces given base values,
theta = theta_ref + K^+ (beta - K theta_ref), which need not be consistent.

:func:`consistent_fit` finds standard parameters that are consistent by construction. Every
LINK of a body (the joint's child link and the links welded or locked to it: the youBot's
body 5 is arm_link_5, the palm and both fingers) gets its own pseudo-inertia in the
log-Cholesky parametrisation of Rucker and Wensing (2022), relative to its prior's:

    J = U0 V V^T U0^T,   V = e^a [[e^d1, s12, s13, t1],
                                  [0,    e^d2, s23, t2],
                                  [0,    0,    e^d3, t3],
                                  [0,    0,    0,    1 ]],

U0 the upper-triangular factor of the prior J0 = U0 U0^T (:func:`upper_cholesky`), so
U = U0 V is upper triangular with a positive diagonal and J is positive definite for any
real psi = (a, d1, d2, d3, s12, s23, s13, t1, t2, t3); psi = 0 is the prior, and psi is
unit-free (a = 0.1 is a mass 22 % above the prior's). The body's pseudo-inertia is the sum of
its links' moved into the body frame (T J T^T, T the link's homogeneous placement),
positive definite as a sum of positive definite ones, and each link written into a URDF is
consistent on its own. The fit is the least-squares problem

    min 1/2 |R (K theta(psi, f) - beta)|^2 + w/2 sum_links |psi_link|^2,   R^T R = C^-1,

over the links' psi and the friction parameters f (viscous and Coulomb >= 0, offsets free):
least squares on the base parameters (beta, C: the WLS estimate and its covariance, so the
first term is the data's chi^2/2 up to a constant) plus ``w`` times the squared
log-Cholesky distance to the prior URDF's links. The data fix the base parameters; the
regularisation picks, among the standard sets that reproduce them, one near the prior, and
splits each body among its links as the prior does (the data see only the sums). Solved by
scipy's trust-region reflective least squares (exact trust-region solves, the bounds on
friction) with the exact Jacobian: 15 to 30 evaluations on the youBot bags, where
Levenberg-Marquardt crept along a curved valley for thousands.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
import scipy.optimize

from youbot_dynamics.identification.base_parameters import BaseParameters
from youbot_dynamics.identification.regressor import RegressorLayout

#: Weight w of the squared log-Cholesky distance to the prior, against the data's chi^2/2.
#: The node's noisy 10 s youBot bags: the fit moves the base parameters by at most 0.9 to 2.5
#: standard deviations of the estimate (over 13 noise and truth seeds), and by 0.17 for the
#: exact base values of a physical robot. Weight 1e-2 leaves directions the data do not see
#: nearly flat: slow convergence.
PRIOR_WEIGHT = 1.0


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


def parameters_of_pseudo_inertia(pseudo: np.ndarray) -> np.ndarray:
    """The ten parameters of a 4x4 pseudo-inertia (inverse of :func:`pseudo_inertia`):
    m = J_33, h = J_{0:3,3}, I = tr(Sigma) 1 - Sigma."""
    sigma = pseudo[:3, :3]
    inertia = np.trace(sigma) * np.eye(3) - sigma
    return np.array([pseudo[3, 3], *pseudo[:3, 3], inertia[0, 0], inertia[0, 1], inertia[1, 1], inertia[0, 2],
                     inertia[1, 2], inertia[2, 2]])


#: theta (10) = PARAMETER_MAP @ vec(J) (16, row-major): the linear map of
#: :func:`parameters_of_pseudo_inertia`.
PARAMETER_MAP = np.column_stack([parameters_of_pseudo_inertia(e.reshape(4, 4)) for e in np.eye(16)])


def pseudo_inertia_eigenvalues(layout: RegressorLayout, theta: np.ndarray) -> dict[str, float]:
    """Smallest eigenvalue of each body's pseudo-inertia (> 0: consistent), by body name."""
    inertial = theta[:layout.n_inertial].reshape(-1, 10)
    return {body: float(np.linalg.eigvalsh(pseudo_inertia(p))[0]) for body, p in zip(layout.body_names, inertial)}


def standard_from_base(base: BaseParameters, values: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """The standard parameters nearest ``reference`` whose base parameters are ``values``."""
    return reference + np.linalg.pinv(base.matrix) @ (values - base.matrix @ reference)


# ---------------------------------------------------------------------------------------
# Log-Cholesky parametrisation (Rucker and Wensing 2022)
# ---------------------------------------------------------------------------------------
#: Positions in V of (s12, s23, s13, t1, t2, t3), the coordinates after a, d1, d2, d3.
_OFF_DIAGONAL = ((0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3))


def log_cholesky_factor(psi: np.ndarray) -> np.ndarray:
    """V (4x4, upper triangular, positive diagonal, V_33 = e^a) of the coordinates
    psi = (a, d1, d2, d3, s12, s23, s13, t1, t2, t3); psi = 0 gives the identity."""
    factor = np.eye(4)
    factor[np.arange(3), np.arange(3)] = np.exp(psi[1:4])
    for value, (i, j) in zip(psi[4:], _OFF_DIAGONAL):
        factor[i, j] = value
    return np.exp(psi[0]) * factor


def log_cholesky_derivatives(psi: np.ndarray, factor: np.ndarray) -> np.ndarray:
    """dV / dpsi_k (10, 4, 4) at V = log_cholesky_factor(psi)."""
    derivatives = np.zeros((10, 4, 4))
    derivatives[0] = factor
    for i in range(3):
        derivatives[1 + i, i, i] = factor[i, i]
    for k, (i, j) in enumerate(_OFF_DIAGONAL):
        derivatives[4 + k, i, j] = np.exp(psi[0])
    return derivatives


def upper_cholesky(pseudo: np.ndarray) -> np.ndarray:
    """The upper-triangular U with a positive diagonal and U U^T = J (J positive definite):
    the Cholesky factor of J with rows and columns reversed."""
    flip = np.eye(4)[::-1]
    return flip @ np.linalg.cholesky(flip @ pseudo @ flip) @ flip


# ---------------------------------------------------------------------------------------
# The consistent fit
# ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class BodyLink:
    """One link of an identified body: its ``name``, the ``body`` index (layout order),
    ``placement`` (4x4 homogeneous transform of the link frame in the body's joint frame)
    and its prior ``inertia`` (the URDF's, a pin.Inertia in the link frame)."""

    name: str
    body: int
    placement: np.ndarray
    inertia: pin.Inertia

    @property
    def prior(self) -> np.ndarray:
        """The prior pseudo-inertia in the link frame (4x4)."""
        return pseudo_inertia(self.inertia.toDynamicParameters())


@dataclass(frozen=True)
class ConsistentFit:
    """Consistent standard parameters ``theta`` (layout order), each link's fitted
    ``inertias`` (pin.Inertia in the link frame, by link name) and its log-Cholesky
    distance |psi| from the prior (``distance``), the base parameters they give
    (``base_values``) and how far those moved from the estimate in its standard deviations
    (``moved_std``, signed, per base parameter); the smallest pseudo-inertia eigenvalue over
    the links; the weight used; the optimiser's evaluations, ``success`` and ``message``."""

    theta: np.ndarray
    inertias: dict[str, pin.Inertia]
    distance: dict[str, float]
    base_values: np.ndarray
    moved_std: np.ndarray
    smallest_eigenvalue: float
    weight: float
    evaluations: int
    success: bool
    message: str


def inertial_parameters(links: tuple[BodyLink, ...], psi: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """The bodies' inertial parameters (``count`` = 10 per body, layout order) of the links
    at log-Cholesky coordinates ``psi`` (10 per link, relative to each link's prior), and
    their derivative d theta / d psi (count, 10 links)."""
    theta, jacobian = np.zeros(count), np.zeros((count, psi.size))
    for k, link in enumerate(links):
        coordinates = psi[10 * k:10 * k + 10]
        own = log_cholesky_factor(coordinates)
        base_factor = link.placement @ upper_cholesky(link.prior)
        moved = base_factor @ own                       # T U0 V: the body-frame factor
        rows = slice(10 * link.body, 10 * link.body + 10)
        theta[rows] += PARAMETER_MAP @ (moved @ moved.T).ravel()
        for m, derivative in enumerate(log_cholesky_derivatives(coordinates, own)):
            d_moved = base_factor @ derivative
            jacobian[rows, 10 * k + m] = PARAMETER_MAP @ (d_moved @ moved.T + moved @ d_moved.T).ravel()
    return theta, jacobian


def consistent_fit(layout: RegressorLayout, base: BaseParameters, values: np.ndarray, covariance: np.ndarray,
                   links: tuple[BodyLink, ...], weight: float = PRIOR_WEIGHT) -> ConsistentFit:
    """Consistent standard parameters reproducing the base estimate ``values`` (covariance
    ``covariance``) in the least-squares sense, regularised toward the links' priors (see
    the module docstring)."""
    n_links, n_inertial = len(links), layout.n_inertial
    friction_names = layout.names[n_inertial:]
    whitening = np.linalg.cholesky(np.linalg.inv(covariance)).T          # R, R^T R = C^-1
    theta_prior = layout.standard_parameters()
    root_weight = np.sqrt(weight)

    def evaluate(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """theta and d theta / dx."""
        inertial, d_inertial = inertial_parameters(links, x[:10 * n_links], n_inertial)
        jacobian = np.zeros((len(theta_prior), len(x)))
        jacobian[:n_inertial, :10 * n_links] = d_inertial
        jacobian[n_inertial:, 10 * n_links:] = np.eye(len(friction_names))
        return np.concatenate([inertial, x[10 * n_links:]]), jacobian

    def residual(x: np.ndarray) -> np.ndarray:
        theta, _ = evaluate(x)
        return np.concatenate([whitening @ (base.matrix @ theta - values), root_weight * x[:10 * n_links]])

    def residual_jacobian(x: np.ndarray) -> np.ndarray:
        _, jacobian = evaluate(x)
        regularisation = np.zeros((10 * n_links, len(x)))
        regularisation[:, :10 * n_links] = root_weight * np.eye(10 * n_links)
        return np.vstack([whitening @ base.matrix @ jacobian, regularisation])

    x0 = np.concatenate([np.zeros(10 * n_links), theta_prior[n_inertial:]])
    lower = np.array([-np.inf] * (10 * n_links)
                     + [-np.inf if name.endswith(".offset") else 0.0 for name in friction_names])
    x0 = np.maximum(x0, np.where(np.isfinite(lower), 1e-9, -np.inf))     # strictly inside the bounds
    result = scipy.optimize.least_squares(residual, x0, jac=residual_jacobian, bounds=(lower, np.inf), method="trf",
                                          tr_solver="exact", xtol=1e-10, ftol=1e-10, gtol=1e-10, max_nfev=500)
    theta, _ = evaluate(result.x)
    fitted = base.matrix @ theta
    factors = [upper_cholesky(link.prior) @ log_cholesky_factor(result.x[10 * k:10 * k + 10])
               for k, link in enumerate(links)]
    pseudos = [factor @ factor.T for factor in factors]
    return ConsistentFit(
        theta=theta,
        inertias={link.name: pin.Inertia.FromDynamicParameters(parameters_of_pseudo_inertia(p))
                  for link, p in zip(links, pseudos)},
        distance={link.name: float(np.linalg.norm(result.x[10 * k:10 * k + 10])) for k, link in enumerate(links)},
        base_values=fitted, moved_std=(fitted - values) / np.sqrt(np.diag(covariance)),
        smallest_eigenvalue=min(float(np.linalg.eigvalsh(p)[0]) for p in pseudos), weight=weight,
        evaluations=int(result.nfev), success=bool(result.success), message=str(result.message))
