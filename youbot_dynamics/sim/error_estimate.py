"""The error estimate of a run: a companion run beside it, compared state group by group.

Settings of the companion (:func:`companion_spec`) and what the difference means
(:func:`estimate_factor`):

- adaptive methods: the same method at tol / ``COMPANION_FACTOR`` (20; rtol and atol both).
  With a global error e(tol) ~ C tol^a (a <= 1 for a method that keeps tolerance
  proportionality), the companion's own error is 20^-a e, so |y - y_c| lies within
  (1 +- 20^-a) e: the difference is the estimate (factor 1).
- fixed-step methods and the constraint steppers: the same run at dt / 2 (Richardson).
  With y_h = y + C h^p + O(h^(p+1)) for a method of order p (the registry's ``order``):
  y_h - y_{h/2} = C h^p (1 - 2^-p), so the error of the run at h is
  C h^p = (y_h - y_{h/2}) 2^p / (2^p - 1) (factor 2 for p = 1, 16/15 for rk4).

Groups, each in its unit (:func:`group_differences`): joint angles (rad; m for a prismatic
joint), joint rates (rad/s), free-body positions (m, the distance between the two centres),
free-body orientations (rad, the angle of R^T R_c), base position (m) and base yaw (rad).
Each is reported as the largest difference over the output grid and at the end, times the
factor. Scenes with contact add the event counts of both runs and the largest difference of
the times of matching events (the k-th event of each pair and kind in both runs), times the
factor.

Where the companion runs and how it is fed: :mod:`youbot_dynamics.sim.companion`.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Sequence

import numpy as np

from youbot_dynamics.integrate.registry import integrator_entry
from youbot_dynamics.integrate.statistics import IntegratorStats
from youbot_dynamics.scene.schema import IntegratorSpec
from youbot_dynamics.sim.model import SimModel
from youbot_dynamics.sim.state import ContactEvent

#: The companion of an adaptive run solves at tol / COMPANION_FACTOR.
COMPANION_FACTOR = 20.0
#: Each group: (name, unit).
GROUPS = (("joint_angles", "rad"), ("joint_rates", "rad/s"), ("positions", "m"), ("orientations", "rad"),
          ("base_position", "m"), ("base_yaw", "rad"))


def companion_spec(spec: IntegratorSpec, factor: float = COMPANION_FACTOR) -> IntegratorSpec:
    """The companion's settings: dt / 2 for a fixed step, else tol, rtol and atol / ``factor``."""
    if not integrator_entry(spec.method).adaptive:
        return replace(spec, dt=spec.dt / 2.0)
    return replace(spec, rtol=spec.rtol / factor, atol=None if spec.atol is None else spec.atol / factor,
                   tol=None if spec.tol is None else spec.tol / factor)


def estimate_factor(method: str) -> float:
    """What |y - y_companion| is multiplied by: 2^p / (2^p - 1) for a fixed-step method of
    order p (Richardson), 1 for an adaptive one (module docstring)."""
    entry = integrator_entry(method)
    if entry.adaptive:
        return 1.0
    return 2.0 ** entry.order / (2.0 ** entry.order - 1.0)


def describe_rule(method: str, factor: float = COMPANION_FACTOR) -> str:
    """One line: how the estimate of a run with ``method`` is made."""
    entry = integrator_entry(method)
    if entry.adaptive:
        return f"companion at tol/{factor:g}, estimate |y - y_c|"
    return (f"Richardson: companion at dt/2, order {entry.order}, estimate |y_h - y_h/2| x "
            f"{estimate_factor(method):.4g}")


def rotation_angle(r1: np.ndarray, r2: np.ndarray) -> np.ndarray:
    """The angle (rad) of r1^T r2 for stacks of rotation matrices (..., 3, 3)."""
    rel = np.einsum("...ji,...jk->...ik", r1, r2)
    skew = np.stack([rel[..., 2, 1] - rel[..., 1, 2], rel[..., 0, 2] - rel[..., 2, 0],
                     rel[..., 1, 0] - rel[..., 0, 1]], axis=-1)
    return np.arctan2(0.5 * np.linalg.norm(skew, axis=-1), 0.5 * (np.trace(rel, axis1=-2, axis2=-1) - 1.0))


def views_of_states(model: SimModel, x: np.ndarray) -> dict[str, np.ndarray]:
    """What the groups compare, from states (k, n): ``q``, ``v`` (k, nv), free bodies'
    ``position`` (k, nb, 3) and ``rotation`` (k, nb, 3, 3), ``base`` pose (k, 3: x, y, yaw);
    a key only where the scene has it."""
    x = np.atleast_2d(x)
    views = {key: x[:, model.block(key)] for key in ("q", "v", "base") if model.block(key).stop > model.block(key).start}
    if model.body_names:
        motion = model.body_motion(x)
        views.update(position=motion["position"], rotation=motion["rotation"])
    return views


def views_of_snapshots(snapshots: Sequence) -> dict[str, np.ndarray]:
    """:func:`views_of_states` from :class:`~youbot_dynamics.sim.engine.Snapshot` s."""
    first = snapshots[0]
    views = {key: np.array([getattr(s, key) for s in snapshots]) for key in ("q", "v") if getattr(first, key).size}
    if first.bodies:
        poses = np.array([list(s.bodies.values()) for s in snapshots])
        views.update(position=poses[:, :, :3, 3], rotation=poses[:, :, :3, :3])
    if first.base is not None:
        views["base"] = np.array([s.base[:3] for s in snapshots])
    return views


def group_differences(model: SimModel, x: np.ndarray, x_companion: np.ndarray) -> dict[str, np.ndarray]:
    """:func:`view_differences` of two state arrays (k, n) on the same grid."""
    return view_differences(views_of_states(model, x), views_of_states(model, x_companion))


def view_differences(views: dict[str, np.ndarray], companion: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Per state group present, its difference (k,) at each of the k instants: the
    largest component (joints, base position), the largest distance (positions, m) or
    rotation angle (orientations, rad) over the free bodies, the base's yaw (rad, wrapped)."""
    out: dict[str, np.ndarray] = {}
    for name, key in (("joint_angles", "q"), ("joint_rates", "v")):
        if key in views:
            out[name] = np.max(np.abs(views[key] - companion[key]), axis=1)
    if "position" in views:
        out["positions"] = np.max(np.linalg.norm(views["position"] - companion["position"], axis=-1), axis=1)
        out["orientations"] = np.max(rotation_angle(views["rotation"], companion["rotation"]), axis=1)
    if "base" in views:
        base, base_c = views["base"], companion["base"]
        out["base_position"] = np.max(np.abs(base[:, :2] - base_c[:, :2]), axis=1)
        out["base_yaw"] = np.abs(np.angle(np.exp(1j * (base[:, 2] - base_c[:, 2]))))
    return out


def event_time_difference(events: Sequence[ContactEvent], companion: Sequence[ContactEvent]) -> float | None:
    """The largest |t - t_c| (s) over matching events: the k-th event of each (pair, kind)
    in both lists; None when no event matches."""
    def by_key(items: Sequence[ContactEvent]) -> dict[tuple[str, str], list[float]]:
        keyed: dict[tuple[str, str], list[float]] = {}
        for event in items:
            keyed.setdefault((event.pair, event.kind), []).append(event.time)
        return keyed
    mine, theirs = by_key(events), by_key(companion)
    gaps = [abs(a - b) for key, times in mine.items() for a, b in zip(times, theirs.get(key, ()))]
    return max(gaps) if gaps else None


@dataclass(frozen=True)
class GroupError:
    """One state group's estimated error in ``unit``: largest over the output grid, at the end."""

    group: str
    unit: str
    max_over_grid: float
    at_end: float


@dataclass(frozen=True)
class ErrorEstimate:
    """A run's estimated error (module docstring): per group, the events (counts of the run
    and of its companion, the largest event-time difference times the factor, s; None
    without contact), how it was made and what the companion cost (its statistics, CPU
    time in s, where it ran)."""

    rule: str
    companion: str
    groups: tuple[GroupError, ...]
    events: int | None
    companion_events: int | None
    event_time: float | None
    companion_stats: IntegratorStats | None
    companion_cpu_time: float
    where: str

    @property
    def largest(self) -> dict[str, float]:
        """Group name -> its largest estimated error over the grid."""
        return {g.group: g.max_over_grid for g in self.groups}

    def as_dict(self) -> dict[str, Any]:
        """Plain data for JSON (units in the group entries; times s)."""
        return {"rule": self.rule, "companion": self.companion, "where": self.where,
                "groups": {g.group: {"unit": g.unit, "max_over_grid": g.max_over_grid, "at_end": g.at_end}
                           for g in self.groups},
                "events": None if self.events is None else {"count": self.events,
                                                            "companion_count": self.companion_events,
                                                            "max_time_difference": self.event_time},
                "companion_cost": {"cpu_time": self.companion_cpu_time,
                                   **({} if self.companion_stats is None else self.companion_stats.as_dict())}}

    def values(self) -> dict[str, float | int | str]:
        """Flat key/value pairs (/diagnostics): ``error_estimate.<group>`` (largest over the
        grid so far, in the group's unit), ``.events`` pair, ``.event_time`` (s), the cost."""
        out: dict[str, float | int | str] = {"error_estimate.rule": self.rule, "error_estimate.where": self.where}
        out.update({f"error_estimate.{g.group} ({g.unit})": g.max_over_grid for g in self.groups})
        if self.events is not None:
            out["error_estimate.events"] = f"{self.events} (companion {self.companion_events})"
            out["error_estimate.event_time (s)"] = "none" if self.event_time is None else self.event_time
        out["error_estimate.companion_cpu_time (s)"] = self.companion_cpu_time
        return out

    def summary(self) -> list[str]:
        """Readable lines for the command line."""
        lines = [f"error estimate ({self.rule}; companion {self.companion}, {self.where}):"]
        lines += [f"  {g.group:14s} max over the grid {g.max_over_grid:.3e} {g.unit}, at the end {g.at_end:.3e} {g.unit}"
                  for g in self.groups]
        if self.events is not None:
            timing = "no matching events" if self.event_time is None else f"event times within {self.event_time:.3e} s"
            lines.append(f"  events         {self.events} (companion {self.companion_events}), {timing}")
        cost = "" if self.companion_stats is None else f"{self.companion_stats.summary()}, "
        lines.append(f"  companion cost {cost}CPU {self.companion_cpu_time:.3f} s")
        return lines


def estimate_from(model: SimModel, x: np.ndarray, x_companion: np.ndarray,
                  events: Sequence[ContactEvent] | None, companion_events: Sequence[ContactEvent] | None,
                  stats: IntegratorStats | None, cpu_time: float, where: str) -> ErrorEstimate:
    """The estimate from the run's and the companion's states on the same grid (k, n) and
    their contact events (None without contact)."""
    diffs = group_differences(model, x, x_companion)
    return make_estimate(model.integrator, {k: float(np.max(d)) for k, d in diffs.items()},
                         {k: float(d[-1]) for k, d in diffs.items()}, events, companion_events, stats, cpu_time, where)


def make_estimate(spec: IntegratorSpec, largest: dict[str, float], last: dict[str, float],
                  events: Sequence[ContactEvent] | None, companion_events: Sequence[ContactEvent] | None,
                  stats: IntegratorStats | None, cpu_time: float, where: str) -> ErrorEstimate:
    """The estimate of a run with settings ``spec`` from its raw differences per group
    (largest over the grid, at the end) and the events: each times :func:`estimate_factor`."""
    factor, units = estimate_factor(spec.method), dict(GROUPS)
    groups = tuple(GroupError(name, units[name], factor * largest[name], factor * last[name]) for name in largest)
    event_time = None
    if events is not None and companion_events is not None:
        gap = event_time_difference(events, companion_events)
        event_time = None if gap is None else factor * gap
    return ErrorEstimate(describe_rule(spec.method), companion_spec(spec).describe(), groups,
                         None if events is None else len(events),
                         None if companion_events is None else len(companion_events), event_time,
                         stats, cpu_time, where)
