"""A scene's stored work-precision front and the accuracy target that chooses from it.

``work-precision --write-back`` stores the front (the sweep's points that no other point
beats on both error and counted work) in the scene file; ``accuracy: E`` in the scene (or
``simulate --accuracy E``) then runs the cheapest stored point whose error is at most E,
and says which and why. Nothing is swept at run time::

    accuracy: 1.0e-6              # the error to meet, in the front's unit
    front:                        # written by work-precision --write-back
      measure: max |q - q_ref| at the end (rad)
      reference: dop853 rtol=1e-12 atol=1e-14
      points:                     # integrator, its dt or rtol/atol, error, counted work
        - {method: dop853, rtol: 1.0e-9, atol: 1.0e-11, error: 1.7e-07, work: 5411.0}
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Mapping

from youbot_dynamics.integrate.registry import integrator_entry
from youbot_dynamics.scene.reader import SceneError, SceneReader


@dataclass(frozen=True)
class FrontPoint:
    """One stored setting: integrator, dt (s) or rtol/atol, its error (the front's
    measure) and counted work (rhs evaluations + Jacobians x state dimension)."""

    method: str
    error: float
    work: float
    dt: float | None = None
    rtol: float | None = None
    atol: float | None = None

    def settings(self) -> dict[str, Any]:
        """The integrator keys that select this point."""
        if self.dt is not None:
            return {"method": self.method, "dt": self.dt}
        return {"method": self.method, "rtol": self.rtol, "atol": self.atol}


@dataclass(frozen=True)
class Front:
    """The stored front: what its error measures (with the unit in brackets), the reference
    it was measured against, and its points by increasing work."""

    measure: str
    reference: str
    points: tuple[FrontPoint, ...]

    @property
    def unit(self) -> str:
        """The unit of the error: what the measure gives in its last brackets."""
        return self.measure.rsplit("(", 1)[-1].rstrip(")") if "(" in self.measure else ""

    def cheapest_meeting(self, target: float) -> tuple[FrontPoint | None, str]:
        """(the point of least work whose error is at most ``target``, why); None and the
        reason when no stored point meets it."""
        meeting = [p for p in self.points if p.error <= target]
        if not meeting:
            best = min(self.points, key=lambda p: p.error)
            return None, (f"no stored point meets {target:g} {self.unit}: the most accurate errs {best.error:.3g} "
                          "(sweep finer with work-precision --write-back)")
        point = min(meeting, key=lambda p: (p.work, p.error))
        cheaper = [p for p in self.points if p.work < point.work]
        beyond = f"; the next cheaper point errs {max(cheaper, key=lambda p: p.work).error:.3g}" if cheaper else ""
        return point, (f"accuracy {target:g} {self.unit}: the cheapest stored point that meets it (error "
                       f"{point.error:.3g}, work {point.work:.6g}{beyond}; front of {len(self.points)} points, "
                       f"{self.measure}, reference {self.reference})")


def read_front(reader: SceneReader, value: Any) -> Front | None:
    """The ``front`` key (module docstring), or None when absent."""
    if value is None:
        return None
    data = reader.mapping(value, "front", ("measure", "reference", "points"))
    rows = data.get("points")
    if not isinstance(rows, list) or not rows:
        raise SceneError(reader.source, "front.points", "a non-empty list of points", rows)
    points = []
    for i, row in enumerate(rows):
        key = f"front.points[{i}]"
        item = reader.mapping(row, key, ("method", "dt", "rtol", "atol", "error", "work"))
        method = item.get("method")
        try:
            integrator_entry(method)
        except Exception as error:  # noqa: BLE001 - the registry's message names the known ones
            raise SceneError(reader.source, f"{key}.method", str(error)) from None
        numbers = {name: reader.positive(item[name], f"{key}.{name}") for name in ("dt", "rtol", "atol", "work")
                   if name in item}
        error = reader.number(item.get("error"), f"{key}.error")
        if not (math.isfinite(error) and error >= 0):
            raise SceneError(reader.source, f"{key}.error", "a non-negative finite number", error)
        points.append(FrontPoint(method, error, numbers.pop("work", math.inf), **numbers))
    return Front(str(data.get("measure", "")), str(data.get("reference", "")),
                 tuple(sorted(points, key=lambda p: p.work)))


def read_accuracy(reader: SceneReader, data: Mapping[str, Any]) -> tuple[float | None, Front | None]:
    """The ``accuracy`` target (positive, the front's unit) and the stored ``front``; an
    accuracy without a front is an error naming the command that stores one."""
    front = read_front(reader, data.get("front"))
    if data.get("accuracy") is None:
        return None, front
    target = reader.positive(data["accuracy"], "accuracy")
    if front is None:
        raise SceneError(reader.source, "accuracy", "needs the scene's stored front: run `youbot-dynamics "
                         f"work-precision --scene {reader.source} --write-back` first", target)
    return target, front


def with_accuracy(scene, target: float):
    """The same scene running the cheapest stored front point that meets ``target``
    (the front's unit); ``scene.accuracy_choice`` says which and why. SceneError when the
    scene has no stored front or no point meets the target."""
    if scene.front is None:
        raise SceneError(scene.source, "accuracy", "needs the scene's stored front: run `youbot-dynamics "
                         f"work-precision --scene {scene.source} --write-back` first", target)
    point, why = scene.front.cheapest_meeting(target)
    if point is None:
        raise SceneError(scene.source, "accuracy", why, target)
    settings = point.settings()
    integrator = dataclasses.replace(scene.integrator, method=settings["method"], dt=settings.get("dt"),
                                     rtol=settings.get("rtol", scene.integrator.rtol),
                                     atol=settings.get("atol", scene.integrator.atol), tol=None)
    return dataclasses.replace(scene, integrator=integrator, accuracy=target,
                               accuracy_choice=f"{integrator.describe()}: {why}")
