"""How good is the error estimate? Estimate against true error, integrator by integrator.

For a scene and an integrator setting, :func:`scene_rows` makes the run with its error
estimate (:mod:`youbot_dynamics.sim.error_estimate`, the product's own path: the companion
in a worker process) and its true error against a reference run made independently at a
much tighter setting (:data:`REFERENCE`: DOP853 at rtol 1e-12 for ODE scenes, the scene's
constraint stepper at dt / ``STEPPER_REFINEMENT`` for constraint contact), per state group
(largest difference over the output grid) and for the contact events' times. The
reference's own error is bounded by a second reference (ten times looser, or at twice the
step): a true error below ten times that bound is not resolved (``resolved`` False) and is
left out of the verdict. :func:`ode_rows` does the same for a bare ODE (the elastic
pendulum) through ``integrate``.

Acceptance (:func:`within`): estimate / true in [1/3, 3].
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Callable, Sequence

import numpy as np

from youbot_dynamics.accuracy.work_precision import REFERENCE_RTOL, STEPPER_REFINEMENT, spec_for
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import IntegrationError, integrate
from youbot_dynamics.integrate.registry import integrator_entry
from youbot_dynamics.scene.schema import IntegratorSpec, Scene
from youbot_dynamics.sim import companion, engine
from youbot_dynamics.sim.build import compile
from youbot_dynamics.sim.error_estimate import (companion_spec, estimate_factor, event_time_difference,
                                                group_differences)

#: The reference of an ODE scene.
REFERENCE = IntegratorSpec("dop853", rtol=REFERENCE_RTOL, atol=1e-2 * REFERENCE_RTOL, energy_tolerance=math.inf)
#: Acceptance: the estimate within this factor of the true error.
FACTOR = 3.0
#: A true error below RESOLUTION x the reference's own error is not resolved.
RESOLUTION = 10.0


@dataclass(frozen=True)
class CheckRow:
    """One (case, setting, quantity): estimate and true error in ``unit``; ``resolved``:
    the true error is at least RESOLUTION x the reference's own error; ``failure``: why
    the run failed (then no numbers)."""

    case: str
    integrator: str
    setting: str
    quantity: str
    unit: str
    estimate: float
    true: float
    resolved: bool
    failure: str | None = None

    @property
    def ratio(self) -> float:
        """estimate / true (nan when either is missing or the true error is 0)."""
        return self.estimate / self.true if self.true > 0 else math.nan

    @property
    def within(self) -> bool:
        """Whether the estimate lies within FACTOR of the true error."""
        return 1.0 / FACTOR <= self.ratio <= FACTOR


def resolved(true: float, own: float) -> bool:
    """Whether a true error is resolved: above 0 and at least RESOLUTION x the reference's
    own error ``own``."""
    return true > 0 and true >= RESOLUTION * own


def _reference_specs(scene: Scene) -> tuple[IntegratorSpec, IntegratorSpec]:
    """(reference, the looser run that bounds its error)."""
    spec = scene.integrator
    if integrator_entry(spec.method).kind == "stepper":
        tight = replace(spec, dt=spec.dt / STEPPER_REFINEMENT, energy_tolerance=math.inf)
        return tight, replace(tight, dt=2 * tight.dt)
    return REFERENCE, replace(REFERENCE, rtol=10 * REFERENCE.rtol, atol=10 * REFERENCE.atol)


def reference_run(scene: Scene) -> tuple[engine.SimulationResult, dict[str, float], float]:
    """(the reference run, its own error per group (largest over the grid), its own
    event-time error, s)."""
    runs = [engine.run(compile(scene, spec)) for spec in _reference_specs(scene)]
    model = compile(scene, runs[0].integrator)
    own = {name: float(np.max(diff)) for name, diff in group_differences(model, runs[0].x, runs[1].x).items()}
    gap = event_time_difference(runs[0].contact_events, runs[1].contact_events)
    return runs[0], own, 0.0 if gap is None else gap


def scene_rows(scene: Scene, method: str, values: Sequence[float],
               reference: tuple[engine.SimulationResult, dict[str, float], float]) -> list[CheckRow]:
    """The rows of ``method`` at each of ``values`` (dt or rtol) on ``scene``."""
    ref, own, own_events = reference
    rows: list[CheckRow] = []
    for value in values:
        spec = spec_for(method, value)
        model = compile(scene, spec)
        setting = spec.describe()
        try:
            result = companion.run(model, error_estimate=True)
        except (IntegrationError, UserInputError) as error:
            rows.append(CheckRow(scene.name, method, setting, "-", "-", math.nan, math.nan, False, str(error)[:80]))
            continue
        estimate = result.error_estimate
        true = group_differences(model, result.x, ref.x)
        for group in estimate.groups:
            error = float(np.max(true[group.group]))
            rows.append(CheckRow(scene.name, method, setting, group.group, group.unit, group.max_over_grid, error,
                                 resolved(error, own[group.group])))
        if estimate.events is not None:
            gap = event_time_difference(result.contact_events, ref.contact_events)
            if gap is not None and estimate.event_time is not None:
                rows.append(CheckRow(scene.name, method, setting, f"event times ({len(result.contact_events)} vs "
                                     f"{len(ref.contact_events)} ref)", "s", estimate.event_time, gap,
                                     resolved(gap, own_events) and len(result.contact_events) == len(ref.contact_events)))
    return rows


def ode_rows(case: str, rhs: Callable, x0: np.ndarray, times: np.ndarray, method: str, values: Sequence[float],
             reference: np.ndarray, reference_error: float, groups: dict[str, tuple[slice, str]],
             jac: Callable | None = None) -> list[CheckRow]:
    """A bare ODE x' = rhs(t, x): the run and its companion (tol / 20 or dt / 2, as the
    product's estimate) through ``integrate``, against ``reference`` states on ``times``
    whose own error is ``reference_error``; ``groups``: name -> (components, unit)."""
    rows = []
    for value in values:
        spec = spec_for(method, value)
        companion = companion_spec(spec)
        try:
            x, x_c = (integrate(rhs, x0, times, method, dt=s.dt, rtol=s.rtol, atol=s.atol, jac=jac,
                                n_positions=len(x0) // 2).x for s in (spec, companion))
        except (IntegrationError, UserInputError) as error:
            rows.append(CheckRow(case, method, spec.describe(), "-", "-", math.nan, math.nan, False, str(error)[:80]))
            continue
        factor = estimate_factor(method)
        for name, (part, unit) in groups.items():
            true = float(np.max(np.abs(x[:, part] - reference[:, part])))
            rows.append(CheckRow(case, method, spec.describe(), name, unit,
                                 factor * float(np.max(np.abs(x[:, part] - x_c[:, part]))), true,
                                 resolved(true, reference_error)))
    return rows


def markdown(rows: Sequence[CheckRow]) -> str:
    """The rows as a markdown table with a closing count of those within FACTOR."""
    lines = ["| case | integrator | setting | quantity | estimate | true | estimate / true |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        if r.failure is not None:
            lines.append(f"| {r.case} | {r.integrator} | {r.setting} | failed: {r.failure} | | | |")
            continue
        mark = "" if r.resolved else " (not resolved)"
        lines.append(f"| {r.case} | {r.integrator} | {r.setting} | {r.quantity} ({r.unit}) | {r.estimate:.3g} "
                     f"| {r.true:.3g}{mark} | {r.ratio:.3g} |")
    judged = [r for r in rows if r.failure is None and r.resolved]
    inside = sum(r.within for r in judged)
    lines += ["", f"{inside} of {len(judged)} resolved rows within a factor {FACTOR:g} of the true error."]
    return "\n".join(lines) + "\n"


def summary_markdown(rows: Sequence[CheckRow]) -> str:
    """One line per (case, integrator): its settings, the range of estimate / true over its
    resolved rows (every group and the event times) and how many lie within FACTOR."""
    lines = ["| case | integrator | settings | estimate / true (min - max) | within a factor 3 |", "|---|---|---|---|---|"]
    for key in dict.fromkeys((r.case, r.integrator) for r in rows):
        mine = [r for r in rows if (r.case, r.integrator) == key]
        settings = ", ".join(dict.fromkeys(r.setting.split(" ", 1)[1].split(" atol")[0] for r in mine))
        judged = [r.ratio for r in mine if r.failure is None and r.resolved]
        failed = sum(r.failure is not None for r in mine)
        span = f"{min(judged):.2f} - {max(judged):.2f}" if judged else "-"
        note = f" ({failed} failed)" if failed else ""
        lines.append(f"| {key[0]} | {key[1]} | {settings} | {span} | "
                     f"{sum(1 / FACTOR <= x <= FACTOR for x in judged)} of {len(judged)}{note} |")
    return "\n".join(lines) + "\n"
