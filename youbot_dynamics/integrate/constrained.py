"""Running a mechanism with holonomic constraints (dynamics.constraints.HolonomicSystem)
in any of its formulations with the project's integrators.

DAE formulations (``index2``, ``ggl``, ``index3``) go to integrate_dae (IDA) with the
exact iteration matrix when the system has second derivatives (else IDA's finite
differences) and the error-test exclusions of dynamics.constraints.dae_tolerances, or to
sim.radau_dae (``radau5``) with Hairer's index-dependent error scaling; the index-1
formulations go to integrate with any ODE integrator.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from youbot_dynamics.dynamics.constraints import (DAE_FORMULATIONS, FORMULATIONS, HolonomicSystem,
                                                  accelerations_and_multipliers, dae_form,
                                                  dae_tolerances, index1_rhs, project_positions,
                                                  project_velocities)
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import IntegratorStats, integrate, integrate_dae
from youbot_dynamics.integrate.radau_dae import integrate_dae_form
from youbot_dynamics.integrate.registry import INTEGRATORS

#: Integrators for the DAE formulations: IDA, and Radau IIA with index scaling.
DAE_INTEGRATORS: tuple[str, ...] = ("ida", "radau5")

__all__ = ["ConstrainedRun", "DAE_INTEGRATORS", "checked_choice", "simulate_holonomic"]


@dataclass
class ConstrainedRun:
    """A run of a HolonomicSystem: outputs t (s), q, v, lambda, the residuals g(q) and
    G v at every output, the integrator statistics, and for ``index1-projection`` the
    number of projections and of Gauss-Newton iterations they took."""

    formulation: str
    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    multipliers: np.ndarray
    position_residual: np.ndarray
    velocity_residual: np.ndarray
    stats: IntegratorStats
    projection: dict = field(default_factory=dict)

    def as_dict(self) -> dict:
        """The end state, residuals and statistics as plain data."""
        return {"formulation": self.formulation, "t_end": float(self.t[-1]),
                "q": self.q[-1].tolist(), "v": self.v[-1].tolist(),
                "lambda": self.multipliers[-1].tolist(),
                "g": self.position_residual[-1].tolist(),
                "Gv": self.velocity_residual[-1].tolist(),
                "stats": self.stats.as_dict(), "projection": self.projection}


def checked_choice(system: HolonomicSystem, formulation: str, integrator: str) -> None:
    """Formulation and integrator must exist and fit (DAE forms need ida or radau5, ODE
    forms an ODE integrator)."""
    if formulation not in FORMULATIONS:
        raise UserInputError(f"unknown formulation {formulation!r}; valid: "
                             + ", ".join(FORMULATIONS))
    if integrator not in INTEGRATORS + DAE_INTEGRATORS:
        raise UserInputError(f"unknown integrator {integrator!r}; valid: "
                             + ", ".join(INTEGRATORS + DAE_INTEGRATORS[1:]))
    if (formulation in DAE_FORMULATIONS) != (integrator in DAE_INTEGRATORS):
        need = ("ida or radau5" if formulation in DAE_FORMULATIONS
                else "an ODE integrator (not ida or radau5)")
        raise UserInputError(f"{system.name}: formulation {formulation!r} needs {need}, "
                             f"got integrator {integrator!r}")


def simulate_holonomic(system: HolonomicSystem, formulation: str, integrator: str,
                       q0: np.ndarray, v0: np.ndarray, t_eval: np.ndarray, *,
                       rtol: float = 1e-6, atol: float = 1e-10, dt: float | None = None,
                       baumgarte_rate: float = 0.0, exact_jacobian: bool | None = None,
                       ida_options: Mapping[str, Any] | None = None) -> ConstrainedRun:
    """Run ``system`` from consistent (q0, v0) with outputs at t_eval (s).

    DAE formulations go to integrate_dae (IDA), with ``exact_jacobian`` (default: when
    the system has second derivatives) the analytic iteration matrix
    dynamics.constraints.dae_jacobian, else IDA's finite differences, and with
    ``ida_options`` passed as they are; index-1 ones go to integrate. For
    ``index1-projection`` each interval between outputs is a separate run and the state at
    its end is projected onto g = 0 and then G v = 0 (M-weighted Gauss-Newton, see
    dynamics.constraints) before the next; their statistics are summed. lambda at the
    outputs comes from the index-1 saddle-point system for ODE formulations.
    """
    checked_choice(system, formulation, integrator)
    n = system.n_positions
    t_eval = np.asarray(t_eval, dtype=float)
    w0, lambda0 = accelerations_and_multipliers(system, q0, v0)
    projection: dict = {}
    if formulation in DAE_FORMULATIONS:
        form = dae_form(system, formulation, q0, v0, w0, lambda0)
        if exact_jacobian and form.residual_jacobian is None:
            raise UserInputError(f"{system.name}: an exact DAE Jacobian needs "
                                 "mass_derivative, force_derivatives and constraint_hessian")
        use_exact = form.residual_jacobian is not None and exact_jacobian is not False
        if integrator == "radau5":
            solution, _ = integrate_dae_form(form, t_eval, rtol=rtol, atol=atol,
                                             exact_jacobian=use_exact)
        else:
            solution = integrate_dae(form.residual, form.y0, form.yp0, t_eval,
                                     algebraic=form.algebraic, rtol=rtol,
                                     atol=dae_tolerances(form, atol),
                                     state_names=form.state_names,
                                     jac=form.residual_jacobian if use_exact else None,
                                     ida_options=ida_options)
        q, v = form.positions(solution.x), form.velocities(solution.x)
        multipliers, stats = form.multipliers(solution.x), solution.stats
        t = solution.t
    else:
        rate = baumgarte_rate if formulation == "index1-baumgarte" else 0.0
        rhs = index1_rhs(system, rate, rate)
        names = (tuple(system.position_names)
                 + tuple(f"v_{name}" for name in system.position_names))
        options = dict(rtol=rtol, atol=atol, dt=dt, state_names=names, n_positions=n)
        if formulation == "index1-projection":
            states, stats = [np.concatenate((q0, v0))], IntegratorStats(integrator)
            iterations = 0
            for t_a, t_b in zip(t_eval[:-1], t_eval[1:]):
                segment = integrate(rhs, states[-1], [t_a, t_b], integrator, **options)
                stats += segment.stats
                q_end, used = project_positions(system, segment.x[-1, :n])
                iterations += used
                states.append(np.concatenate(
                    (q_end, project_velocities(system, q_end, segment.x[-1, n:]))))
            x, t = np.asarray(states), t_eval
            projection = {"projections": len(t_eval) - 1, "gauss_newton_iterations": iterations}
        else:
            solution = integrate(rhs, np.concatenate((q0, v0)), t_eval, integrator, **options)
            x, t, stats = solution.x, solution.t, solution.stats
        q, v = x[:, :n], x[:, n:]
        multipliers = np.array([accelerations_and_multipliers(system, qi, vi, rate, rate)[1]
                                for qi, vi in zip(q, v)])
    position_residual = np.array([system.constraint(qi) for qi in q])
    velocity_residual = np.array([system.jacobian(qi) @ vi for qi, vi in zip(q, v)])
    return ConstrainedRun(formulation, t, q, v, multipliers, position_residual,
                          velocity_residual, stats, projection)
