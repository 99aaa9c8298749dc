"""What every integrator backend shares: events, the solution, the divergence checks and
the one output/event loop that drives a stepper (the statistics are integrate/statistics.py's,
the typed errors integrate/errors.py's).

A backend supplies a *stepper* (see :class:`Stepper`): ``advance`` takes one step (or, for
fixed-step methods without events, the steps up to the next output time) and
``interpolate`` gives the state anywhere inside the last step. :func:`drive` does the rest:
outputs at the requested times, event location by Brent's method on ``interpolate``
(step end when the interpolant shows no sign change) unless the stepper locates events
itself (SUNDIALS' rootfinding), terminal events, and the checks that make divergence loud.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Protocol, Sequence

import numpy as np
from numba import njit, types
from scipy.optimize import brentq

from youbot_dynamics.compiled import BORROWED, FLOAT, unchecked
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.errors import DivergenceError, StepBudgetError
from youbot_dynamics.integrate.statistics import IntegratorStats

@dataclass(frozen=True)
class Event:
    """A state event: the zero crossing of ``function(t, x)``, located by root finding.

    ``direction``: +1 rising only, -1 falling only, 0 both. ``terminal``: stop the run.
    """

    name: str
    function: Callable[[float, np.ndarray], float]
    direction: int = 0
    terminal: bool = True


@dataclass
class EventRecord:
    """An event that occurred: its time (s), its name and the state there."""

    time: float
    name: str
    state: np.ndarray


@dataclass
class Solution:
    """A run's trajectory at the output times and its statistics.

    If a terminal event stopped the run, ``t``/``x`` end with the event time and state and
    ``terminated_by`` names the event. ``xp`` holds y' at the output times for ``ida``.
    """

    t: np.ndarray
    x: np.ndarray
    stats: IntegratorStats
    state_names: tuple[str, ...]
    events: list[EventRecord] = field(default_factory=list)
    terminated_by: str | None = None
    xp: np.ndarray | None = None


def finite_rhs(rhs: Callable[[float, np.ndarray], np.ndarray],
               integrator: str) -> Callable[[float, np.ndarray], np.ndarray]:
    """rhs that raises DivergenceError when called on, or returning, non-finite values:
    a solver fed NaN can loop for ever (scipy's RK step size turns NaN and no step is ever
    accepted or refused)."""
    def checked(t: float, x: np.ndarray) -> np.ndarray:
        if not math.isfinite(x.sum()):
            raise DivergenceError(t, integrator, math.nan, "non-finite state inside a step")
        dx = rhs(t, x)
        if not math.isfinite(dx.sum()):
            raise DivergenceError(t, integrator, math.nan, "non-finite derivative inside a step")
        return dx
    return checked


def state_names_or_default(state_names: Sequence[str] | None, size: int) -> tuple[str, ...]:
    """The given component names (checked against the state size) or x[0], x[1], ..."""
    if state_names is None:
        return tuple(f"x[{i}]" for i in range(size))
    names = tuple(state_names)
    if len(names) != size:
        raise UserInputError(f"state_names has {len(names)} names but the state has {size} "
                             "components")
    return names


_ANY_VECTOR = types.Array(types.float64, 1, "A", readonly=True)


@njit(types.boolean(_ANY_VECTOR, _ANY_VECTOR), **BORROWED)
def finite_within(x: np.ndarray, bounds: np.ndarray) -> bool:
    """Whether every entry of x is finite and (with ``bounds``, one per entry; empty: none)
    |x_i| <= bounds_i (a NaN bound holds nothing back, as numpy's ``|x| > bounds`` reads it):
    the common case of :meth:`StateCheck.step` in one pass, which looks no further when it
    holds, and the compiled loops' check after each step (sim/compiled_steps.py)."""
    bounded = bounds.shape[0] > 0
    if bounded and bounds.shape[0] != x.shape[0]:
        return False  # numpy's comparison decides (and names the mismatch)
    for i in range(x.shape[0]):
        value = x[i]
        if not value - value == 0.0 or (bounded and abs(value) > bounds[i]):  # inf - inf, NaN: NaN
            return False
    return True


#: :func:`finite_within` without numba's dispatch (float64 vectors: :meth:`StateCheck.step`).
_finite_within_unchecked = unchecked(finite_within)
#: The bounds handed to :func:`finite_within` without bounds (none read).
_NO_BOUNDS = np.empty(0)


class StateCheck:
    """Divergence checks: non-finite state and ``bounds`` after every step, ``monitor`` at
    output times. Each failure raises :class:`DivergenceError` naming the offending
    components (all of them, up to eight, for a monitor's complaint)."""

    def __init__(self, integrator: str, names: tuple[str, ...], bounds: np.ndarray | None,
                 monitor: Callable[[float, np.ndarray], str | None] | None) -> None:
        self.integrator = integrator
        self.names = names
        self.bounds = None if bounds is None else np.broadcast_to(
            np.asarray(bounds, dtype=float), (len(names),))
        self._bounds_vector = _NO_BOUNDS if self.bounds is None else self.bounds
        self.monitor = monitor

    def _fail(self, t: float, h: float, reason: str, mask: np.ndarray, x: np.ndarray) -> None:
        indices = np.flatnonzero(mask)[:8]
        raise DivergenceError(t, self.integrator, h, reason,
                              {self.names[i]: float(x[i]) for i in indices})

    def step(self, t: float, x: np.ndarray, h: float) -> None:
        """After a step of size h (s) reaching (t, x): non-finite values and bounds (a float64
        state vector within them passes in one compiled call)."""
        if type(x) is np.ndarray and x.dtype is FLOAT and x.ndim == 1 and \
                _finite_within_unchecked(x, self._bounds_vector):
            return
        if not math.isfinite(x.sum()):
            bad = ~np.isfinite(x)
            if bad.any():
                self._fail(t, h, "non-finite state", bad, x)
        if self.bounds is not None:
            over = np.abs(x) > self.bounds
            if over.any():
                self._fail(t, h, "state outside its bounds", over, x)

    def output(self, t: float, x: np.ndarray, h: float) -> None:
        """At an output time: the user's monitor."""
        if self.monitor is not None:
            reason = self.monitor(t, x)
            if reason:
                self._fail(t, h, reason, np.ones(len(x), dtype=bool), x)


class Stepper(Protocol):
    """What :func:`drive` needs from a backend."""

    t: float
    x: np.ndarray
    h: float  # the last step's size, s
    steps: int  # steps taken so far

    def advance(self, t_target: float) -> None:
        """Step towards ``t_target`` (never beyond the run's end); updates t and x."""

    def interpolate(self, t: float) -> np.ndarray:
        """The state at t inside the last step (t_previous <= t <= self.t)."""

    def finish(self, stats: IntegratorStats) -> None:
        """Copy the backend's counters into stats."""


def located_by_stepper(stepper: Stepper) -> bool:
    """Whether the stepper stops at event roots itself (then ``stepper.roots`` lists the
    indices of the events whose root is at ``stepper.t`` after each ``advance``)."""
    return getattr(stepper, "locates_events", False)


def crossed(g_old: float, g_new: float, direction: int) -> bool:
    """Whether an event function crossed zero between two steps in the given direction."""
    rising = g_old < 0.0 <= g_new
    falling = g_old > 0.0 >= g_new
    return (direction >= 0 and rising) or (direction <= 0 and falling)


def locate_crossings(events: Sequence[Event], g_old: list[float], g_new: list[float],
                     t_a: float, t_b: float,
                     state_at: Callable[[float], np.ndarray]) -> list[tuple[float, int]]:
    """Times of the zero crossings in [t_a, t_b], earliest first.

    A crossing is detected on the step-end states (``g_old``, ``g_new``) and located by
    Brent's method on the one function g(t, state_at(t)), bracketed by that same function's
    values at t_a and t_b (t to 4 eps |t| + 1e-14 s). The interpolant's ends can differ from
    the step-end states (by round-off, or an implicit solver's interpolation error); where
    they show no sign change, the crossing is put at the step end t_b, where it was seen.
    """
    found = []
    for i, event in enumerate(events):
        if crossed(g_old[i], g_new[i], event.direction):
            found.append((root_on_interpolant(event.function, t_a, t_b, state_at), i))
    return sorted(found)


def root_on_interpolant(function: Callable[[float, np.ndarray], float], t_a: float,
                        t_b: float, state_at: Callable[[float], np.ndarray]) -> float:
    """The zero of g(t) = function(t, state_at(t)) in [t_a, t_b] (s) by Brent's method,
    or t_b if g shows no sign change between the two ends."""
    def g(t: float) -> float:
        return function(t, state_at(t))

    g_a, g_b = g(t_a), g(t_b)
    if not (np.isfinite(g_a) and np.isfinite(g_b)) or np.sign(g_a) * np.sign(g_b) > 0:
        return t_b
    xtol = 4 * np.finfo(float).eps * max(abs(t_a), abs(t_b)) + 1e-14
    return brentq(g, t_a, t_b, xtol=xtol)


class _Outputs:
    """The states at the output times (and y' there, with ``derivative_at``), each checked
    by ``check.output`` as it is recorded."""

    def __init__(self, t0: float, x0: np.ndarray, check: StateCheck,
                 derivative_at: Callable[[float], np.ndarray] | None) -> None:
        self.t, self.x = [t0], [x0]
        self.xp = [] if derivative_at is None else [derivative_at(t0)]
        self.check, self.derivative_at = check, derivative_at

    def emit(self, t: float, x: np.ndarray, h: float) -> None:
        """Record the state x at output time t (s), reached by a step of size h (s)."""
        self.check.output(t, x, h)
        self.t.append(t)
        self.x.append(x)
        if self.derivative_at is not None:
            self.xp.append(self.derivative_at(t))

    def solution(self, stats: IntegratorStats, names: tuple[str, ...], records: list[EventRecord],
                 terminated_by: str | None) -> Solution:
        """The run's Solution, its statistics' event count and simulated time (s) filled in."""
        stats.events = len(records)
        stats.simulated_time = self.t[-1] - self.t[0]
        return Solution(np.asarray(self.t), np.asarray(self.x), stats, names, records,
                        terminated_by, None if self.derivative_at is None else np.asarray(self.xp))


def _step_budget_error(integrator: str, t: float, h: float, steps: int, max_steps: int,
                       t_end: float) -> StepBudgetError:
    """The error of a run stopped at t (s, step h s) after ``steps`` steps short of t_end."""
    return StepBudgetError(t, integrator, h, max_steps,
                           f"{integrator} stopped at t={t:.6g} s (step {h:.3g} s): "
                           f"{steps} steps did not reach t={t_end:.6g} s, "
                           f"over its step budget of {max_steps} steps")


def drive(stepper: Stepper, integrator: str, t_eval: np.ndarray, events: Sequence[Event],
          check: StateCheck, names: tuple[str, ...],
          derivative_at: Callable[[float], np.ndarray] | None = None,
          max_steps: int | None = None,
          progress: Callable[[float], None] | None = None) -> Solution:
    """Run ``stepper`` over ``t_eval`` with outputs, events and checks; returns the Solution.

    ``derivative_at`` (IDA) gives y' at an output time just after ``interpolate`` there.
    More than ``max_steps`` steps raise :class:`StepBudgetError`; ``progress(t)`` is called
    with the time (s) reached after every output.
    The caller sets ``stats.wall_time`` around the whole run (solver set-up included).
    """
    stats = IntegratorStats(integrator)
    outputs = _Outputs(float(t_eval[0]), stepper.x.copy(), check, derivative_at)
    emit, t_out = outputs.emit, outputs.t
    records: list[EventRecord] = []
    terminated_by = None
    own_roots = located_by_stepper(stepper)
    g_old = [] if own_roots else [e.function(stepper.t, stepper.x) for e in events]
    k, n_out = 1, len(t_eval)

    with np.errstate(over="ignore", invalid="ignore"):
        while k < n_out and terminated_by is None:
            t_a = stepper.t
            stepper.advance(float(t_eval[k]))
            t_b, h = stepper.t, stepper.h
            check.step(t_b, stepper.x, h)
            if max_steps is not None and stepper.steps > max_steps:
                raise _step_budget_error(integrator, t_b, h, stepper.steps, max_steps, t_eval[-1])
            stop_at = t_b
            if events:
                if own_roots:
                    found = [(t_b, i) for i in stepper.roots]
                else:
                    g_new = [e.function(t_b, stepper.x) for e in events]
                    found = locate_crossings(events, g_old, g_new, t_a, t_b, stepper.interpolate)
                    g_old = g_new
                for t_r, i in found:
                    x_r = stepper.x.copy() if t_r == t_b else stepper.interpolate(t_r)
                    records.append(EventRecord(t_r, events[i].name, x_r))
                    if events[i].terminal:
                        terminated_by, stop_at = events[i].name, t_r
                        break
            while k < n_out and t_eval[k] <= stop_at:
                t_k = float(t_eval[k])
                x_k = stepper.x.copy() if t_k == t_b else stepper.interpolate(t_k)
                emit(t_k, x_k, h)
                k += 1
            if progress is not None:
                progress(t_out[-1])
            if terminated_by is not None and t_out[-1] < stop_at:
                emit(stop_at, records[-1].state.copy(), h)
    stepper.finish(stats)
    return outputs.solution(stats, names, records, terminated_by)
