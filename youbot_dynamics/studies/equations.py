"""A small equation-based model form (ModiaLang / ModelingToolkit style) and document
000's example models written in it, with the document's parameters and start values.

An :class:`EquationModel` holds unknown functions of time with start values (None: no
start value, an algebraic unknown to be computed), parameters with defaults, and the
equations as sympy residuals (expression = 0) in ``sp.Function(name)(T)`` and
``sp.Symbol(parameter)``. ``model | {"L": 0.5}`` is the parameter merge (ModiaLang's
``Model | Map(L = 0.5)``, ModelingToolkit's ``[L => 0.5]``): a new model with those
parameter defaults or start values replaced; the original is unchanged. An unknown name is
a :class:`UserInputError` naming the model and the valid names.

``derivative_names`` names the variable that order lowering introduces for the first
derivative of a function (x'' = ... becomes u' = ... with u = x'); declared among the
variables when it needs a start value.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Callable, Mapping

import sympy as sp

from youbot_dynamics.errors import UserInputError

#: The independent variable (time, s) of every equation model.
T = sp.Symbol("t")


def unknown(name: str) -> sp.Expr:
    """The unknown function ``name`` of time, as the equations use it."""
    return sp.Function(name)(T)


def der(expression: sp.Expr, order: int = 1) -> sp.Expr:
    """d^order expression / dt^order (ModiaLang's der, ModelingToolkit's D)."""
    return sp.diff(expression, T, order)


@dataclass(frozen=True)
class EquationModel:
    """Unknowns (name -> start value or None, in this order), parameters (name -> default,
    SI), residuals (sympy, = 0) named f1, f2, ... in their order, the names order
    lowering gives to first derivatives, and the time span [t0, t_end] (s) the start
    values hold at t0."""

    name: str
    variables: Mapping[str, float | None]
    parameters: Mapping[str, float]
    equations: tuple[sp.Expr, ...]
    derivative_names: Mapping[str, str] = field(default_factory=dict)
    t_end: float = 10.0
    t0: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "variables", MappingProxyType(dict(self.variables)))
        object.__setattr__(self, "parameters", MappingProxyType(dict(self.parameters)))
        object.__setattr__(self, "equations", tuple(sp.sympify(e) for e in self.equations))
        both = set(self.variables) & set(self.parameters)
        if both:
            raise UserInputError(f"model {self.name}: {sorted(both)} declared both as "
                                 "variable and parameter")

    def __or__(self, overrides: Mapping[str, float]) -> EquationModel:
        """The parameter merge: a copy with parameter defaults and start values replaced."""
        unknown_names = sorted(set(overrides) - set(self.parameters) - set(self.variables))
        if unknown_names:
            raise UserInputError(
                f"model {self.name}: no parameter or variable {', '.join(unknown_names)}; "
                f"parameters: {', '.join(self.parameters)}; variables: "
                f"{', '.join(self.variables)}")
        parameters = {k: float(overrides.get(k, v)) for k, v in self.parameters.items()}
        variables = {k: (float(overrides[k]) if k in overrides else v)
                     for k, v in self.variables.items()}
        return replace(self, variables=variables, parameters=parameters)

    @property
    def equation_names(self) -> list[str]:
        """f1, f2, ... in the given order."""
        return [f"f{i + 1}" for i in range(len(self.equations))]


def first_order_lag() -> EquationModel:
    """ModelingToolkit's first-order lag as document 000 writes it (unitstep_fol_factory):
    x' = RHS, RHS = (1 - x) / tau, defaults x(0) = 0, tau = 1 s, on [0, 5] s;
    x(t) = 1 + (x(0) - 1) exp(-t / tau). RHS is an alias of x' that alias elimination
    removes. The document's second run is :data:`LAG_SECOND_RUN` on [0, 10] s."""
    x, rhs = unknown("x"), unknown("RHS")
    tau = sp.Symbol("tau")
    return EquationModel("lag", {"x": 0.0, "RHS": None}, {"tau": 1.0},
                         (rhs - (1 - x) / tau, der(x) - rhs), t_end=5.0)


#: Document 000's second lag run: ``ODEProblem(fol, [:x => 2.0], (0.0, 10.0), [:tau => 5.0])``
#: (merge, t_end in s).
LAG_SECOND_RUN = ({"x": 2.0, "tau": 5.0}, 10.0)


def cartesian_pendulum(angle0: float = math.pi / 2) -> EquationModel:
    """Document 000's Cartesian pendulum in ModelingToolkit's second-order form (m = 1,
    L = l^2, lambda = -T / l): x'' = lambda x, y'' = lambda y - g, x^2 + y^2 = L; order
    lowering names x' u and y' v, giving the document's f1..f5 (benchmarks.md section 6).
    Starts at rest at ``angle0`` (rad) from hanging straight down (y < 0); the default is
    the document's ModelingToolkit run: x = 1, y = 0 (horizontal), g = 9.8 m/s^2, L = 1,
    on [0, 10] s."""
    x, y, lam = unknown("x"), unknown("y"), unknown("lambda")
    length_squared, gravity = sp.symbols("L g")
    parameters = {"L": 1.0, "g": 9.8}
    length = math.sqrt(parameters["L"])
    starts = {"x": length * math.sin(angle0), "y": 0.0 if angle0 == math.pi / 2 else
              -length * math.cos(angle0),
              "u": 0.0, "v": 0.0, "lambda": None}
    return EquationModel("pendulum", starts, parameters,
                         (der(x, 2) - lam * x, der(y, 2) - lam * y + gravity,
                          x**2 + y**2 - length_squared),
                         derivative_names={"x": "u", "y": "v"}, t_end=10.0)


def second_order_system() -> EquationModel:
    """Document 000's ModelingToolkit second-order system (its ode_order_lowering example):
    x'' = sigma (y - x), y' = x (rho - z) - y, z' = x y - beta z with sigma = 10,
    rho = 10, beta = 8/3, x(0) = 1, x'(0) = y(0) = z(0) = 0, on [0, 100] s; lowering names
    x' xd."""
    x, y, z = unknown("x"), unknown("y"), unknown("z")
    sigma, rho, beta = sp.symbols("sigma rho beta")
    return EquationModel(
        "second-order", {"x": 1.0, "xd": 0.0, "y": 0.0, "z": 0.0},
        {"sigma": 10.0, "rho": 10.0, "beta": 8.0 / 3.0},
        (der(x, 2) - sigma * (y - x), der(y) - (x * (rho - z) - y), der(z) - (x * y - beta * z)),
        derivative_names={"x": "xd"}, t_end=100.0)


def lowpass_filter() -> EquationModel:
    """An RC low-pass filter whose incidence is document 000's graph (benchmarks.md section 6,
    variables numbered as there): a source u0 = U0 (V) drives R1 and R2 in series into C;
    1 uR1 (V across R1), 2 u0, 3 uR2, 4 vn (node between R1 and R2), 5 vC (the state),
    6 vC', 7 i (A). f1 u0 = uR1 + vn, f2 uR1 = R1 i, f3 vn = uR2 + vC, f4 uR2 = R2 i,
    f5 C vC' = i, f6 u0 = U0; vC(t) = U0 (1 - exp(-t / ((R1 + R2) C)))."""
    u_r1, u0, u_r2, vn, vc, i = (unknown(n) for n in ("uR1", "u0", "uR2", "vn", "vC", "i"))
    r1, r2, c, source = sp.symbols("R1 R2 C U0")
    return EquationModel(
        "lowpass", {"uR1": None, "u0": None, "uR2": None, "vn": None, "vC": 0.0, "i": None},
        {"R1": 100.0, "R2": 100.0, "C": 1e-3, "U0": 1.0},
        (u0 - u_r1 - vn, u_r1 - r1 * i, vn - u_r2 - vc, u_r2 - r2 * i, c * der(vc) - i,
         u0 - source), t_end=1.0)


def modia_pendulum() -> EquationModel:
    """Document 000's ModiaLang damped pendulum: L = 0.8 m, m = 1 kg, d = 0.5 N m s/rad,
    g = 9.81 m/s^2, phi(0) = 1.57 rad, w(0) = 0;
    w = der(phi), 0 = m L^2 der(w) + d w + m g L sin(phi), r = (L cos phi, -L sin phi)."""
    phi, w, rx, ry = (unknown(n) for n in ("phi", "w", "rx", "ry"))
    length, mass, damping, gravity = sp.symbols("L m d g")
    return EquationModel(
        "modia-pendulum", {"phi": 1.57, "w": 0.0, "rx": None, "ry": None},
        {"L": 0.8, "m": 1.0, "d": 0.5, "g": 9.81},
        (w - der(phi), mass * length**2 * der(w) + damping * w
         + mass * gravity * length * sp.sin(phi),
         rx - length * sp.cos(phi), ry + length * sp.sin(phi)),
        t_end=10.0)


#: Document 000's parameter merge for the ModiaLang pendulum (``Pendulum | Map(L = 0.5)``).
MODIA_MERGE = {"L": 0.5}
#: Example name -> its model builder, for the command line.
EXAMPLE_MODELS: Mapping[str, Callable[[], EquationModel]] = MappingProxyType({
    "lag": first_order_lag, "pendulum": cartesian_pendulum, "lowpass": lowpass_filter,
    "modia-pendulum": modia_pendulum, "second-order": second_order_system})
