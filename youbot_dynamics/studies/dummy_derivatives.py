"""Mattsson and Soederlind's dummy derivatives (SIAM J. Sci. Comput. 14(3), 1993): the
state selection after Pantelides' index reduction.

Level 1: the equations E1 of the reduced system that were made by differentiation, and as
candidates Z1 the highest derivatives in them that are derivatives of another variable.
From the Jacobian dE1/dZ1 choose |E1| columns with a nonsingular square submatrix: those
variables become *dummy derivatives*, plain algebraic unknowns. Level k+1: E(k+1) = the
equations one differentiation below E(k) that are themselves differentiated, Z(k+1) = the
variables one differentiation below the selected ones that are themselves derivatives;
repeat until no equation is left. There is one dummy per differentiated equation.

The choice is Gaussian elimination with full pivoting on the Jacobian evaluated at the start
values (an entry that still contains an unknown without a start value counts as 1): the
largest pivot first, on ties the candidate of higher derivative order, then the earlier
variable. So a constraint x^2 + y^2 = L makes y' the dummy when |y| > |x| at the start
(y is then computed from the constraint and x stays a state). A state is a variable whose
derivative occurs and is not a dummy; all other variables are unknowns of the index-1
system. The selection is static: it holds while its pivots stay away from zero
(state_selection.py chooses again where one fades).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np
import sympy as sp

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.studies.structure import PantelidesResult, symbolic_equation, variable_name


@dataclass
class DummyLevel:
    """One level of the selection: equations, candidates, the Jacobian (symbolic, as text,
    and at the start values) and the chosen dummy derivatives with their pivots."""

    equations: list[str]
    candidates: list[str]
    jacobian: list[list[sp.Expr]]
    jacobian_at_start: list[list[float]]
    selected: list[str]
    pivots: list[float]


@dataclass
class DummySelection:
    """All levels, the dummy derivatives (variable indices), the states and the unknowns
    of the index-1 system (indices into the Pantelides result's variables)."""

    levels: list[DummyLevel]
    dummies: list[int]
    states: list[int]
    unknowns: list[int]


def full_pivot_columns(matrix: np.ndarray, preference: list[tuple]
                       ) -> tuple[list[int], list[float]]:
    """Columns of a full-row-rank choice by Gaussian elimination with full pivoting (largest
    |entry|, ties to the smallest ``preference`` key); returns the columns and pivots in
    the order chosen. A pivot below 1e-12 times the largest entry is a singular matrix."""
    a = np.array(matrix, dtype=float)
    rows, cols = list(range(a.shape[0])), list(range(a.shape[1]))
    chosen, pivots = [], []
    scale = max(np.abs(a).max(initial=0.0), 1.0)
    while rows:
        r, c = max(((r, c) for r in rows for c in cols),
                   key=lambda rc: (round(abs(a[rc]), 12), _negated(preference[rc[1]])))
        value = abs(a[r, c])
        if value <= 1e-12 * scale:
            raise UserInputError("dummy derivatives: the Jacobian of the differentiated "
                                 "equations is singular at the start values")
        chosen.append(c)
        pivots.append(float(a[r, c]))
        for other in rows:
            if other != r:
                a[other] -= a[other, c] / a[r, c] * a[r]
        rows.remove(r)
        cols.remove(c)
    return chosen, pivots


def _negated(key: tuple) -> tuple:
    """A key that sorts ``key`` descending when maximised."""
    return tuple(-k for k in key)


def select_dummy_derivatives(result: PantelidesResult, symbols: Mapping[int, sp.Symbol],
                             values: Mapping[sp.Symbol, float]) -> DummySelection:
    """The dummy derivatives of a Pantelides result (see the module docstring).
    ``symbols``: variable index -> its symbol (structure.variable_symbol); ``values``:
    start values and parameters by symbol."""
    A, B = result.variable_association, result.equation_association
    lower_equation = {k: i for i, k in enumerate(B) if k is not None}
    lower_variable = {k: j for j, k in enumerate(A) if k is not None}
    equations = [i for i in result.active_equations if i in lower_equation]
    candidates = [j for j in range(len(result.variables))
                  if A[j] is None and j in lower_variable
                  and any(j in result.equation_vars[i] for i in equations)]
    levels, dummies = [], []
    while equations:
        level, selected = dummy_level(result, equations, candidates, symbols, values)
        levels.append(level)
        dummies += selected
        equations = [lower_equation[i] for i in equations
                     if lower_equation[i] in lower_equation]
        candidates = [lower_variable[j] for j in selected
                      if j in lower_variable and lower_variable[j] in lower_variable]
    states, unknowns = state_selection(result, dummies)
    return DummySelection(levels, dummies, states, unknowns)


def dummy_level(result: PantelidesResult, equations: list[int], candidates: list[int],
                symbols: Mapping[int, sp.Symbol], values: Mapping[sp.Symbol, float]
                ) -> tuple[DummyLevel, list[int]]:
    """One level of the selection: the Jacobian of the level's differentiated
    ``equations`` with respect to its ``candidates`` (variable indices), at the start
    values, and the candidates full pivoting picks (highest derivative first on ties)."""
    if len(candidates) < len(equations):
        raise UserInputError(
            "dummy derivatives: fewer candidates ("
            + ", ".join(variable_name(result.variables[j]) for j in candidates)
            + ") than differentiated equations ("
            + ", ".join(result.equation_names[i] for i in equations) + ")")
    residuals = [symbolic_equation(result.equations[i], result.variables, symbols)
                 for i in equations]
    jacobian = [[sp.diff(r, symbols[j]) for j in candidates] for r in residuals]
    numeric = [[_magnitude(entry, values) for entry in row] for row in jacobian]
    preference = [(-result.variables[j][1], j) for j in candidates]
    chosen, pivots = full_pivot_columns(np.array(numeric), preference)
    selected = [candidates[c] for c in chosen]
    return DummyLevel([result.equation_names[i] for i in equations],
                      [variable_name(result.variables[j]) for j in candidates],
                      jacobian, numeric,
                      [variable_name(result.variables[j]) for j in selected], pivots), selected


def state_selection(result: PantelidesResult, dummies: list[int]) -> tuple[list[int], list[int]]:
    """The states (variables whose derivative appears and is no dummy) and the unknowns of
    the index-1 system (every other variable), as variable indices; UserInputError when
    the unknowns do not match the equations in number."""
    dummy_set = set(dummies)
    states = [j for j, k in enumerate(result.variable_association)
              if k is not None and k not in dummy_set]
    unknowns = [j for j in range(len(result.variables)) if j not in set(states)]
    if len(unknowns) != len(result.equations):
        raise UserInputError(f"dummy derivatives: {len(result.equations)} equations but "
                             f"{len(unknowns)} unknowns after the state selection")
    return states, unknowns


def _magnitude(entry: sp.Expr, values: Mapping[sp.Symbol, float]) -> float:
    """A Jacobian entry at the start values; 1 where it still holds an unknown without a
    start value (structurally nonzero), 0 where it is identically zero."""
    if entry == 0:
        return 0.0
    value = entry.xreplace(dict(values))
    return float(value) if not value.free_symbols else 1.0
