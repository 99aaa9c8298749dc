"""Reading a scene file's parsed YAML: typed access whose every mistake is a
:class:`SceneError` naming the file, the key (dotted path) and the value. Shared by
:mod:`youbot_dynamics.sim.scene` and :mod:`youbot_dynamics.sim.scene_contacts`.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from youbot_dynamics import package_share
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model.robot import Robot


class SceneError(UserInputError):
    """A scene file that cannot be used: names the file, the key and the value."""

    def __init__(self, source: str, key: str, problem: str, value: Any = None) -> None:
        self.source, self.key, self.value = source, key, value
        shown = "" if value is None else f" (got {value!r})"
        super().__init__(f"{source}: {key}: {problem}{shown}")


class SceneReader:
    """Typed access to parsed YAML with errors naming the file, the key and the value."""

    def __init__(self, source: str) -> None:
        self.source = source

    def mapping(self, value: Any, key: str, allowed: tuple[str, ...] | None = None) -> Mapping[str, Any]:
        if not isinstance(value, Mapping):
            raise SceneError(self.source, key, "expected a mapping", value)
        if allowed is not None:
            for name in value:
                if name not in allowed:
                    prefix = "" if key == "(top level)" else f"{key}."
                    raise SceneError(self.source, f"{prefix}{name}", "unknown key; known keys: "
                                     + ", ".join(allowed), name)
        return value

    def number(self, value: Any, key: str) -> float:
        if isinstance(value, bool):
            raise SceneError(self.source, key, "expected a number", value)
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise SceneError(self.source, key, "expected a number", value) from None
        if not math.isfinite(number):
            raise SceneError(self.source, key, "expected a finite number", value)
        return number

    def positive(self, value: Any, key: str) -> float:
        number = self.number(value, key)
        if number <= 0:
            raise SceneError(self.source, key, "must be positive", value)
        return number

    def vector3(self, value: Any, key: str) -> np.ndarray:
        if not isinstance(value, (list, tuple)) or len(value) != 3:
            raise SceneError(self.source, key, "expected a list of 3 numbers", value)
        return np.array([self.number(x, f"{key}[{i}]") for i, x in enumerate(value)])

    def joint_list(self, value: Any, key: str, robot: Robot) -> tuple[str, ...]:
        if not isinstance(value, list) or not value:
            raise SceneError(self.source, key, "expected a non-empty list of joint names", value)
        for i, name in enumerate(value):
            self._joint(robot, name, f"{key}[{i}]")
        if len(set(value)) != len(value):
            raise SceneError(self.source, key, "a joint is listed twice", value)
        return tuple(value)

    def joint_values(self, value: Any, key: str, robot: Robot) -> dict[str, float]:
        values = self.mapping(value, key)
        out = {}
        for name, number in values.items():
            self._joint(robot, name, f"{key}.{name}")
            out[name] = self.number(number, f"{key}.{name}")
        return out

    def within_limits(self, robot: Robot, name: str, value: float, key: str) -> None:
        joint = robot.joints[robot.joint_index(name)]
        if not joint.lower - 1e-12 <= value <= joint.upper + 1e-12:
            raise SceneError(self.source, key, f"outside the joint limits [{joint.lower:g}, {joint.upper:g}]", value)

    def _joint(self, robot: Robot, name: Any, key: str) -> None:
        if name not in robot.joint_names:
            raise SceneError(self.source, key, f"not a moving joint of {robot.source} "
                             f"(joints: {', '.join(robot.joint_names)})", name)

    def file(self, value: Any, key: str, scene_path: Path) -> Path:
        """The file ``value`` names, relative to the scene file's folder, else to the
        package share."""
        if value is None or value == "":
            raise SceneError(self.source, key, "missing: give a file path")
        for base in (scene_path.parent, package_share()):
            candidate = (base / str(value)).resolve()
            if candidate.is_file():
                return candidate
        raise SceneError(self.source, key, f"file not found next to the scene ({scene_path.parent}) "
                         f"or in the package share ({package_share()})", value)
