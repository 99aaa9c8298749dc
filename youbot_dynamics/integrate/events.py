"""Hybrid systems: modes with their own dynamics, guards located by root finding, and reset
maps applied at the guards (impacts, stick/slip and contact switches, state machines).

A :class:`Mode` has a right-hand side x' = rhs(t, x) (and optionally its Jacobian) and a
set of :class:`Transition` objects. A transition's guard is a terminal state event (the
zero crossing of ``function(t, x)`` in the given direction); its reset map
``reset(t, x) -> (next_mode, x_new)`` gives the mode and state after the switch (the same
mode for an impact that changes only velocities). :func:`simulate_hybrid` integrates a
mode with one of our integrators until a guard fires, records the switch, applies the
reset and restarts, summing the statistics over the segments.

With ``integrator="ida"`` each mode's ODE is handed to IDA as the residual y' - rhs(t, y)
(no algebraic components), so IDA's figures can be compared with the ODE solvers'.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import (Event, IntegrationError, IntegratorStats,
                                                   Solution, integrate, integrate_dae)

Rhs = Callable[[float, np.ndarray], np.ndarray]
Reset = Callable[[float, np.ndarray], tuple[str, np.ndarray]]


@dataclass(frozen=True)
class Transition:
    """A guard ``function(t, x) = 0`` crossed in ``direction`` (+1 rising, -1 falling, 0
    both) and the reset map applied there: ``reset(t, x) -> (next_mode, x_new)``.
    ``name`` is the kind of the switch in the records. With a ``condition(t, x)`` that is
    false at the crossing, the crossing is passed over: no reset, the mode goes on."""

    name: str
    function: Callable[[float, np.ndarray], float]
    reset: Reset
    direction: int = 0
    condition: Callable[[float, np.ndarray], bool] | None = None

    def event(self, consumed_at: float | None = None) -> Event:
        """The guard as a terminal :class:`Event`. With ``consumed_at`` (s) it reads 0 at
        that time, so the crossing just handled there is not found again on restart."""
        if consumed_at is None:
            return Event(self.name, self.function, self.direction, terminal=True)

        def consumed(t: float, x: np.ndarray, f=self.function) -> float:
            return 0.0 if t == consumed_at else f(t, x)
        return Event(self.name, consumed, self.direction, terminal=True)


@dataclass(frozen=True)
class Mode:
    """One discrete state: x' = rhs(t, x), its Jacobian d rhs/dx (optional, used by the
    implicit integrators) and the transitions that leave it."""

    name: str
    rhs: Rhs
    transitions: tuple[Transition, ...] = ()
    jac: Callable[[float, np.ndarray], np.ndarray] | None = None


@dataclass
class Switch:
    """A guard that fired: time (s), kind (the transition's name), the modes and the states
    just before and just after the reset."""

    time: float
    kind: str
    mode_before: str
    mode_after: str
    state_before: np.ndarray
    state_after: np.ndarray


@dataclass
class HybridSolution:
    """A hybrid run: outputs at the requested times plus both sides of every switch
    (so ``t`` repeats at a switch), the mode of each sample, the switches and the summed
    statistics (``stats.events`` counts the switches)."""

    t: np.ndarray
    x: np.ndarray
    mode: list[str]
    stats: IntegratorStats
    state_names: tuple[str, ...]
    switches: list[Switch] = field(default_factory=list)

    def count(self, kind: str) -> int:
        """How many switches of the given kind occurred."""
        return sum(switch.kind == kind for switch in self.switches)


def segment_times(t_eval: np.ndarray, t_start: float) -> np.ndarray:
    """The output times of a segment starting at t_start: t_start, the requested times
    after it, and the end time."""
    inner = t_eval[(t_eval > t_start) & (t_eval < t_eval[-1])]
    return np.concatenate(([t_start], inner, [t_eval[-1]]))


def integrate_mode(mode: Mode, x0: np.ndarray, times: np.ndarray, integrator: str,
                   options: dict, consumed: str | None = None) -> Solution:
    """One segment in one mode until its end time or the first guard; the guard named
    ``consumed`` fired at the segment's start and is not found there again."""
    events = [tr.event(times[0] if tr.name == consumed else None) for tr in mode.transitions]
    if integrator != "ida":
        return integrate(mode.rhs, x0, times, integrator, jac=mode.jac, events=events,
                         **options)
    rhs, jac = mode.rhs, mode.jac
    identity = np.eye(x0.size)
    dae_jac = None if jac is None else (lambda t, y, yp, cj: cj * identity - jac(t, y))
    dae_options = {k: v for k, v in options.items() if k in ("rtol", "atol", "state_names")}
    return integrate_dae(lambda t, y, yp: yp - rhs(t, y), x0, rhs(times[0], x0), times,
                         algebraic=np.zeros(x0.size, dtype=bool), events=events,
                         jac=dae_jac, **dae_options)


def simulate_hybrid(modes: Sequence[Mode], initial_mode: str, x0, t_eval, integrator: str,
                    *, max_switches: int = 10_000, **options) -> HybridSolution:
    """Simulate a hybrid system from ``initial_mode`` and x0 at t_eval[0] to t_eval[-1] (s).

    ``options`` go to :func:`~youbot_dynamics.integrate.integrators.integrate` (rtol, atol, dt,
    max_step, state_names, bounds, ...; with ``ida`` only rtol, atol and state_names are
    used). ``stats.events`` counts every located guard crossing, including those passed
    over by a false condition; ``switches`` lists the others. More than ``max_switches``
    crossings (chattering, a Zeno run) raise :class:`IntegrationError` naming the time.
    """
    start = time.perf_counter()
    by_name = {mode.name: mode for mode in modes}
    if initial_mode not in by_name:
        raise UserInputError(f"initial mode {initial_mode!r} is not one of {sorted(by_name)}")
    t_eval = np.asarray(t_eval, dtype=float)
    t_end = float(t_eval[-1])
    mode, x = by_name[initial_mode], np.array(x0, dtype=float)
    stats = IntegratorStats(integrator)
    t_out: list[np.ndarray] = []
    x_out: list[np.ndarray] = []
    mode_out: list[str] = []
    switches: list[Switch] = []
    t_now, consumed, crossings = float(t_eval[0]), None, 0
    while t_now < t_end:
        solution = integrate_mode(mode, x, segment_times(t_eval, t_now), integrator, options,
                                  consumed)
        stats += solution.stats
        first = 1 if t_out else 0  # a restart's first sample is already stored
        t_out.append(solution.t[first:])
        x_out.append(solution.x[first:])
        mode_out.extend([mode.name] * (solution.t.size - first))
        if solution.terminated_by is None:
            break
        crossings += 1
        if crossings > max_switches:
            raise IntegrationError(f"more than {max_switches} guard crossings by "
                                   f"t={solution.t[-1]:.9g} s (chattering or a Zeno run?); "
                                   f"last: {solution.terminated_by} in mode {mode.name}")
        transition = next(tr for tr in mode.transitions if tr.name == solution.terminated_by)
        t_now, x_before, consumed = float(solution.t[-1]), solution.x[-1], transition.name
        x = x_before.copy()
        if transition.condition is not None and not transition.condition(t_now, x):
            continue
        next_name, x = transition.reset(t_now, x)
        if next_name not in by_name:
            raise UserInputError(f"transition {transition.name!r} of mode {mode.name!r} "
                                 f"leads to unknown mode {next_name!r}")
        x = np.array(x, dtype=float)
        switches.append(Switch(t_now, transition.name, mode.name, next_name, x_before, x))
        mode = by_name[next_name]
        t_out.append(np.array([t_now]))
        x_out.append(x[None, :])
        mode_out.append(mode.name)
    stats.events = crossings
    stats.wall_time = time.perf_counter() - start
    return HybridSolution(np.concatenate(t_out), np.concatenate(x_out), mode_out, stats,
                          solution.state_names, switches)
