"""The one table of integrators: each name's kind, step control, options and stepper factory.

Kinds: ``ode`` solves x' = f(t, x) (:func:`~youbot_dynamics.integrate.integrators.integrate`),
``dae`` solves F(t, y, y') = 0 (``integrate_dae``), ``stepper`` is the constraint-contact
time stepper (velocity level, impulses, fixed dt; the engine builds it from its contact
model, so its entries carry no factory here). Fixed-step methods take ``dt`` (s); adaptive
ones ``tol`` or ``rtol``/``atol``. ``stiff`` methods are implicit (they use a Jacobian).

``dop853_compiled`` is scipy's DOP853 (the same step-size control: steps and states equal
to rounding) run in compiled code (integrate/dop853.py) where the right-hand side carries a compiled loop for it
(``rhs.compiled_steps``: a robot alone under a held torque or no controller,
sim/compiled_steps.py); any other right-hand side falls back to scipy's DOP853 itself, the
same method in Python, so the name is valid in every scene and only the speed differs.

Every other module asks this table: the scene validator (names and options), ``integrate``
(the factory), the engine's dispatch (:func:`integrator_kind`), the command line (choices)
and the work-precision sweep (which methods are fixed-step or stiff).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.adaptive import ScipyStepper
from youbot_dynamics.integrate.dop853 import CompiledDop853Stepper
from youbot_dynamics.integrate.drive import Event, StateCheck, Stepper, finite_rhs
from youbot_dynamics.integrate.fixed_step import FixedStepStepper
from youbot_dynamics.integrate.sundials import CVODE_METHODS, CvodeStepper

KINDS = ("ode", "dae", "stepper")
#: The scene's ``integrator.method`` that stands for "chosen offline by work-precision".
AUTO = "auto"


@dataclass(frozen=True)
class OdeProblem:
    """What an ODE stepper factory needs: x' = rhs(t, x) from (t0, x0) to t_end (s), the
    step dt (s, fixed-step) or rtol/atol (adaptive), the Jacobian d rhs / dx if known, step
    limits (s), ``n_positions`` (x = [q, v, ...], symplectic Euler), the events and the
    divergence checks; ``max_order`` caps a multistep method's order (CVODE); ``max_steps``
    is the run's step budget (None: none), for a stepper that takes many steps per
    ``advance``."""

    rhs: Callable[[float, np.ndarray], np.ndarray]
    t0: float
    x0: np.ndarray
    t_end: float
    dt: float | None
    rtol: float
    atol: float | np.ndarray
    jac: Callable[[float, np.ndarray], np.ndarray] | None
    max_step: float
    min_step: float | None
    n_positions: int
    events: tuple[Event, ...]
    check: StateCheck
    max_order: int | None = None
    max_steps: int | None = None


@dataclass(frozen=True)
class IntegratorEntry:
    """One integrator: its name, kind, step control, stiffness, the factory that builds
    its :class:`~youbot_dynamics.integrate.drive.Stepper` and, for a fixed-step method, its
    order of convergence p (global error ~ dt^p; the error estimate's Richardson factor)."""

    name: str
    kind: str
    adaptive: bool
    stiff: bool
    factory: Callable[[str, OdeProblem], Stepper] | None = None
    order: int | None = None

    @property
    def options(self) -> tuple[str, ...]:
        """The scene's ``integrator`` keys that set its accuracy."""
        return ("tol", "rtol", "atol") if self.adaptive else ("dt",)


def fixed_step_stepper(name: str, problem: OdeProblem) -> Stepper:
    """The hand-written fixed-step loops (integrate/fixed_step.py)."""
    return FixedStepStepper(name, problem.rhs, problem.t0, problem.x0, float(problem.dt),
                            problem.n_positions, bool(problem.events), problem.check)


def scipy_stepper(name: str, problem: OdeProblem) -> Stepper:
    """A scipy.integrate OdeSolver stepped one step at a time (integrate/adaptive.py)."""
    return ScipyStepper(name, finite_rhs(problem.rhs, name), problem.t0, problem.x0,
                        problem.t_end, problem.rtol, problem.atol, problem.jac,
                        problem.max_step, problem.min_step)


def compiled_dop853_stepper(name: str, problem: OdeProblem) -> Stepper:
    """DOP853 in compiled code (integrate/dop853.py) through the right-hand side's compiled
    loop (``rhs.compiled_steps``); scipy's DOP853 where the right-hand side has none."""
    loop = getattr(problem.rhs, "compiled_steps", None)
    if loop is None:
        return scipy_stepper("dop853", problem)
    return CompiledDop853Stepper(name, loop, problem.t0, problem.x0, problem.t_end, problem.rtol, problem.atol,
                                 problem.max_step, problem.min_step, bool(problem.events), problem.check.bounds,
                                 problem.max_steps)


def cvode_stepper(name: str, problem: OdeProblem) -> Stepper:
    """SUNDIALS CVODE through scikit-sundae (integrate/sundials.py); it locates events itself."""
    return CvodeStepper(CVODE_METHODS[name], name, problem.rhs, problem.t0, problem.x0,
                        problem.t_end, problem.rtol, problem.atol, problem.jac,
                        problem.max_step, problem.min_step, problem.events, problem.max_order)


REGISTRY: dict[str, IntegratorEntry] = {entry.name: entry for entry in (
    IntegratorEntry("euler", "ode", False, False, fixed_step_stepper, 1),  # hand-written loops
    IntegratorEntry("symplectic_euler", "ode", False, False, fixed_step_stepper, 1),
    IntegratorEntry("rk4", "ode", False, False, fixed_step_stepper, 4),
    IntegratorEntry("rk45", "ode", True, False, scipy_stepper),  # Dormand-Prince 5(4)
    IntegratorEntry("dop853", "ode", True, False, scipy_stepper),
    IntegratorEntry("dop853_compiled", "ode", True, False, compiled_dop853_stepper),  # the same, compiled
    IntegratorEntry("radau", "ode", True, True, scipy_stepper),  # Radau IIA, order 5
    IntegratorEntry("bdf", "ode", True, True, scipy_stepper),
    IntegratorEntry("lsoda", "ode", True, True, scipy_stepper),  # Adams / BDF, switching on stiffness
    IntegratorEntry("cvode_bdf", "ode", True, True, cvode_stepper),  # SUNDIALS
    IntegratorEntry("cvode_adams", "ode", True, False, cvode_stepper),
    IntegratorEntry("ida", "dae", True, True),  # SUNDIALS IDA: integrate_dae
    IntegratorEntry("pgs", "stepper", False, False, order=1),  # constraint contact: Pinocchio's PGS
    IntegratorEntry("admm", "stepper", False, False, order=1),  # and ADMM (velocity level, order 1)
)}


def integrator_names(kind: str | Sequence[str] = KINDS, *, adaptive: bool | None = None,
                     stiff: bool | None = None) -> tuple[str, ...]:
    """The names of the given kind(s) (``ode``, ``dae``, ``stepper``), in table order,
    optionally only the adaptive (or fixed-step) and the stiff (or non-stiff) ones."""
    kinds = (kind,) if isinstance(kind, str) else tuple(kind)
    return tuple(name for name, entry in REGISTRY.items() if entry.kind in kinds
                 and (adaptive is None or entry.adaptive == adaptive)
                 and (stiff is None or entry.stiff == stiff))


def integrator_entry(name: str) -> IntegratorEntry:
    """The entry of ``name``; UserInputError listing the known names if there is none."""
    try:
        return REGISTRY[name]
    except (KeyError, TypeError):
        raise UserInputError(f"unknown integrator {name!r}; known: {', '.join(REGISTRY)}") from None


def integrator_kind(name: str) -> str:
    """``ode``, ``dae`` or ``stepper``: the engine's dispatch in one lookup."""
    return integrator_entry(name).kind


def is_fixed_step(name: str) -> bool:
    """Whether ``name`` takes a fixed step dt (s) rather than tolerances."""
    return not integrator_entry(name).adaptive


#: ODE and DAE integrators (every name ``integrate`` or ``integrate_dae`` takes).
INTEGRATORS: tuple[str, ...] = integrator_names(("ode", "dae"))
#: The fixed-step ODE integrators.
FIXED_STEP: tuple[str, ...] = integrator_names("ode", adaptive=False)
#: The constraint-contact steppers (fixed dt).
STEPPERS: tuple[str, ...] = integrator_names("stepper")
