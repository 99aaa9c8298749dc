"""Greedy tearing of an algebraic loop (a BLT block of several equations) and the explicit
solution of BLT blocks with sympy.

Tearing (the simple greedy causalisation of Modelica tools, cf. Elmqvist and Otter 1994):
go through the block's equations; one with a single unknown left that it contains linearly
with a coefficient free of unknowns (a constant or a parameter: no division by a variable
that may pass zero) is solved for it. When no equation qualifies, the unknown occurring in
most of the unsolved equations becomes a *tearing variable* (ties: an algebraic variable
before a derivative, then the earlier one) and is treated as known. The equations left
over are the *residuals*, as many as tearing variables; sympy solves them for the tearing
variables after substituting the causal assignments.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, Sequence

import sympy as sp

from youbot_dynamics.errors import UserInputError


@dataclass
class Tearing:
    """A torn block: tearing variables, residual equations (by name) and the causal
    assignments (equation name, variable, expression in knowns and tearing variables)."""

    tearing_variables: list[sp.Symbol]
    residuals: list[str]
    causal: list[tuple[str, sp.Symbol, sp.Expr]]


def solvable_for(residual: sp.Expr, variable: sp.Symbol, unknowns: set[sp.Symbol]) -> bool:
    """True when ``residual`` is linear in ``variable`` with a coefficient free of
    ``unknowns`` (and not zero)."""
    coefficient = sp.diff(residual, variable)
    return coefficient != 0 and not (coefficient.free_symbols & (unknowns | {variable}))


def greedy_tearing(residuals: Sequence[sp.Expr], names: Sequence[str],
                   unknowns: Sequence[sp.Symbol], all_unknowns: set[sp.Symbol],
                   algebraic: set[sp.Symbol]) -> Tearing:
    """Tear the block ``residuals`` (= 0, named ``names``) in ``unknowns`` (see the module
    docstring). ``all_unknowns``: every unknown symbol of the system (a coefficient must
    be free of them); ``algebraic``: the unknowns that are not derivatives (preferred as
    tearing variables)."""
    known: set[sp.Symbol] = set()
    tearing: list[sp.Symbol] = []
    causal: list[tuple[str, sp.Symbol, sp.Expr]] = []
    open_equations = list(range(len(residuals)))
    while len(known) < len(unknowns):
        progress = True
        while progress:
            progress = False
            for i in list(open_equations):
                left = [v for v in unknowns if v not in known and residuals[i].has(v)]
                if len(left) == 1 and solvable_for(residuals[i], left[0], all_unknowns):
                    (solution,) = sp.solve(residuals[i], left[0])
                    causal.append((names[i], left[0], solution))
                    known.add(left[0])
                    open_equations.remove(i)
                    progress = True
        left = [v for v in unknowns if v not in known]
        if not left:
            break
        order = {v: k for k, v in enumerate(unknowns)}
        chosen = max(left, key=lambda v: (sum(residuals[i].has(v) for i in open_equations),
                                          v in algebraic, -order[v]))
        tearing.append(chosen)
        known.add(chosen)
    return Tearing(tearing, [names[i] for i in open_equations], causal)


def solve_single(residual: sp.Expr, variable: sp.Symbol, name: str,
                 start: Mapping[sp.Symbol, float]) -> sp.Expr:
    """Solve one equation for one variable; among several solutions (a nonlinear equation)
    take the one nearest the variable's start value, evaluated at the start values."""
    solutions = sp.solve(residual, variable)
    if not solutions:
        raise UserInputError(f"equation {name}: sympy finds no explicit solution for "
                             f"{variable}")
    if len(solutions) == 1:
        return solutions[0]
    if variable not in start:
        raise UserInputError(f"equation {name} has {len(solutions)} solutions for {variable}: "
                             "give it a start value to choose the branch")
    return min(solutions, key=lambda s: abs(complex(s.xreplace(dict(start))) - start[variable]))


def solve_torn_block(residuals: Sequence[sp.Expr], names: Sequence[str], torn: Tearing
                     ) -> list[tuple[sp.Symbol, sp.Expr]]:
    """The block's explicit assignments: the tearing variables from the residuals (with
    the causal assignments substituted; sympy solve, one solution required), then the
    causal assignments in their order."""
    substitution: dict[sp.Symbol, sp.Expr] = {}
    for _, variable, expression in torn.causal:
        substitution[variable] = expression.xreplace(substitution)
    index = {name: i for i, name in enumerate(names)}
    reduced = [residuals[index[name]].xreplace(substitution) for name in torn.residuals]
    solutions = sp.solve(reduced, torn.tearing_variables, dict=True)
    if len(solutions) != 1:
        raise UserInputError(f"residuals {', '.join(torn.residuals)}: {len(solutions)} "
                             f"solutions for the tearing variables "
                             f"{', '.join(map(str, torn.tearing_variables))}, need one")
    assignments = [(v, sp.simplify(solutions[0][v])) for v in torn.tearing_variables]
    return assignments + [(variable, expression) for _, variable, expression in torn.causal]
