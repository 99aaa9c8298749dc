"""Integrators behind one interface, each run returning its statistics.

The names, their kinds and their stepper factories are the table in integrate/registry.py:
``euler``, ``symplectic_euler``, ``rk4`` (fixed step, hand-written loops, integrate/fixed_step.py);
``rk45`` (Dormand-Prince 5(4)), ``dop853``, ``radau``, ``bdf``, ``lsoda`` (scipy.integrate,
integrate/adaptive.py); ``dop853_compiled`` (scipy's DOP853 in compiled code for a right-hand
side with a compiled loop, integrate/dop853.py; scipy's own elsewhere); ``cvode_bdf``, ``cvode_adams`` and ``ida`` (SUNDIALS through
scikit-sundae, integrate/sundials.py).

:func:`integrate` solves x' = rhs(t, x); :func:`integrate_dae` solves F(t, y, y') = 0 with
IDA. Both return a :class:`Solution` with outputs at ``t_eval`` (which starts with t0 and
ends with t_end), the located events and :class:`IntegratorStats`. Divergence is never
silent: see :class:`DivergenceError`.
"""
from __future__ import annotations

import math
import time
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.drive import (Event, EventRecord, Solution, StateCheck, drive,
                                             state_names_or_default)
from youbot_dynamics.integrate.errors import DivergenceError, IntegrationError, StepBudgetError
from youbot_dynamics.integrate.registry import REGISTRY, OdeProblem, integrator_names
from youbot_dynamics.integrate.statistics import IntegratorStats
from youbot_dynamics.integrate.sundials import CVODE_METHODS, IdaStepper

__all__ = ["IntegratorStats", "Event", "EventRecord", "Solution", "IntegrationError",
           "DivergenceError", "StepBudgetError", "integrate", "integrate_dae",
           "tolerances_from_tol", "fixed_step_count", "checked_fixed_step",
           "checked_output_spacing"]

Rhs = Callable[[float, np.ndarray], np.ndarray]

#: Smallest nominal magnitude of a state component (SI units: 1 mm, 1 mrad, 1 mm/s, ...),
#: so that a component that starts at 0 still gets a positive absolute tolerance.
NOMINAL_FLOOR = 1e-3


def tolerances_from_tol(tol: float, x0, nominal=None) -> tuple[float, np.ndarray]:
    """The one accuracy knob, as Modia and Dymola derive it: rtol = tol and, per state
    component, atol_i = tol * nominal_i with nominal_i = max(|x0_i|, NOMINAL_FLOOR) (or the
    given ``nominal`` scales, same units as x). Returns (rtol, atol array)."""
    checked_positive("tol", tol)
    scale = np.abs(checked_state("x0", x0)) if nominal is None else np.abs(
        np.asarray(nominal, dtype=float).ravel())
    return float(tol), float(tol) * np.maximum(scale, NOMINAL_FLOOR)


def checked_times(t_eval) -> np.ndarray:
    """t_eval as a float array: at least two strictly increasing finite times."""
    times = np.asarray(t_eval, dtype=float).ravel()
    if times.size < 2 or not np.all(np.isfinite(times)) or np.any(np.diff(times) <= 0):
        raise UserInputError("t_eval must hold at least two strictly increasing finite times "
                             f"(start first, end last), got {times!r}")
    return times


def checked_positive(name: str, value) -> None:
    """A step size or tolerance must be positive (every component of an array)."""
    if value is None or not np.all(np.asarray(value, dtype=float) > 0):
        raise UserInputError(f"{name} must be positive, got {value!r}")


def fixed_step_count(dt: float, times: np.ndarray) -> float:
    """Steps of size dt (s) a fixed-step run over ``times`` takes at least (one more per
    output interval that dt does not divide), as a float (it can exceed any int64)."""
    ratio = float(times[-1] - times[0]) / dt
    return float(math.ceil(ratio)) if ratio < 2.0 ** 52 else ratio


def checked_fixed_step(integrator: str, dt: float, times: np.ndarray,
                       max_steps: int | None) -> None:
    """Refuse, before any step, a dt (s) too small to move the clock (t + dt == t at the
    run's largest |t|) and a run of more than ``max_steps`` steps."""
    latest = float(np.max(np.abs(times[[0, -1]])))
    if latest + dt == latest:
        raise UserInputError(f"dt={dt:g} s is below the time resolution at t={latest:g} s "
                             f"(t + dt == t): use dt > {np.spacing(latest):.3g} s")
    count = fixed_step_count(dt, times)
    if max_steps is not None and count > max_steps:
        raise StepBudgetError(float(times[0]), integrator, dt, max_steps,
                              f"{integrator}: {count:.4g} steps of dt={dt:g} s over "
                              f"{times[-1] - times[0]:g} s exceed the step budget of "
                              f"{max_steps} steps")


def checked_output_spacing(dt: float | None, times: np.ndarray, where: str) -> None:
    """Refuse a fixed step dt (s) larger than the smallest output spacing: the integrator
    would shorten its steps to hit the outputs, silently running another method."""
    if dt is None or times.size < 2:
        return
    spacing = float(np.min(np.diff(times)))
    if dt > spacing * (1.0 + 1e-9):
        raise UserInputError(f"{where}: fixed step dt={dt:g} s is larger than the output "
                             f"spacing {spacing:g} s, so steps would be cut to it: lower dt "
                             f"to at most {spacing:g} s")


def checked_state(name: str, value) -> np.ndarray:
    """An initial state as a 1-D float array."""
    state = np.array(value, dtype=float).ravel()
    if state.size == 0 or not np.all(np.isfinite(state)):
        raise UserInputError(f"{name} must be a non-empty finite vector, got {value!r}")
    return state


def integrate(rhs: Rhs, x0, t_eval, integrator: str, *, dt: float | None = None,
              rtol: float = 1e-6, atol: float | np.ndarray = 1e-8,
              jac: Callable[[float, np.ndarray], np.ndarray] | None = None,
              events: Sequence[Event] = (), state_names: Sequence[str] | None = None,
              n_positions: int | None = None, bounds: np.ndarray | None = None,
              monitor: Callable[[float, np.ndarray], str | None] | None = None,
              max_step: float = np.inf, min_step: float | None = None,
              max_steps: int | None = None,
              progress: Callable[[float], None] | None = None,
              max_order: int | None = None) -> Solution:
    """Solve x' = rhs(t, x) from x0 at t_eval[0], with outputs at t_eval (s).

    Fixed-step methods need ``dt`` (s); adaptive ones use ``rtol``/``atol`` (``jac``, the
    Jacobian d rhs / dx, is used by the implicit ones). ``symplectic_euler`` needs
    ``n_positions``: x = [q (n), v (n), extra] with dq/dt = v. ``bounds``: |x_i| <= bounds_i
    or DivergenceError; ``monitor(t, x)`` is called at output times and a returned string
    is a DivergenceError. Adaptive steps below ``min_step`` (s) are a DivergenceError. A
    run of more than ``max_steps`` steps is a StepBudgetError (fixed steps: before the
    first; a dt that cannot move the clock is a UserInputError). ``progress(t)`` is called
    with the time reached (s) after each output. ``max_order`` caps CVODE's order.
    """
    start = time.perf_counter()
    entry = REGISTRY.get(integrator)
    if entry is None or entry.kind != "ode":
        hint = {"dae": " (use integrate_dae for it)",
                "stepper": " (a constraint-contact stepper)"}.get(getattr(entry, "kind", ""), "")
        raise UserInputError(f"unknown ODE integrator {integrator!r}{hint}; valid names: "
                             + ", ".join(integrator_names("ode")))
    times = checked_times(t_eval)
    x = checked_state("x0", x0)
    names = state_names_or_default(state_names, x.size)
    check = StateCheck(integrator, names, bounds, monitor)
    n = 0 if n_positions is None else int(n_positions)
    if not entry.adaptive:
        if dt is None:
            raise UserInputError(f"integrator {integrator!r} takes fixed steps: give dt (s), "
                                 "or use an adaptive one: "
                                 + ", ".join(integrator_names("ode", adaptive=True)))
        checked_positive("dt", dt)
        checked_fixed_step(integrator, float(dt), times, max_steps)
        if integrator == "symplectic_euler" and not 0 < 2 * n <= x.size:
            raise UserInputError("symplectic_euler needs n_positions with 0 < 2*n_positions "
                                 f"<= state size {x.size}, got {n_positions!r}")
    else:
        checked_positive("rtol", rtol)
        checked_positive("atol", atol)
        checked_positive("max_step", max_step)
    if max_order is not None and integrator not in CVODE_METHODS:
        raise UserInputError(f"max_order applies to cvode_bdf and cvode_adams, not {integrator}")
    problem = OdeProblem(rhs, times[0], x, times[-1], dt, rtol, atol, jac, max_step, min_step,
                         n, tuple(events), check, max_order, max_steps)
    stepper = entry.factory(integrator, problem)
    solution = drive(stepper, integrator, times, events, check, names, max_steps=max_steps,
                     progress=progress)
    solution.stats.wall_time = time.perf_counter() - start
    return solution


def integrate_dae(residual: Callable[[float, np.ndarray, np.ndarray], np.ndarray], y0, yp0,
                  t_eval, *, algebraic: Sequence[bool], rtol: float = 1e-6,
                  atol: float | np.ndarray = 1e-8,
                  exclude_from_error_test: Sequence[bool] | None = None,
                  events: Sequence[Event] = (), state_names: Sequence[str] | None = None,
                  jac: Callable | None = None, bounds: np.ndarray | None = None,
                  monitor: Callable[[float, np.ndarray], str | None] | None = None,
                  ida_options: Mapping[str, Any] | None = None, max_steps: int | None = None,
                  progress: Callable[[float], None] | None = None) -> Solution:
    """Solve the DAE residual(t, y, y') = 0 with SUNDIALS IDA (integrator ``ida``).

    ``algebraic[i]`` marks y_i as algebraic (no y_i' in the equations). y0, yp0 must be
    consistent. ``exclude_from_error_test``: IDASetSuppressAlg (integrate/sundials.py), which
    takes every algebraic component out of IDA's error test, so its True entries must be
    exactly the algebraic ones (or none). ``jac(t, y, yp, cj)``
    returns dF/dy + cj dF/dy' (IDA builds it by finite differences without it).
    ``ida_options``: further sksundae.ida.IDA options passed as they are (first_step,
    max_step, max_order, max_nonlin_iters, max_conv_fails, ...; times in s). Events see
    (t, y). Solution.xp holds y' at the outputs. ``max_steps`` and ``progress`` as for
    :func:`integrate`.
    """
    start = time.perf_counter()
    times = checked_times(t_eval)
    y, yp = checked_state("y0", y0), checked_state("yp0", yp0)
    names = state_names_or_default(state_names, y.size)
    flags = [np.asarray(algebraic, dtype=bool).ravel()]
    if exclude_from_error_test is not None:
        flags.append(np.asarray(exclude_from_error_test, dtype=bool).ravel())
    if yp.size != y.size or any(f.size != y.size for f in flags):
        raise UserInputError(f"y0 has {y.size} components but yp0 has {yp.size} and "
                             f"algebraic/exclude_from_error_test have "
                             f"{[f.size for f in flags]}")
    suppress = len(flags) > 1 and bool(flags[1].any())
    if suppress and not np.array_equal(flags[0], flags[1]):
        raise UserInputError("exclude_from_error_test must mark exactly the algebraic "
                             "components (IDA's suppress-alg excludes all of them), got "
                             f"{flags[1].tolist()} for algebraic {flags[0].tolist()}")
    checked_positive("rtol", rtol)
    checked_positive("atol", atol)
    check = StateCheck("ida", names, bounds, monitor)
    stepper = IdaStepper(residual, times[0], y, yp, times[-1], flags[0], rtol, atol, jac,
                         dict(ida_options or {}), tuple(events), suppress)
    solution = drive(stepper, "ida", times, events, check, names,
                     derivative_at=stepper.derivative_at, max_steps=max_steps,
                     progress=progress)
    solution.stats.wall_time = time.perf_counter() - start
    return solution
