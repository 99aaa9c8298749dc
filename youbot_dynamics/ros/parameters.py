"""The dynamics node's parameters on rclpy: declared from the table of
:data:`youbot_dynamics.node.interface.PARAMETERS` (names, defaults, ranges, descriptions).

Numeric parameters carry a range in their descriptor, so an out-of-range set is refused
with a result (rclpy checks it); string choices are checked by
:func:`~youbot_dynamics.node.interface.check_choice`.
"""
from __future__ import annotations

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.node import Node

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.node.interface import CHOICES, PARAMETERS, Spec, check_choice


def descriptor(name: str, spec: Spec) -> ParameterDescriptor:
    """The ParameterDescriptor of one parameter (with its range, if numeric)."""
    extra = {}
    if spec.limits is not None and isinstance(spec.default, int):
        extra["integer_range"] = [IntegerRange(from_value=int(spec.limits[0]), to_value=int(spec.limits[1]), step=1)]
    elif spec.limits is not None:
        extra["floating_point_range"] = [FloatingPointRange(from_value=spec.limits[0], to_value=spec.limits[1])]
    choices = CHOICES.get(name)
    return ParameterDescriptor(name=name, description=spec.description, read_only=spec.read_only,
                               additional_constraints=f"one of: {', '.join(choices)}" if choices else "", **extra)


def declare_all(node: Node) -> dict[str, object]:
    """Declare every parameter on ``node``; returns their values. A bad choice raises
    UserInputError naming the parameter."""
    values = {}
    for name, spec in PARAMETERS.items():
        values[name] = node.declare_parameter(name, spec.default, descriptor(name, spec)).value
        problem = check_choice(name, values[name])
        if problem:
            raise UserInputError(problem)
    return values
