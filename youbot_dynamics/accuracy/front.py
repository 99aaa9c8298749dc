"""The work-precision front of a sweep, and writing it into the scene file.

:func:`pareto_front`: the points of a sweep that no other point beats on both error and
counted work (ties: registry order). :func:`write_front` stores them as the scene's
``front`` block (read back by :mod:`youbot_dynamics.scene.front`, which the ``accuracy``
target chooses from), replacing an earlier one and leaving every other line of the file
as it was.
"""
from __future__ import annotations

from pathlib import Path
from typing import Sequence

from youbot_dynamics.accuracy.work_precision import Reference, SweepPoint, block_end, replace_file, yaml_scalar
from youbot_dynamics.integrate.registry import REGISTRY
from youbot_dynamics.scene.reader import SceneError, read_yaml
from youbot_dynamics.scene.schema import Scene

#: The comment on the ``front`` key.
FRONT_NOTE = "written by work-precision --write-back: the sweep's points no other beats on error and work"


def pareto_front(points: Sequence[SweepPoint]) -> list[SweepPoint]:
    """The successful points with counted work that no other such point beats on both
    error and work, by increasing work (equal work: the smaller error; then registry order)."""
    order = list(REGISTRY)
    good = sorted((p for p in points if p.failure is None and p.work is not None),
                  key=lambda p: (p.work, p.q_error, order.index(p.integrator)))
    front: list[SweepPoint] = []
    for point in good:
        if not front or point.q_error < front[-1].q_error:
            front.append(point)
    return front


def front_lines(reference: Reference, front: Sequence[SweepPoint]) -> list[str]:
    """The scene file's ``front`` block (scene/front.py's form)."""
    unit = "rad" if reference.ee_position.size else "m"
    measure = reference.measure.replace(' (rad)', '').replace(' (m)', '')
    measure = measure if "at the end" in measure else f"{measure} at the end"
    lines = [f"front:   # {FRONT_NOTE}",
             f"  measure: \"{measure} ({unit})\"",
             f"  reference: \"{reference.spec.describe()}\"",
             "  points:"]
    for p in front:
        spec = p.spec
        settings = f"dt: {short(spec.dt)}" if spec.dt is not None else \
            f"rtol: {short(spec.rtol)}, atol: {short(spec.atol)}"
        lines.append(f"    - {{method: {p.integrator}, {settings}, error: {short(p.q_error, 4)}, "
                     f"work: {short(p.work, 12)}}}")
    return lines


def short(value: float, digits: int = 6) -> str:
    """``value`` to ``digits`` significant digits, as YAML reads a float back."""
    return yaml_scalar(float(f"{float(value):.{digits}g}"))


def with_front_block(text: str, lines: Sequence[str]) -> str:
    """The scene file's ``text`` with its top-level ``front`` block replaced by ``lines``
    (appended when it has none)."""
    rows = text.splitlines()
    head = next((i for i, line in enumerate(rows) if line.startswith("front:")), None)
    if head is None:
        return "\n".join(rows + list(lines)) + "\n"
    return "\n".join(rows[:head] + list(lines) + rows[block_end(rows, head):]) + "\n"


def write_front(path: str | Path, reference: Reference, points: Sequence[SweepPoint]) -> str:
    """Store the sweep's front in the scene file at ``path`` after checking that the edited
    file reads back as the same scene with that front; the file is replaced in one step.
    Returns the new text."""
    path = Path(path)
    text = path.read_text(encoding="utf-8")
    edited = with_front_block(text, front_lines(reference, pareto_front(points)))
    before, after = (read_yaml(t.encode("utf-8"), str(path)) for t in (text, edited))
    if {k: v for k, v in before.items() if k != "front"} != {k: v for k, v in after.items() if k != "front"}:
        raise SceneError(str(path), "front", "the file could not be edited safely")
    Scene.from_dict(after, str(path), path.parent)  # still a valid scene, its front readable
    replace_file(path, edited)
    return edited

