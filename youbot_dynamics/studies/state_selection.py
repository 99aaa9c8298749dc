"""Dynamic state selection: the dummy derivatives chosen again when their pivot fades.

The static selection (dummy_derivatives.py) holds while its pivots stay away from zero: the
Cartesian pendulum chosen with y' dummy (states x, u) breaks where y passes 0. Here the run
is split into segments. In each, a terminal state event watches every selection level of
one equation: g = |J_chosen| - HYSTERESIS max |J_other| over that equation's candidates,
the Jacobian entries in closed form along the trajectory. When g falls through zero the
segment ends, every variable is evaluated there (the generated observed expressions), those
values become the start values of the model's declared variables, and the pipeline runs
again from that time: the new selection takes the other candidate (its pivot is now at
least 1 / HYSTERESIS times larger, so the choice does not flip back at once). Levels of
several equations are not watched: in the pendulum they follow the single-equation level.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import sympy as sp

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import Event, IntegratorStats, Solution
from youbot_dynamics.studies.equations import T, EquationModel
from youbot_dynamics.studies.pipeline import PipelineResult, run_pipeline, simulate

#: A new selection is made when the chosen pivot falls below this fraction of the largest
#: other candidate's entry.
HYSTERESIS = 0.5


@dataclass
class Segment:
    """One stretch of a run under one selection: its pipeline result and solution."""

    result: PipelineResult
    solution: Solution

    @property
    def states(self) -> list[str]:
        return self.result.ode.state_names


@dataclass
class ReselectedRun:
    """A run over several selections, and its merged statistics."""

    segments: list[Segment]
    stats: IntegratorStats

    def switches(self) -> list[str]:
        """Each change of selection: time (s), old states -> new states."""
        return [f"t = {b.solution.t[0]:.6g} s: states {', '.join(a.states)} -> "
                f"{', '.join(b.states)}" for a, b in zip(self.segments, self.segments[1:])]

    def values(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """Times (s) and values of the variable ``name`` over all segments (a state or an
        observed variable), the switching times once."""
        times, values = [], []
        for k, segment in enumerate(self.segments):
            ode, solution = segment.result.ode, segment.solution
            start = 1 if k else 0
            for t, x in zip(solution.t[start:], solution.x[start:]):
                states = dict(zip(ode.state_names, x))
                value = states[name] if name in states else ode.observe(t, x)[name]
                times.append(t)
                values.append(float(value))
        return np.array(times), np.array(values)


def pivot_margin(result: PipelineResult) -> Event | None:
    """The terminal event g = |J_chosen| - HYSTERESIS max |J_other| (minimum over the
    single-equation levels), falling; None when no level has one equation and two or more
    candidates."""
    ode = result.ode
    closed = {sp.Symbol(k): v for k, v in ode.observed.items()}
    margins = []
    for level in result.dummies.levels:
        if len(level.equations) != 1 or len(level.candidates) < 2:
            continue
        entries = {c: sp.sympify(e).xreplace(closed) for c, e in
                   zip(level.candidates, level.jacobian[0])}
        chosen = sp.Abs(entries[level.selected[0]])
        others = [sp.Abs(e) for c, e in entries.items() if c != level.selected[0]]
        margins.append(chosen - HYSTERESIS * sp.Max(*others))
    if not margins:
        return None
    parameters = [sp.Symbol(k) for k in result.model.parameters]
    values = list(result.model.parameters.values())
    function = sp.lambdify([T, *map(sp.Symbol, ode.state_names), *parameters],
                           sp.Min(*margins), modules="numpy", dummify=True)
    return Event("state selection", lambda t, x: float(function(t, *x, *values)),
                 direction=-1, terminal=True)


def simulate_with_reselection(model: EquationModel, integrator: str = "cvode_bdf",
                              tol: float = 1e-6, n_outputs: int = 201, dt: float | None = None,
                              max_steps: int | None = None,
                              max_segments: int = 100) -> ReselectedRun:
    """Run the pipeline and simulate over [model.t0, model.t_end] (s) with ``n_outputs``
    equally spaced outputs, choosing the states again wherever a pivot fades (see the
    module docstring). A run that needs more than ``max_segments`` selections is a
    UserInputError at the time it would change (1: the static selection)."""
    times = np.linspace(model.t0, model.t_end, n_outputs)
    segments: list[Segment] = []
    current = model
    while True:
        result = run_pipeline(current)
        event = pivot_margin(result)
        remaining = times[times > current.t0]
        solution = simulate(result, integrator, tol, dt=dt, max_steps=max_steps,
                            t_eval=np.concatenate(([current.t0], remaining)),
                            events=() if event is None else (event,))
        segments.append(Segment(result, solution))
        if solution.terminated_by is None:
            break
        if len(segments) >= max_segments:
            raise UserInputError(
                f"model {model.name}: at t = {solution.t[-1]:.6g} s the state selection "
                f"({', '.join(result.ode.state_names)}) must change (a pivot fades), and "
                f"only {max_segments} selection(s) are allowed")
        t, x = float(solution.t[-1]), solution.x[-1]
        found = {**result.ode.observe(t, x), **dict(zip(result.ode.state_names, x))}
        current = replace(current | {k: float(v) for k, v in found.items()
                                     if k in current.variables}, t0=t)
    stats = replace(segments[0].solution.stats)
    for segment in segments[1:]:
        stats += segment.solution.stats
    return ReselectedRun(segments, stats)
