"""Mechanisms with holonomic constraints g(q) = 0, given as equations, and the ways of
writing them for an integrator.

Equations of motion (n positions q, m constraints, multipliers lambda):

    q' = v,   M(q) v' = f(q, v) - G(q)^T lambda,   0 = g(q),   G = dg/dq.

Formulations (names as on the command line):

- ``index3``: the DAE above for IDA, y = (q, v, w, lambda) with w = v' (the test set's
  form); w and lambda are algebraic.
- ``index2``: 0 = G v instead of 0 = g (velocity level); w and lambda algebraic.
- ``ggl``: stabilised index 2 (Gear, Gupta and Leimkuhler 1985): q' = v - G^T mu with both
  0 = g and 0 = G v; y = (q, v, w, lambda, mu).
- ``index1``: the acceleration level as an ODE x = (q, v), x' = (v, w) with
  [M G^T; G 0][w; lambda] = [f; -g_qq(v, v)], g_qq(v, v) = (d/dt G) v; drifts off g = 0.
- ``index1-baumgarte``: the acceleration constraint replaced by
  G w + g_qq(v, v) + 2 alpha G v + beta^2 g = 0, so that the drift e = g obeys
  e'' + 2 alpha e' + beta^2 e = 0 (rates in 1/s).
- ``index1-projection``: index 1, and at every output time the state is projected back
  onto g = 0 and G v = 0 (:func:`project_positions`, :func:`project_velocities`) and the
  integrator restarted from there.

Error test. Higher-index variables must be kept out of IDA's local error test: lambda,
w (and mu) for index 2 and GGL, and also v for index 3 (Hairer's choice; document 001's
Assimulo run excluded only w and lambda, but then IDA's first step, sized from
|y0'| = |w0| ~ 1.4e4 in v's weights, collapses at t = 0). Radau IIA (integrate/radau_dae.py,
``radau5``) realises the exclusion as Hairer does, by index-dependent weights. On IDA,
whose suppress-alg (integrate/sundials.py) still fails the squeezer's index 3 at t = 0 in its
Newton test (``squeezer --table``), :attr:`DaeForm.excluded` is realised by an absolute
tolerance of EXCLUDED_ATOL on those components (:func:`dae_tolerances`): that takes them
out of the Newton convergence test as well, so their values are only as good as the converged q and v
make them (the tests measure q against the reference and lambda against index 1). For
index 3 it also leaves the tangential velocity without error control: on the squeezer
q's error is 1e2 to 1e4 times rtol and not monotone in it, and below rtol ~ 1e-9 IDA's
error test or corrector fails at steps of 1e-11 s and less.

Jacobian. :func:`dae_jacobian` is the exact iteration matrix dF/dy + cj dF/dy' of the DAE
forms, from the system's optional second derivatives (d(M w)/dq, df/dq, df/dv and the
constraint Hessians); without them IDA differences the residual.

This module holds the formulas only (nothing here integrates); the driver that runs them
with youbot_dynamics.integrate.integrators is sim.constrained.simulate_holonomic.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from youbot_dynamics.errors import UserInputError

FORMULATIONS: tuple[str, ...] = ("index1", "index1-baumgarte", "index1-projection",
                                 "index2", "ggl", "index3")
#: Formulations solved as DAEs by IDA (the rest are ODEs for any ODE integrator).
DAE_FORMULATIONS: tuple[str, ...] = ("index2", "ggl", "index3")

Vector = np.ndarray


@dataclass(frozen=True)
class HolonomicSystem:
    """A mechanism with n generalised positions and m holonomic constraints, SI units.

    mass(q) -> M (n, n); forces(q, v) -> f (n,) (applied plus Coriolis/centrifugal forces,
    time-invariant); constraint(q) -> g (m,); jacobian(q) -> G = dg/dq (m, n);
    curvature(q, v) -> g_qq(v, v) = (dG/dt) v (m,), so that d^2 g/dt^2 = G v' + g_qq(v, v).

    Optional second derivatives, for the exact Jacobian of the DAE forms (IDA builds one
    by finite differences without them): mass_derivative(q, w) -> d(M(q) w)/dq (n, n);
    force_derivatives(q, v) -> (df/dq, df/dv), each (n, n); constraint_hessian(q) ->
    d^2 g_i / dq_j dq_k (m, n, n).
    """

    name: str
    position_names: tuple[str, ...]
    n_constraints: int
    mass: Callable[[Vector], np.ndarray]
    forces: Callable[[Vector, Vector], Vector]
    constraint: Callable[[Vector], Vector]
    jacobian: Callable[[Vector], np.ndarray]
    curvature: Callable[[Vector, Vector], Vector]
    mass_derivative: Callable[[Vector, Vector], np.ndarray] | None = None
    force_derivatives: Callable[[Vector, Vector], tuple[np.ndarray, np.ndarray]] | None = None
    constraint_hessian: Callable[[Vector], np.ndarray] | None = None

    @property
    def n_positions(self) -> int:
        """n, the number of generalised positions."""
        return len(self.position_names)

    @property
    def has_second_derivatives(self) -> bool:
        """Whether the exact DAE Jacobian can be formed (all three derivatives given)."""
        return None not in (self.mass_derivative, self.force_derivatives,
                            self.constraint_hessian)


def saddle_point_solve(mass: np.ndarray, jacobian: np.ndarray, top: Vector,
                       bottom: Vector) -> tuple[Vector, Vector]:
    """Solve [M G^T; G 0][x; mu] = [top; bottom]; returns (x, mu)."""
    n, m = mass.shape[0], jacobian.shape[0]
    matrix = np.empty((n + m, n + m))
    matrix[:n, :n] = mass
    matrix[:n, n:] = jacobian.T
    matrix[n:, :n] = jacobian
    matrix[n:, n:] = 0.0
    solution = np.linalg.solve(matrix, np.concatenate((top, bottom)))
    return solution[:n], solution[n:]


def accelerations_and_multipliers(system: HolonomicSystem, q: Vector, v: Vector,
                                  alpha: float = 0.0, beta: float = 0.0
                                  ) -> tuple[Vector, Vector]:
    """The index-1 system: w = v' and lambda from [M G^T; G 0][w; lambda] =
    [f; -g_qq(v, v) - 2 alpha G v - beta^2 g] (Baumgarte rates alpha, beta in 1/s; zero
    for the plain acceleration constraint)."""
    jacobian = system.jacobian(q)
    bottom = -system.curvature(q, v)
    if alpha:
        bottom -= 2.0 * alpha * (jacobian @ v)
    if beta:
        bottom -= beta * beta * system.constraint(q)
    return saddle_point_solve(system.mass(q), jacobian, system.forces(q, v), bottom)


def index1_rhs(system: HolonomicSystem, alpha: float = 0.0, beta: float = 0.0
               ) -> Callable[[float, Vector], Vector]:
    """x' for x = (q, v): (v, w) with w from :func:`accelerations_and_multipliers`."""
    n = system.n_positions

    def rhs(t: float, x: Vector) -> Vector:
        q, v = x[:n], x[n:]
        w, _ = accelerations_and_multipliers(system, q, v, alpha, beta)
        return np.concatenate((v, w))

    return rhs


@dataclass(frozen=True)
class DaeForm:
    """A DAE formulation for IDA: residual(t, y, y'), its exact iteration matrix
    residual_jacobian(t, y, y', cj) = dF/dy + cj dF/dy' (None when the system lacks the
    second derivatives), consistent (y0, y0'), which components are algebraic and which
    are left out of the error test, their names, and the slices of q, v, lambda in y."""

    name: str
    residual: Callable[[float, Vector, Vector], Vector]
    residual_jacobian: Callable[[float, Vector, Vector, float], np.ndarray] | None
    y0: Vector
    yp0: Vector
    algebraic: np.ndarray
    excluded: np.ndarray
    state_names: tuple[str, ...]
    n: int
    m: int

    def positions(self, y: np.ndarray) -> np.ndarray:
        """q from y (or a time series of y along axis 0), a view."""
        return y[..., :self.n]

    def velocities(self, y: np.ndarray) -> np.ndarray:
        """v from y, a view."""
        return y[..., self.n:2 * self.n]

    def multipliers(self, y: np.ndarray) -> np.ndarray:
        """lambda from y (M v' = f - G^T lambda), a view."""
        return y[..., 3 * self.n:3 * self.n + self.m]


def dae_form(system: HolonomicSystem, formulation: str, q0: Vector, v0: Vector,
             w0: Vector, lambda0: Vector) -> DaeForm:
    """The ``index3``, ``index2`` or ``ggl`` DAE for IDA from consistent initial values.

    y = (q, v, w, lambda[, mu]); residual blocks q' - v [+ G^T mu], v' - w,
    M w - f + G^T lambda, then g (index 3), G v (index 2) or both (GGL). w, lambda and mu
    are algebraic and, with v for index 3, marked for exclusion from the error test.
    The exact Jacobian is :func:`dae_jacobian` when the system has second derivatives.
    """
    n, m = system.n_positions, system.n_constraints
    ggl = formulation == "ggl"
    if formulation not in DAE_FORMULATIONS:
        raise UserInputError(f"formulation {formulation!r} is not a DAE formulation; "
                             f"valid: {', '.join(DAE_FORMULATIONS)}")

    def residual(t: float, y: Vector, yp: Vector) -> Vector:
        q, v, w, lam = y[:n], y[n:2 * n], y[2 * n:3 * n], y[3 * n:3 * n + m]
        jacobian = system.jacobian(q)
        kinematic = yp[:n] - v
        if ggl:
            kinematic = kinematic + jacobian.T @ y[3 * n + m:]
        dynamic = system.mass(q) @ w - system.forces(q, v) + jacobian.T @ lam
        if formulation == "index3":
            constraints = (system.constraint(q),)
        elif formulation == "index2":
            constraints = (jacobian @ v,)
        else:
            constraints = (system.constraint(q), jacobian @ v)
        return np.concatenate((kinematic, yp[n:2 * n] - w, dynamic, *constraints))

    size = 3 * n + m * (2 if ggl else 1)
    y0 = np.zeros(size)
    y0[:3 * n + m] = np.concatenate((q0, v0, w0, lambda0))
    yp0 = np.zeros(size)
    yp0[:2 * n] = np.concatenate((v0, w0))
    algebraic = np.arange(size) >= 2 * n
    names = (tuple(system.position_names)
             + tuple(f"v_{name}" for name in system.position_names)
             + tuple(f"w_{name}" for name in system.position_names)
             + tuple(f"lambda{i + 1}" for i in range(m))
             + (tuple(f"mu{i + 1}" for i in range(m)) if ggl else ()))
    excluded = algebraic | ((np.arange(size) >= n) if formulation == "index3" else False)
    jacobian = (dae_jacobian(system, formulation) if system.has_second_derivatives
                else None)
    return DaeForm(formulation, residual, jacobian, y0, yp0, algebraic, excluded, names,
                   n, m)


def dae_jacobian(system: HolonomicSystem, formulation: str
                 ) -> Callable[[float, Vector, Vector, float], np.ndarray]:
    """dF/dy + cj dF/dy' of :func:`dae_form`'s residual, from the system's second
    derivatives. With H = d^2 g/dq^2: d(G^T lambda)/dq = lambda . H, d(G v)/dq = H . v;
    the kinematic and v' - w rows give cj I on their own derivatives, -I on v and w."""
    n, m = system.n_positions, system.n_constraints
    ggl = formulation == "ggl"
    position_rows = formulation in ("index3", "ggl")
    velocity_rows = formulation in ("index2", "ggl")
    size = 3 * n + m * (2 if ggl else 1)
    identity = np.eye(n)
    qs, vs, ws = (slice(k * n, (k + 1) * n) for k in range(3))
    ls = slice(3 * n, 3 * n + m)

    def jacobian(t: float, y: Vector, yp: Vector, cj: float) -> np.ndarray:
        q, v, w, lam = y[qs], y[vs], y[ws], y[ls]
        constraint_jacobian = system.jacobian(q)
        hessian = system.constraint_hessian(q)
        force_q, force_v = system.force_derivatives(q, v)
        matrix = np.zeros((size, size))
        matrix[qs, qs] = cj * identity
        matrix[qs, vs] = -identity
        if ggl:
            mu = y[3 * n + m:]
            matrix[qs, qs] += np.einsum("i,ijk->jk", mu, hessian)
            matrix[qs, 3 * n + m:] = constraint_jacobian.T
        matrix[vs, vs] = cj * identity
        matrix[vs, ws] = -identity
        matrix[ws, qs] = (system.mass_derivative(q, w) - force_q
                          + np.einsum("i,ijk->jk", lam, hessian))
        matrix[ws, vs] = -force_v
        matrix[ws, ws] = system.mass(q)
        matrix[ws, ls] = constraint_jacobian.T
        row = 3 * n
        if position_rows:
            matrix[row:row + m, qs] = constraint_jacobian
            row += m
        if velocity_rows:
            matrix[row:row + m, qs] = np.einsum("ijk,j->ik", hessian, v)
            matrix[row:row + m, vs] = constraint_jacobian
        return matrix

    return jacobian


#: Absolute tolerance standing in for "excluded from the error test" (see module notes).
EXCLUDED_ATOL = 1e6


def dae_tolerances(form: DaeForm, atol: float) -> np.ndarray:
    """Per-component absolute tolerances for IDA: atol, and EXCLUDED_ATOL on the
    components the formulation excludes from the error test."""
    return np.where(form.excluded, EXCLUDED_ATOL, atol)


def project_positions(system: HolonomicSystem, q: Vector, tolerance: float = 1e-12,
                      max_iterations: int = 20) -> tuple[Vector, int]:
    """A point of g = 0 near q: Gauss-Newton steps dq = -M^-1 G^T (G M^-1 G^T)^-1 g, each
    the least M-norm correction for the linearised constraint (solved as one saddle-point
    system, M and G taken at the current iterate), until max|g| <= tolerance. The result
    is the M-nearest point to first order in the distance. Returns (q, iterations)."""
    q = np.array(q, dtype=float)
    for iteration in range(max_iterations + 1):
        residual = system.constraint(q)
        if np.max(np.abs(residual)) <= tolerance:
            return q, iteration
        if iteration == max_iterations:
            break
        step, _ = saddle_point_solve(system.mass(q), system.jacobian(q),
                                     np.zeros_like(q), -residual)
        q += step
    raise UserInputError(f"{system.name}: position projection did not reach max|g| <= "
                         f"{tolerance:g} in {max_iterations} Gauss-Newton steps "
                         f"(max|g| = {np.max(np.abs(residual)):.3g})")


def project_velocities(system: HolonomicSystem, q: Vector, v: Vector) -> Vector:
    """The v of G(q) v = 0 nearest to v in the metric of M(q) (one linear solve)."""
    jacobian = system.jacobian(q)
    step, _ = saddle_point_solve(system.mass(q), jacobian, np.zeros_like(v), -(jacobian @ v))
    return v + step


def consistent_initial_values(system: HolonomicSystem, q_guess: Vector, v_guess: Vector,
                              fixed: Sequence[int], tolerance: float = 1e-13,
                              max_iterations: int = 30
                              ) -> tuple[Vector, Vector, Vector, Vector, int]:
    """Consistent (q, v, w, lambda) from a guess, holding the positions and velocities
    listed in ``fixed`` (0-based indices) at their guessed values.

    Position level: Newton on g(q) = 0 in the free positions (the least-squares step
    with numpy.linalg.lstsq, which is Newton's when as many free positions as constraints
    remain) until max|g| <= tolerance. Velocity level: G v = 0 solved for the free
    velocities. Acceleration level: w and lambda from the index-1 saddle-point system.
    Returns (q, v, w, lambda, Newton iterations).
    """
    n = system.n_positions
    fixed_set = set(int(i) for i in fixed)
    if any(not 0 <= i < n for i in fixed_set):
        raise UserInputError(f"{system.name}: fixed coordinate indices {sorted(fixed_set)} "
                             f"must lie in 0..{n - 1}")
    free = np.array([i for i in range(n) if i not in fixed_set])
    if free.size < system.n_constraints:
        raise UserInputError(f"{system.name}: {free.size} free coordinates cannot satisfy "
                             f"{system.n_constraints} constraints; fix fewer of them")
    q = np.array(q_guess, dtype=float)
    for iteration in range(max_iterations + 1):
        residual = system.constraint(q)
        if np.max(np.abs(residual)) <= tolerance:
            break
        if iteration == max_iterations:
            raise UserInputError(f"{system.name}: Newton on g(q) = 0 did not converge from "
                                 f"the guess in {max_iterations} iterations (max|g| = "
                                 f"{np.max(np.abs(residual)):.3g}); give a closer guess")
        q[free] -= np.linalg.lstsq(system.jacobian(q)[:, free], residual, rcond=None)[0]
    v = np.array(v_guess, dtype=float)
    jacobian = system.jacobian(q)
    held = np.array(sorted(fixed_set), dtype=int)
    v[free] = np.linalg.lstsq(jacobian[:, free], -(jacobian[:, held] @ v[held]),
                              rcond=None)[0]
    w, lam = accelerations_and_multipliers(system, q, v)
    return q, v, w, lam, iteration
