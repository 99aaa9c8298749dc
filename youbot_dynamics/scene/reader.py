"""Reading a scene: :func:`read_yaml` parses a scene file with bounded work, and
:class:`SceneReader` gives typed access to the parsed data (from a file or a Python
mapping) whose every mistake is a :class:`SceneError` naming the source, the key (dotted
path) and the value. Shared by :mod:`youbot_dynamics.scene.schema` and
:mod:`youbot_dynamics.scene.contacts`.

Uncertain parameters: a number may be written ``"0.8 ± 0.2"`` (or ``"0.8 +- 0.2"``), a
nominal value and one standard deviation (sigma > 0). The reader returns the nominal value
(the simulation runs with it) and records the parameter in ``uncertain`` under its key
(``friction.joints.pivot.damping``); ``values`` (key -> number) replaces the nominal
value of such keys, which is how a sample of the parameters is read
(accuracy/scene_uncertainty.py).
"""
from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import yaml

from youbot_dynamics import package_share
from youbot_dynamics.errors import UserInputError
from youbot_dynamics.model import limits
from youbot_dynamics.model.robot import Robot


class SceneError(UserInputError):
    """A scene that cannot be used: names its source (file or label), the key and the value."""

    def __init__(self, source: str, key: str, problem: str, value: Any = None) -> None:
        self.source, self.key, self.value = source, key, value
        if isinstance(value, np.generic):   # a numpy scalar reads as the plain number
            value = value.item()
        shown = "" if value is None else f" (got {value!r})"
        super().__init__(f"{source}: {key}: {problem}{shown}")


#: ``value ± sigma`` (also ``+-``): the two numbers, each as float() reads it.
UNCERTAIN_NUMBER = re.compile(r"^\s*(\S+)\s*(?:±|\+-)\s*(\S+)\s*$")


def is_uncertain(value: Any) -> bool:
    """Whether ``value`` is written as an uncertain number (a string with ± or +-)."""
    return isinstance(value, str) and ("±" in value or "+-" in value)


class _YAMLTooLarge(Exception):
    """A YAML document beyond the bounds of youbot_dynamics.model.limits."""


class _BoundedLoader(yaml.SafeLoader):
    """PyYAML's safe loader that refuses more than MAX_YAML_ALIASES aliases."""

    def __init__(self, stream: str) -> None:
        super().__init__(stream)
        self.aliases = 0

    def compose_node(self, parent: yaml.Node | None, index: Any) -> yaml.Node:
        if self.check_event(yaml.AliasEvent):
            self.aliases += 1
            if self.aliases > limits.MAX_YAML_ALIASES:
                line = self.peek_event().start_mark.line + 1
                raise _YAMLTooLarge(f"line {line}: more than {limits.MAX_YAML_ALIASES} aliases (*name)")
        return super().compose_node(parent, index)


def _expanded_nodes(node: yaml.Node, counted: dict[int, int]) -> int:
    """Nodes of the document under ``node`` with every alias expanded (shared nodes counted
    once per use, each computed once); a node that contains itself is refused."""
    key = id(node)
    if key in counted:
        if counted[key] < 0:
            raise _YAMLTooLarge(f"line {node.start_mark.line + 1}: an alias refers to a node that contains it")
        return counted[key]
    counted[key] = -1
    if isinstance(node, yaml.MappingNode):
        children = [child for pair in node.value for child in pair]
    elif isinstance(node, yaml.SequenceNode):
        children = node.value
    else:
        children = []
    counted[key] = 1 + sum(_expanded_nodes(child, counted) for child in children)
    return counted[key]


def read_yaml(raw: bytes, source: str) -> Any:
    """The parsed YAML of a scene file's bytes, with bounded work: at most MAX_SCENE_BYTES,
    MAX_YAML_ALIASES aliases and MAX_YAML_NODES nodes with the aliases expanded (a 1 kB alias
    bomb expands to 1e9); an empty file is ``{}``. Every failure is a one-line SceneError."""
    if len(raw) > limits.MAX_SCENE_BYTES:
        raise SceneError(source, "(file)", f"{len(raw)} bytes is beyond the bound of "
                         f"{limits.MAX_SCENE_BYTES} bytes on a scene file")
    try:
        loader = _BoundedLoader(raw.decode("utf-8"))
        try:
            node = loader.get_single_node()
            if node is None:
                return {}
            size = _expanded_nodes(node, {})
            if size > limits.MAX_YAML_NODES:
                raise _YAMLTooLarge(f"{size} nodes with the aliases expanded, beyond the bound of "
                                    f"{limits.MAX_YAML_NODES}")
            return loader.construct_document(node)
        finally:
            loader.dispose()
    except (yaml.YAMLError, UnicodeDecodeError) as error:
        raise SceneError(source, "(file)", f"not valid YAML: {' '.join(str(error).split())}") from None
    except _YAMLTooLarge as error:
        raise SceneError(source, "(file)", f"YAML refused: {error}") from None
    except RecursionError:
        raise SceneError(source, "(file)", "YAML refused: nested too deeply") from None


class SceneReader:
    """Typed access to a scene's parsed data with errors naming the source, the key and the value."""

    def __init__(self, source: str, values: Mapping[str, float] | None = None) -> None:
        self.source = source
        self.values = dict(values or {})
        #: key -> (nominal value, sigma) of every uncertain number read, in reading order.
        self.uncertain: dict[str, tuple[float, float]] = {}

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

    def number(self, value: Any, key: str, bound: limits.Bound | None = None) -> float:
        """A finite number (a YAML number or a string such as ``1e-6``), within ``bound``;
        an uncertain number ``"v ± s"`` reads as v (or as ``values[key]``)."""
        if is_uncertain(value):
            value = self.uncertain_number(value, key)
        if isinstance(value, bool):
            raise SceneError(self.source, key, "expected a number", value)
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise SceneError(self.source, key, "expected a number", value) from None
        if not math.isfinite(number):
            raise SceneError(self.source, key, "expected a finite number", value)
        return self.bounded(number, key, bound)

    def uncertain_number(self, value: str, key: str) -> float:
        """The value of ``"v ± s"`` at ``key``: v, or ``values[key]`` if given; (v, s) is
        recorded in ``uncertain``."""
        match = UNCERTAIN_NUMBER.match(value)
        problem = "expected 'value ± sigma' (or 'value +- sigma'): two finite numbers, sigma > 0"
        if match is None:
            raise SceneError(self.source, key, problem, value)
        try:
            nominal, sigma = float(match.group(1)), float(match.group(2))
        except ValueError:
            raise SceneError(self.source, key, problem, value) from None
        if not (math.isfinite(nominal) and math.isfinite(sigma) and sigma > 0):
            raise SceneError(self.source, key, problem, value)
        self.uncertain[key] = (nominal, sigma)
        return self.values.get(key, nominal)

    def unused_values(self) -> None:
        """Refuse a value given for a key that holds no uncertain number."""
        for key in self.values:
            if key not in self.uncertain:
                known = ", ".join(self.uncertain) or "none"
                raise SceneError(self.source, key, f"not an uncertain parameter of the scene (uncertain: {known})")

    def positive(self, value: Any, key: str, bound: limits.Bound | None = None) -> float:
        number = self.number(value, key, bound)
        if number <= 0:
            raise SceneError(self.source, key, "must be positive", value)
        return number

    def bounded(self, number: float, key: str, bound: limits.Bound | None) -> float:
        """``number`` if within ``bound`` (youbot_dynamics.model.limits), else a SceneError."""
        problem = bound.problem(number) if bound is not None else ""
        if problem:
            raise SceneError(self.source, key, problem)
        return number

    def vector3(self, value: Any, key: str, bound: limits.Bound | None = None) -> np.ndarray:
        """Three numbers, each within ``bound``."""
        if not isinstance(value, (list, tuple)) or len(value) != 3:
            raise SceneError(self.source, key, "expected a list of 3 numbers", value)
        return np.array([self.number(x, f"{key}[{i}]", bound) for i, x in enumerate(value)])

    def joint_list(self, value: Any, key: str, robot: Robot) -> tuple[str, ...]:
        if not isinstance(value, list) or not value:
            raise SceneError(self.source, key, "expected a non-empty list of joint names", value)
        for i, name in enumerate(value):
            self._joint(robot, name, f"{key}[{i}]")
        if len(set(value)) != len(value):
            raise SceneError(self.source, key, "a joint is listed twice", value)
        return tuple(value)

    def joint_values(self, value: Any, key: str, robot: Robot,
                     bound: limits.Bound | None = None) -> dict[str, float]:
        values = self.mapping(value, key)
        out = {}
        for name, number in values.items():
            self._joint(robot, name, f"{key}.{name}")
            out[name] = self.number(number, f"{key}.{name}", bound)
        return out

    def within_limits(self, robot: Robot, name: str, value: float, key: str) -> None:
        joint = robot.joints[robot.joint_index(name)]
        if not joint.lower - 1e-12 <= value <= joint.upper + 1e-12:
            raise SceneError(self.source, key, f"outside the joint limits [{joint.lower:g}, {joint.upper:g}]", value)

    def _joint(self, robot: Robot, name: Any, key: str) -> None:
        if name not in robot.joint_names:
            raise SceneError(self.source, key, f"not a moving joint of {robot.source} "
                             f"(joints: {', '.join(robot.joint_names)})", name)

    def file(self, value: Any, key: str, base_dir: Path | None) -> Path:
        """The file ``value`` names: absolute, else relative to ``base_dir`` (the scene
        file's folder; None for a scene from a mapping), else to the package share."""
        if value is None or value == "":
            raise SceneError(self.source, key, "missing: give a file path")
        bases = (package_share(),) if base_dir is None else (base_dir, package_share())
        for base in bases:
            candidate = (base / str(value)).resolve()
            if candidate.is_file():
                return candidate
        beside = "" if base_dir is None else f"in {base_dir} or "
        raise SceneError(self.source, key, f"file not found {beside}in the package share ({package_share()})", value)
