"""SUNDIALS CVODE (BDF and Adams-Moulton) and IDA through scikit-sundae, one internal step
per ``advance`` (``method='onestep'`` with ``tstop`` = t_end) so that steps are counted;
states between steps come from SUNDIALS' own interpolation (``method='normal'`` with a time
inside the last step, which takes no step and evaluates nothing).

Events are located by SUNDIALS' own rootfinding (``eventsfn``) on the solver's interpolant:
a step that holds a root returns at the root first (``roots`` names the events there, and
:func:`~youbot_dynamics.integrate.drive.drive` takes them as they are), then at its end.
A guard that reads exactly 0 at the start is inactive until it leaves 0 (SUNDIALS' rule),
which is how a hybrid restart ignores the crossing it just handled.

scikit-sundae 1.2 reports only right-hand-side (residual) and Jacobian evaluations and does
not expose IDASetSuppressAlg. Both are reached through the SUNDIALS libraries that its wheel
ships (``scikit_sundae.libs/libsundials_{cvode,ida}-*.so``, already loaded by its extension
modules): :func:`solver_memory` reads the solver's CVODE or IDA memory pointer out of the
extension object (its layout is that of scikit-sundae 1.2.0, the locked version; another
version is refused, and every read is checked against what scikit-sundae itself reports),
then :func:`solver_counters` reads the error-test failures, nonlinear iterations and
nonlinear convergence failures, and :func:`suppress_algebraic_error` calls IDASetSuppressAlg,
which takes the algebraic components (id 0) out of IDA's local error test.
"""
from __future__ import annotations

import ctypes
import ctypes.util
import functools
import os
from pathlib import Path
from typing import Callable, NamedTuple

import numpy as np
import sksundae
from sksundae.cvode import CVODE
from sksundae.ida import IDA

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.drive import Event
from youbot_dynamics.integrate.errors import DivergenceError, IntegrationError
from youbot_dynamics.integrate.statistics import IntegratorStats

#: SUNDIALS' logger writes warnings straight to stderr. The one these runs raise says that a
#: guard reads exactly 0 at a restart (the sleeve sitting at its stop), which is the rule
#: relied on above; set the variable to a file name (or "stderr") to see SUNDIALS' warnings.
os.environ.setdefault("SUNLOGGER_WARNING_FILENAME", os.devnull)

CVODE_METHODS = {"cvode_bdf": "BDF", "cvode_adams": "Adams"}
#: SUNDIALS flags meaning the step size collapsed (error or convergence test failures at
#: the minimum step, or accuracy beyond machine precision): divergence, not a usage error.
COLLAPSE_FLAGS = (-2, -3, -4)
#: SUNDIALS' flag for a return at a located root (CV_ROOT_RETURN, IDA_ROOT_RETURN).
ROOT_RETURN = 2

#: The scikit-sundae version whose extension-object layout :func:`solver_memory` reads.
LAYOUT_VERSION = "1.2.0"
#: Byte offset of ``void* mem`` in sksundae._cy_cvode.CVODE and sksundae._cy_ida.IDA: after
#: the object header (reference count and type, 16 bytes) and Cython's virtual-table pointer
#: (8 bytes).
MEMORY_OFFSET = 24


class SundialsSolver(NamedTuple):
    """Where one SUNDIALS solver of scikit-sundae's wheel is reached: its library (file-name
    pattern in ``scikit_sundae.libs``, else the system's ``system_name``), the prefix of its
    C functions, its evaluation counter (checked against scikit-sundae's ``nfev``) and the
    attribute of the sksundae solver that holds the extension object."""

    library_glob: str
    system_name: str
    prefix: str
    evaluations: str
    extension: str


SOLVERS = {"cvode": SundialsSolver("libsundials_cvode-*.so*", "sundials_cvode", "CVode", "GetNumRhsEvals",
                                   "_CVODE__CVODE"),
           "ida": SundialsSolver("libsundials_ida-*.so*", "sundials_ida", "IDA", "GetNumResEvals", "_IDA__IDA")}
#: IntegratorStats counters read from either solver (field -> <prefix>GetNum* function).
COUNTERS = {"rejected_steps": "GetNumErrTestFails",
            "nonlinear_iterations": "GetNumNonlinSolvIters",
            "nonlinear_convergence_failures": "GetNumNonlinSolvConvFails"}


@functools.cache
def solver_library(kind: str) -> ctypes.CDLL | None:
    """The SUNDIALS library of solver ``kind`` ('cvode' or 'ida') that scikit-sundae's
    extension is linked against (the wheel's copy, else the system's), or None if neither
    is found."""
    solver = SOLVERS[kind]
    shipped = sorted((Path(sksundae.__file__).parent.parent / "scikit_sundae.libs").glob(solver.library_glob))
    path = str(shipped[0]) if shipped else ctypes.util.find_library(solver.system_name)
    if path is None:
        return None
    library = ctypes.CDLL(path)
    for name in (*COUNTERS.values(), solver.evaluations):
        getattr(library, solver.prefix + name).argtypes = (ctypes.c_void_p, ctypes.POINTER(ctypes.c_long))
    getattr(library, solver.prefix + "GetCurrentTime").argtypes = (ctypes.c_void_p, ctypes.POINTER(ctypes.c_double))
    if kind == "ida":
        library.IDASetSuppressAlg.argtypes = (ctypes.c_void_p, ctypes.c_int)
    return library


def solver_memory(kind: str, solver: CVODE | IDA) -> ctypes.c_void_p | None:
    """The SUNDIALS memory pointer inside an initialised scikit-sundae solver of ``kind``, or
    None when the library or the known layout (scikit-sundae LAYOUT_VERSION) is not
    available."""
    if sksundae.__version__ != LAYOUT_VERSION or solver_library(kind) is None:
        return None
    extension = getattr(solver, SOLVERS[kind].extension)
    return ctypes.c_void_p(ctypes.c_void_p.from_address(id(extension) + MEMORY_OFFSET).value)


def solver_count(kind: str, memory: ctypes.c_void_p, function: str) -> int:
    """One <prefix>GetNum* counter (``function`` without the prefix); a failing call is an
    IntegrationError."""
    name = SOLVERS[kind].prefix + function
    value = ctypes.c_long()
    flag = getattr(solver_library(kind), name)(memory, ctypes.byref(value))
    if flag != 0:
        raise IntegrationError(f"{kind}: {name} failed with flag {flag}")
    return int(value.value)


def checked_memory(kind: str, memory: ctypes.c_void_p, result) -> None:
    """The pointer must be the solver's own: its current time must be readable and its
    evaluation count must be the one scikit-sundae reports in ``result``."""
    now = ctypes.c_double()
    flag = getattr(solver_library(kind), SOLVERS[kind].prefix + "GetCurrentTime")(memory, ctypes.byref(now))
    if flag != 0 or solver_count(kind, memory, SOLVERS[kind].evaluations) != int(result.nfev):
        raise IntegrationError(f"{kind}: the SUNDIALS memory read from scikit-sundae's solver does "
                               f"not match its results (flag {flag}); its layout differs "
                               f"from scikit-sundae {LAYOUT_VERSION}'s")


def solver_counters(kind: str, memory: ctypes.c_void_p) -> dict[str, int]:
    """Error-test failures, nonlinear iterations and convergence failures so far."""
    return {field: solver_count(kind, memory, function) for field, function in COUNTERS.items()}


def suppress_algebraic_error(memory: ctypes.c_void_p) -> None:
    """IDASetSuppressAlg(mem, true): the components with id 0 leave the error test."""
    flag = solver_library("ida").IDASetSuppressAlg(memory, 1)
    if flag != 0:
        raise IntegrationError(f"ida: IDASetSuppressAlg failed with flag {flag}")


def events_options(events: tuple[Event, ...], with_yp: bool) -> dict:
    """sksundae options that make SUNDIALS locate the zero crossings of the events'
    functions g(t, y) in their directions (every root stops the solver; :func:`drive`
    decides what is terminal). ``with_yp``: IDA's signature g(t, y, yp, out)."""
    if not events:
        return {}
    functions = [event.function for event in events]

    def values(t, y, out):
        for i, function in enumerate(functions):
            out[i] = function(t, y)

    eventsfn = (lambda t, y, yp, out: values(t, y, out)) if with_yp else values
    eventsfn.direction = [event.direction for event in events]
    eventsfn.terminal = [True] * len(events)
    return {"eventsfn": eventsfn, "num_events": len(events)}


class SundialsStepper:
    """Shared stepping for CVODE and IDA: one new internal step per ``advance``, or the
    part of it up to a root that SUNDIALS located (``roots``: the events' indices there;
    ``steps`` counts the internal steps, not the returns at roots)."""

    locates_events = True

    def __init__(self, kind: str, name: str, solver: CVODE | IDA, t0: float, t_end: float, initial) -> None:
        self.kind, self.name, self.solver, self.t_end = kind, name, solver, t_end
        self.t, self.x = t0, np.array(initial.y, dtype=float)
        self.h = 0.0
        self.steps = 0
        self.last = initial
        self.roots: list[int] = []
        self.memory = solver_memory(kind, solver)
        if self.memory is not None:
            checked_memory(kind, self.memory, initial)

    def checked(self, result):
        """The solver's result, or the typed error for its failure flag."""
        if not result.success:
            if result.status in COLLAPSE_FLAGS:
                raise DivergenceError(float(self.t), self.name, self.h,
                                      f"step size collapsed: {result.message}")
            raise IntegrationError(f"{self.name} failed at t={self.t:.6g} s "
                                   f"(flag {result.status}): {result.message}")
        return result

    def advance(self, t_target: float) -> None:
        # After an interpolation SUNDIALS first returns its current step end again.
        result = self.last
        while result.t <= self.t:
            result = self.checked(self.solver.step(self.t_end, method="onestep",
                                                   tstop=self.t_end))
        at_root = result.status == ROOT_RETURN
        self.roots = np.flatnonzero(result.i_events[-1]).tolist() if at_root else []
        self.steps += not at_root
        self.h = float(result.t) - self.t
        self.t, self.x, self.last = float(result.t), np.array(result.y), result

    def interpolate(self, t: float) -> np.ndarray:
        self.last = self.checked(self.solver.step(t, method="normal"))
        return np.array(self.last.y)

    def finish(self, stats: IntegratorStats) -> None:
        """Steps, evaluations and SUNDIALS' own error-test failures, nonlinear iterations and
        convergence failures (None only if its memory cannot be reached)."""
        stats.steps = self.steps
        stats.rhs_evals, stats.jac_evals = int(self.last.nfev), int(self.last.njev)
        counters = dict.fromkeys(COUNTERS)
        if self.memory is not None:
            checked_memory(self.kind, self.memory, self.last)
            counters = solver_counters(self.kind, self.memory)
        for field, value in counters.items():
            setattr(stats, field, value)


def common_options(rtol: float, atol, max_step: float, min_step: float | None) -> dict:
    """Options shared by CVODE and IDA (SUNDIALS uses 0 for 'no limit')."""
    return {"rtol": rtol, "atol": atol, "max_step": 0.0 if np.isinf(max_step) else max_step,
            "min_step": min_step or 0.0, "max_num_steps": 100_000}


#: Highest order of each CVODE method (SUNDIALS' defaults and limits).
CVODE_MAX_ORDER = {"BDF": 5, "Adams": 12}


class CvodeStepper(SundialsStepper):
    """CVODE with method 'BDF' or 'Adams'; ``jac(t, x)`` is d rhs / dx if given;
    ``max_order`` caps the method's order (1..5 for BDF, 1..12 for Adams; None: the
    highest)."""

    def __init__(self, method: str, name: str, rhs: Callable, t0: float, x0: np.ndarray,
                 t_end: float, rtol: float, atol, jac, max_step: float,
                 min_step: float | None, events: tuple[Event, ...] = (),
                 max_order: int | None = None) -> None:
        def rhsfn(t, y, yp):
            yp[:] = rhs(t, y)

        options = common_options(rtol, atol, max_step, min_step)
        if max_order is not None:
            if not 1 <= max_order <= CVODE_MAX_ORDER[method]:
                raise UserInputError(f"{name}: max_order must be 1..{CVODE_MAX_ORDER[method]}, "
                                     f"got {max_order!r}")
            options["max_order"] = int(max_order)
        options.update(events_options(events, with_yp=False))
        if jac is not None:
            def jacfn(t, y, yp, jj):
                jj[:, :] = jac(t, y)
            options["jacfn"] = jacfn
        solver = CVODE(rhsfn, method=method, **options)
        super().__init__("cvode", name, solver, t0, t_end, solver.init_step(t0, x0))


class IdaStepper(SundialsStepper):
    """IDA on residual(t, y, y') = 0; ``jac(t, y, yp, cj)`` = dF/dy + cj dF/dy' if given;
    ``extra`` holds further sksundae.ida.IDA options (e.g. first_step, max_step in s,
    max_order, max_nonlin_iters), which take precedence over the defaults here.
    ``suppress_alg``: the algebraic components leave the error test (IDASetSuppressAlg).
    The statistics carry IDA's own error-test failures, nonlinear iterations and
    convergence failures (None only if the IDA memory cannot be reached)."""

    def __init__(self, residual: Callable, t0: float, y0: np.ndarray, yp0: np.ndarray,
                 t_end: float, algebraic: np.ndarray, rtol: float, atol, jac,
                 extra: dict | None = None, events: tuple[Event, ...] = (),
                 suppress_alg: bool = False) -> None:
        def resfn(t, y, yp, res):
            res[:] = residual(t, y, yp)

        options = common_options(rtol, atol, np.inf, None)
        options.update(events_options(events, with_yp=True))
        options["algebraic_idx"] = np.flatnonzero(algebraic) if algebraic.any() else None
        if jac is not None:
            def jacfn(t, y, yp, res, cj, jj):
                jj[:, :] = jac(t, y, yp, cj)
            options["jacfn"] = jacfn
        options.update(extra or {})
        solver = IDA(resfn, **options)
        super().__init__("ida", "ida", solver, t0, t_end, solver.init_step(t0, y0, yp0))
        if suppress_alg:
            if self.memory is None:
                library = "missing" if solver_library("ida") is None else "found"
                raise NotImplementedError(
                    "suppress_alg needs IDASetSuppressAlg through scikit-sundae "
                    f"{LAYOUT_VERSION}'s SUNDIALS library, found version "
                    f"{sksundae.__version__} (library {library})")
            suppress_algebraic_error(self.memory)

    def derivative_at(self, t: float) -> np.ndarray:
        """y' at t: the last result's when it is at t, else IDA's interpolation."""
        if float(self.last.t) != t:
            self.interpolate(t)
        return np.array(self.last.yp)
