"""Fixed-step BDF1-6 written out (document 001 sections 1.6-1.9), and their stability regions.

The k-step backward differentiation formula on x' = f(t, x) with step h:

    sum_{j=0..k} a_j x_{n+1-j} = h b f(t_{n+1}, x_{n+1}),   a_0 = 1,

is implicit in x_{n+1}; each step solves G(y) = y - h b f(t_{n+1}, y) - psi = 0 (psi =
-sum_{j>=1} a_j x_{n+1-j}) by Newton's method from the polynomial extrapolation of the
previous points, with the matrix I - h b df/dx,
df/dx analytic when given, else by forward differences, refreshed every JACOBIAN_REFRESH
iterations and inverted (the systems here are small; document 001 used scipy's fsolve). The
first k - 1 steps are classic RK4 steps (integrate/fixed_step.py), accurate enough not to
spoil order k, or with ``start="bdf"`` steps of BDF1, BDF2, ... BDF(k-1) (the usual
classroom start, and likely document 001's: its listings 2 and 3 are not in the text). The
start changes only the first few steps' errors, never the roots that decide stability.

Stability on x' = lambda x, z = h lambda: the characteristic polynomial
rho(zeta) - z sigma(zeta), rho(zeta) = sum_j a_j zeta^(k-j), sigma(zeta) = b zeta^k, must
have every root in the closed unit disc. Its boundary lies on the root locus
z(theta) = rho(e^{i theta}) / sigma(e^{i theta}), theta in [0, 2 pi).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.fixed_step import rk4_step
from youbot_dynamics.integrate.integrators import DivergenceError, IntegratorStats

#: order k -> (a_0..a_k, b): sum_j a_j x_{n+1-j} = h b f_{n+1}.
BDF_COEFFICIENTS = {
    1: ((1.0, -1.0), 1.0),
    2: ((1.0, -4.0 / 3.0, 1.0 / 3.0), 2.0 / 3.0),
    3: ((1.0, -18.0 / 11.0, 9.0 / 11.0, -2.0 / 11.0), 6.0 / 11.0),
    4: ((1.0, -48.0 / 25.0, 36.0 / 25.0, -16.0 / 25.0, 3.0 / 25.0), 12.0 / 25.0),
    5: ((1.0, -300.0 / 137.0, 300.0 / 137.0, -200.0 / 137.0, 75.0 / 137.0, -12.0 / 137.0),
        60.0 / 137.0),
    6: ((1.0, -360.0 / 147.0, 450.0 / 147.0, -400.0 / 147.0, 225.0 / 147.0, -72.0 / 147.0,
         10.0 / 147.0), 60.0 / 147.0),
}
#: Starting procedures of :func:`bdf_fixed_step`.
STARTS = ("rk4", "bdf")
#: Newton stops when the update's max-norm is below NEWTON_TOL (1 + |x|_max).
NEWTON_TOL = 1e-12
NEWTON_MAX_ITERATIONS = 20
#: The Newton matrix is re-evaluated and factored every JACOBIAN_REFRESH iterations
#: (simplified Newton in between; quadratic convergence is not needed at these steps).
JACOBIAN_REFRESH = 4
#: Forward-difference step for the Jacobian when none is given: sqrt(eps) (1 + |x_i|).
FD_STEP = 1.5e-8


def coefficients(order: int) -> tuple[np.ndarray, float]:
    """(a, b) of BDF``order`` as in BDF_COEFFICIENTS; UserInputError for other orders."""
    if order not in BDF_COEFFICIENTS:
        raise UserInputError(f"BDF order must be one of {sorted(BDF_COEFFICIENTS)}, got {order!r}")
    a, b = BDF_COEFFICIENTS[order]
    return np.array(a), b


def forward_difference_jacobian(rhs: Callable, t: float, x: np.ndarray,
                                f0: np.ndarray) -> np.ndarray:
    """df/dx by forward differences, one column per component (n extra f evaluations)."""
    jacobian = np.empty((x.size, x.size))
    for i in range(x.size):
        step = FD_STEP * (1.0 + abs(x[i]))
        shifted = x.copy()
        shifted[i] += step
        jacobian[:, i] = (rhs(t, shifted) - f0) / step
    return jacobian


@dataclass
class FixedBdfSolution:
    """x at every step (t (N+1,), x (N+1, n)) and the run's statistics."""

    t: np.ndarray
    x: np.ndarray
    stats: IntegratorStats


def bdf_fixed_step(rhs: Callable[[float, np.ndarray], np.ndarray], x0, t_end: float,
                   n_steps: int, order: int, *,
                   jac: Callable[[float, np.ndarray], np.ndarray] | None = None,
                   bound: float = np.inf, start: str = "rk4") -> FixedBdfSolution:
    """N steps of BDF``order`` with h = t_end / N from x0 at t = 0 (s); the first
    order - 1 steps by RK4 (``start="rk4"``) or by BDF of rising order (``"bdf"``).

    A step whose Newton iteration fails to converge within
    NEWTON_MAX_ITERATIONS, or a state beyond ``bound`` (max-norm) or non-finite, is a
    DivergenceError naming the time and step.
    """
    coefficients(order)
    if n_steps < order or not t_end > 0:
        raise UserInputError(f"BDF{order} needs t_end > 0 and at least {order} steps, got "
                             f"t_end={t_end!r}, N={n_steps!r}")
    if start not in STARTS:
        raise UserInputError(f"start must be one of {STARTS}, got {start!r}")
    began = time.perf_counter()
    name = f"bdf{order}_fixed"
    h = t_end / n_steps
    stats = IntegratorStats(name, nonlinear_convergence_failures=0)
    x = np.empty((n_steps + 1, np.size(x0)))
    x[0] = np.asarray(x0, dtype=float)
    t = h * np.arange(n_steps + 1)
    counted = _counted(rhs, stats)
    for n in range(n_steps):
        if n < order - 1 and start == "rk4":
            x[n + 1] = rk4_step(counted, t[n], x[n], h, 0)
            continue
        y = bdf_step(counted, jac, x, t, h, n, min(order, n + 1), stats, name)
        if not np.all(np.isfinite(y)) or np.max(np.abs(y)) > bound:
            raise DivergenceError(float(t[n + 1]), name, h, f"|x| beyond {bound:g}",
                                  {f"x{i}": float(v) for i, v in enumerate(y)})
        x[n + 1] = y
    stats.steps = n_steps
    stats.rejected_steps = 0
    stats.simulated_time = t_end
    stats.wall_time = time.perf_counter() - began
    return FixedBdfSolution(t, x, stats)


def bdf_step(rhs: Callable, jac: Callable | None, x: np.ndarray, t: np.ndarray, h: float,
             n: int, order: int, stats: IntegratorStats, name: str) -> np.ndarray:
    """x_{n+1} of one BDF``order`` step of size h from x[n], x[n-1], ... (simplified
    Newton, see the module's docstring); DivergenceError if Newton does not converge."""
    a, b = coefficients(order)
    psi = -sum(a[j] * x[n + 1 - j] for j in range(1, order + 1))
    y, t_new = extrapolated(x, n, order), t[n + 1]
    identity = np.eye(x.shape[1])
    for iteration in range(NEWTON_MAX_ITERATIONS):
        f = rhs(t_new, y)
        if iteration % JACOBIAN_REFRESH == 0:
            df = jac(t_new, y) if jac is not None else forward_difference_jacobian(
                rhs, t_new, y, f)
            stats.jac_evals += 1
            newton_inverse = np.linalg.inv(identity - h * b * df)
        update = newton_inverse @ (psi + h * b * f - y)
        y += update
        stats.nonlinear_iterations += 1
        if np.max(np.abs(update)) <= NEWTON_TOL * (1.0 + np.max(np.abs(y))):
            return y
    stats.nonlinear_convergence_failures += 1
    raise DivergenceError(float(t_new), name, h, f"Newton did not converge in "
                          f"{NEWTON_MAX_ITERATIONS} iterations")


def extrapolated(x: np.ndarray, n: int, order: int) -> np.ndarray:
    """Newton's starting guess for x_{n+1}: the polynomial through x_n .. x_{n-order}
    extrapolated one step, sum_j (-1)^j C(order+1, j+1) x_{n-j} (x_n itself while fewer
    points exist)."""
    if n < order:
        return x[n].copy()
    return sum((-1) ** j * math.comb(order + 1, j + 1) * x[n - j] for j in range(order + 1))


def _counted(rhs: Callable, stats: IntegratorStats) -> Callable:
    """rhs that counts its evaluations in stats.rhs_evals."""
    def counted(t: float, x: np.ndarray) -> np.ndarray:
        stats.rhs_evals += 1
        return rhs(t, x)
    return counted


def root_locus(order: int, theta: np.ndarray) -> np.ndarray:
    """z(theta) = rho(e^{i theta}) / sigma(e^{i theta}): the stability boundary's locus."""
    a, b = coefficients(order)
    zeta = np.exp(1j * np.asarray(theta, dtype=float))
    return np.polyval(a, zeta) / (b * zeta ** order)


def amplification(order: int, z: complex) -> float:
    """max |zeta| over the roots of rho(zeta) - z sigma(zeta): > 1 means unstable at z."""
    a, b = coefficients(order)
    polynomial = a.astype(complex)
    polynomial[0] -= z * b
    return float(np.max(np.abs(np.roots(polynomial))))


def locus_radius_on_ray(order: int, angle: float, samples: int = 200_001) -> float:
    """|z| of the root locus's nearest crossing of the ray arg z = angle (rad) from the
    origin (theta in (0, 2 pi), sampled; crossings interpolated linearly)."""
    theta = np.linspace(1e-6, 2.0 * np.pi - 1e-6, samples)
    z = root_locus(order, theta) * np.exp(-1j * angle)  # rotate the ray onto the +real axis
    crossings = np.flatnonzero((np.sign(z.imag[:-1]) != np.sign(z.imag[1:]))
                               & (z.real[:-1] > 0))
    if crossings.size == 0:
        raise ValueError(f"BDF{order}: the root locus does not cross the ray at "
                         f"{np.degrees(angle):g} deg")
    radii = []
    for i in crossings:  # linear interpolation of the crossing
        w = z.imag[i] / (z.imag[i] - z.imag[i + 1])
        radii.append(abs(z[i] + w * (z[i + 1] - z[i])))
    return float(min(radii))


def alpha_angle(order: int, samples: int = 200_001) -> float:
    """A(alpha) angle (rad): the largest sector |arg(-z)| < alpha inside the stability
    region, from the locus points in the left half-plane (pi/2 if there are none)."""
    z = root_locus(order, np.linspace(1e-6, np.pi, samples))
    left = z[z.real < 0]
    if left.size == 0:
        return np.pi / 2
    return float(np.min(np.abs(np.angle(-left))))


def measured_growth(order: int, z: complex, n_steps: int = 400) -> float:
    """Per-step growth factor of the written-out solver on x' = lambda x with h lambda =
    z (as the real 2 x 2 system of Re, Im), from max|x_N| / max|x_{N/2}| (an overflow is
    inf, a decay below the smallest double 0): > 1 means unstable."""
    rotation = np.array([[z.real, -z.imag], [z.imag, z.real]])
    with np.errstate(over="ignore", invalid="ignore", under="ignore"):
        solution = bdf_fixed_step(lambda t, x: rotation @ x, [1.0, 0.3], float(n_steps),
                                  n_steps, order, jac=lambda t, x: rotation)
    half = n_steps // 2
    end, middle = (float(np.max(np.abs(solution.x[i]))) for i in (-1, half))
    if not (np.isfinite(end) and np.isfinite(middle)):
        return np.inf
    if middle == 0.0:  # decayed below the smallest double
        return 0.0
    return (end / middle) ** (1.0 / (n_steps - half))


def measured_boundary_radius(order: int, angle: float, r_low: float = 1e-3,
                             r_high: float = 20.0, iterations: int = 30) -> float:
    """|z| along the ray arg z = angle where the solver's measured growth falls through 1
    (bisection between r_low, unstable, and r_high, stable)."""
    direction = np.exp(1j * angle)
    for _ in range(iterations):
        middle = 0.5 * (r_low + r_high)
        if measured_growth(order, middle * direction) > 1.0:
            r_low = middle
        else:
            r_high = middle
    return 0.5 * (r_low + r_high)
