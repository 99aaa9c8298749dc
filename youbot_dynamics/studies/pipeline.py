"""The equation pipeline (ModiaBase / ModelingToolkit's structural_simplify): from an
:class:`~youbot_dynamics.studies.equations.EquationModel` to a generated ODE x' = f(t, x)
and its simulation. Stages, in order:

1. order lowering: a derivative of order k > 1 of x gets new variables x1 = x',
   ..., x(k-1) = x^(k-1) and equations x' - x1 = 0, ... (placed first);
2. alias elimination: an equation a = b or a = -b in which a is an undifferentiated
   unknown that never occurs differentiated is removed and a substituted everywhere
   (a becomes an observed variable);
3. matching of the highest derivatives and algebraic unknowns (Hopcroft-Karp,
   structure.maximum_matching);
4. Pantelides' index reduction (structure.pantelides);
5. dummy derivatives: the state selection (dummy_derivatives.py);
6. BLT of the index-1 system, states known (structure.block_lower_triangular);
7. greedy tearing of the blocks of several equations (tearing.py);
8. code generation: the blocks solved explicitly with sympy, the state derivatives as
   closed expressions, sympy ``lambdify`` (with common subexpressions) into
   rhs(t, x);
9. simulation with youbot_dynamics.integrate.integrators.integrate.

:func:`run_pipeline` runs stages 1-8, :func:`simulate` stage 9;
state_selection.simulate_with_reselection repeats both where the state selection must
change.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.integrate.integrators import Event, Solution, integrate, tolerances_from_tol
from youbot_dynamics.studies.dummy_derivatives import DummySelection, select_dummy_derivatives
from youbot_dynamics.studies.equations import T, EquationModel, unknown
from youbot_dynamics.studies.structure import (PantelidesResult, block_lower_triangular,
                                               equation_variables, incidence, incidence_rows,
                                               maximum_matching, pantelides, symbolic_equation,
                                               variable_name, variable_symbol)
from youbot_dynamics.studies.tearing import Tearing, greedy_tearing, solve_single, solve_torn_block


@dataclass
class GeneratedOde:
    """x' = rhs(t, x) for the states (names, start values), with parameters bound; the
    closed expression of every state derivative and of every other variable (observed)
    in t, the states and the parameters."""

    state_names: list[str]
    x0: np.ndarray
    derivatives: dict[str, sp.Expr]
    observed: dict[str, sp.Expr]
    rhs: Callable[[float, np.ndarray], np.ndarray]
    observe: Callable[[float, np.ndarray], dict[str, float]]


@dataclass
class PipelineResult:
    """Every stage's product, for printing (:func:`pipeline_report`) and for tests."""

    model: EquationModel
    lowered: list[sp.Expr]
    lowered_names: list[str]
    new_variables: list[str]
    aliases: list[tuple[str, str, str]]
    equations: list[sp.Expr]
    initial_matching: dict[str, str]
    unmatched: list[str]
    incidence_variables: list[str]
    incidence: list[str]
    pantelides: PantelidesResult
    dummies: DummySelection
    blt_variables: list[str]
    blt_incidence: list[str]
    blocks: list[list[str]]
    block_variables: list[list[str]]
    tearing: list[dict] = field(default_factory=list)
    ode: GeneratedOde | None = None


def lower_order(model: EquationModel) -> tuple[list[sp.Expr], list[str], list[str]]:
    """Stage 1: the equations with every derivative of order > 1 lowered (the new
    equations first), the function order (declared variables, then new ones) and the new
    variables described ("u = x'")."""
    highest: dict[str, int] = {}
    for equation in model.equations:
        for name, order in equation_variables(equation, T):
            highest[name] = max(order, highest.get(name, 0))
    new_equations, replacements, new_names, described = [], {}, [], []
    for name, order in highest.items():
        if order < 2:
            continue
        chain = [name, model.derivative_names.get(name, f"{name}_t")]
        while len(chain) < order:
            chain.append(f"{chain[-1]}_t")
        for k in range(1, order):
            new_equations.append(sp.diff(unknown(chain[k - 1]), T) - unknown(chain[k]))
            new_names.append(chain[k])
            described.append(f"{chain[k]} = {chain[k - 1]}'")
        for k in range(order, 0, -1):
            replacements[sp.Derivative(unknown(name), (T, k))] = (
                sp.Derivative(unknown(chain[k - 1]), (T, 1)) if k >= 2 else unknown(chain[1]))
    lowered = new_equations + [e.xreplace(replacements) for e in model.equations]
    order = list(model.variables) + [n for n in new_names if n not in model.variables]
    return lowered, order, described


def eliminate_aliases(equations: list[sp.Expr], names: list[str], order: list[str]
                      ) -> tuple[list[sp.Expr], list[tuple[str, sp.Expr, str]]]:
    """Stage 2: remove equations a -+ b = 0 whose a (an unknown at order 0, the later
    declared of two candidates) never occurs differentiated; substitute a. Returns the
    remaining equations and the eliminated (a, expression, name of the equation) triples
    in order."""
    equations, names = list(equations), list(names)
    eliminated: list[tuple[str, sp.Expr, str]] = []
    rank = {n: k for k, n in enumerate(order)}
    while True:
        differentiated = {n for e in equations for n, o in equation_variables(e, T) if o > 0}
        found = None
        for i, equation in enumerate(equations):
            terms = [unknown_term(term) for term in sp.Add.make_args(sp.expand(equation))]
            if len(terms) != 2 or None in terms:
                continue
            candidates = [term for term in terms if isinstance(term, AppliedUndef)
                          and term.func.__name__ not in differentiated]
            if candidates:
                alias = max(candidates, key=lambda term: rank.get(term.func.__name__, 0))
                found = i, alias, sp.solve(equation, alias)[0]
                break
        if found is None:
            return equations, eliminated
        i, alias, value = found
        eliminated.append((alias.func.__name__, value, names[i]))
        del equations[i], names[i]
        equations = [e.xreplace({alias: value}) for e in equations]


def unknown_term(term: sp.Expr) -> sp.Expr | None:
    """The unknown (a function of t or its derivative) when ``term`` is plus or minus one
    unknown, else None."""
    rest = -term if term.could_extract_minus_sign() else term
    if isinstance(rest, sp.Derivative) or (isinstance(rest, AppliedUndef) and rest.args == (T,)):
        return rest
    return None


def run_pipeline(model: EquationModel) -> PipelineResult:
    """Stages 1-8 on ``model`` (its parameter values as merged)."""
    lowered, order, new_names = lower_order(model)
    lowered_names = [f"f{i + 1}" for i in range(len(lowered))]
    equations, aliases = eliminate_aliases(lowered, lowered_names, order)
    alias_names = {a for a, _, _ in aliases}
    order = [n for n in order if n not in alias_names]

    variables, equation_vars = incidence(equations, T, order)
    matching = highest_derivative_matching(variables, equation_vars)
    names = [f"f{i + 1}" for i in range(len(equations))]
    reduced = pantelides(equations, T, names, order)

    symbols = {j: variable_symbol(v) for j, v in enumerate(reduced.variables)}
    parameters = {sp.Symbol(k): v for k, v in model.parameters.items()}
    start = {sp.Symbol(k): v for k, v in model.variables.items() if v is not None}
    selection = select_dummy_derivatives(reduced, symbols, {**start, **parameters})

    residuals = [symbolic_equation(e, reduced.variables, symbols) for e in reduced.equations]
    restricted, blocks, matched = index1_blocks(model, reduced, selection)

    result = PipelineResult(
        model, lowered, lowered_names, new_names,
        [(a, str(pretty_expression(v)), where) for a, v, where in aliases], equations,
        *matching_views(variables, equation_vars, matching, names), reduced, selection,
        *blt_views(reduced, selection, restricted, blocks, matched))

    explicit = solve_blocks(model, result, residuals, symbols, matched, start, parameters)
    result.ode = generate_ode(model, reduced, selection, symbols, explicit, aliases)
    return result


def highest_derivative_matching(variables: list, equation_vars: list[set[int]]) -> dict[int, int]:
    """A maximum matching (variable -> equation) of the highest derivatives only: the
    variables whose next derivative does not appear."""
    highest = [j for j, (name, o) in enumerate(variables) if (name, o + 1) not in variables]
    return maximum_matching(equation_vars, highest)


def matching_views(variables: list, equation_vars: list[set[int]], matching: dict[int, int],
                   names: list[str]) -> tuple[dict[str, str], list[str], list[str], list[str]]:
    """Stage 3 as printed: the matching by name, the unmatched equations, the variables'
    names and the incidence rows."""
    return ({variable_name(variables[j]): names[i] for j, i in sorted(matching.items())},
            [names[i] for i in range(len(names)) if i not in matching.values()],
            [variable_name(v) for v in variables], incidence_rows(equation_vars, len(variables)))


def blt_views(reduced: PantelidesResult, selection: DummySelection, restricted: list[set[int]],
              blocks: list[list[int]], matched: dict[int, int]
              ) -> tuple[list[str], list[str], list[list[str]], list[list[str]]]:
    """Stage 6 as printed: the unknowns' names, the incidence rows in them, each block's
    equations and the variables it solves for."""
    return ([variable_name(reduced.variables[j]) for j in selection.unknowns],
            incidence_rows([{selection.unknowns.index(j) for j in vs} for vs in restricted],
                           len(selection.unknowns)),
            [[reduced.equation_names[i] for i in block] for block in blocks],
            [[variable_name(reduced.variables[j]) for j in sorted(matched[i] for i in block)]
             for block in blocks])


def index1_blocks(model: EquationModel, reduced: PantelidesResult, selection: DummySelection
                  ) -> tuple[list[set[int]], list[list[int]], dict[int, int]]:
    """The index-1 system with the states known: each equation's unknowns, its BLT blocks
    (equation indices) and the matching equation -> unknown; UserInputError when it has
    no perfect matching."""
    unknown_set = set(selection.unknowns)
    restricted = [{j for j in vs if j in unknown_set} for vs in reduced.equation_vars]
    assignment = maximum_matching(restricted, selection.unknowns)
    if len(assignment) != len(reduced.equations):
        raise UserInputError(f"model {model.name}: the index-1 system has no perfect "
                             "matching after the state selection")
    return (restricted, block_lower_triangular(restricted, assignment),
            {i: j for j, i in assignment.items()})


def solve_blocks(model: EquationModel, result: PipelineResult, residuals: list[sp.Expr],
                 symbols: dict[int, sp.Symbol], matched: dict[int, int],
                 start: dict[sp.Symbol, float], parameters: dict[sp.Symbol, float]
                 ) -> list[tuple[sp.Symbol, sp.Expr]]:
    """Stages 7-8a: each BLT block of ``result`` solved explicitly in solution order (one
    equation by sympy, several after greedy tearing, recorded in ``result.tearing``), the
    consistent initial values checked on the way. ``matched``: equation -> variable."""
    reduced, selection = result.pantelides, result.dummies
    all_unknowns = {symbols[j] for j in selection.unknowns}
    algebraic = {symbols[j] for j in selection.unknowns if reduced.variables[j][1] == 0}
    index = {name: i for i, name in enumerate(reduced.equation_names)}
    explicit: list[tuple[sp.Symbol, sp.Expr]] = []
    values = dict(start)
    for block_names in result.blocks:
        block = [index[name] for name in block_names]
        block_residuals = [residuals[i] for i in block]
        if len(block) == 1:
            variable = symbols[matched[block[0]]]
            solved = [(variable, solve_single(block_residuals[0], variable, block_names[0],
                                              {**values, **parameters}))]
        else:
            torn = greedy_tearing(block_residuals, block_names,
                                  [symbols[j] for j in sorted(matched[i] for i in block)],
                                  all_unknowns, algebraic)
            result.tearing.append(_tearing_report(torn))
            solved = solve_torn_block(block_residuals, block_names, torn)
        for variable, expression in solved:
            explicit.append((variable, expression))
            consistent_start(model, block_names, variable, expression, values, parameters)
    return explicit


def consistent_start(model: EquationModel, equations: list[str], variable: sp.Symbol,
                     expression: sp.Expr, values: dict[sp.Symbol, float],
                     parameters: dict[sp.Symbol, float]) -> None:
    """Evaluate a solved variable at t0 into ``values`` (the consistent initial values
    that choose the branches of later nonlinear equations). A value that is not real, or
    that contradicts the variable's declared start value (beyond 1e-9 relative), is a
    UserInputError: the start values do not satisfy the equations."""
    value = sp.sympify(expression.xreplace({**values, **parameters, T: model.t0}))
    if not (value.is_number and value.is_finite):
        return
    number = complex(value)
    where = f"model {model.name}, equations {', '.join(equations)}"
    if abs(number.imag) > 1e-12 * max(1.0, abs(number)):
        raise UserInputError(f"{where}: {variable} = {number:.6g} at the start is not real; "
                             "the start values do not satisfy the constraints")
    declared = values.get(variable)
    if declared is not None and abs(number.real - declared) > 1e-9 * max(1.0, abs(declared)):
        raise UserInputError(f"{where}: {variable} = {number.real:.10g} at the start, but its "
                             f"start value is {declared:.10g}; make the start values "
                             "consistent with the equations")
    values[variable] = number.real


def _tearing_report(torn: Tearing) -> dict:
    """A torn block as plain data."""
    return {"tearing_variables": [str(v) for v in torn.tearing_variables],
            "residuals": torn.residuals,
            "causal": [f"{name}: {v} := {pretty_expression(e)}" for name, v, e in torn.causal]}


def pretty_expression(expression: sp.Expr) -> sp.Expr:
    """An expression in functions of t printed with x, x', ... ."""
    replacements = {}
    for node in sp.preorder_traversal(expression):
        if isinstance(node, sp.Derivative):
            replacements[node] = variable_symbol(
                (node.expr.func.__name__, sum(c for _, c in node.variable_count)))
    expression = expression.xreplace(replacements)
    return expression.xreplace({f: sp.Symbol(f.func.__name__) for f in expression.atoms(sp.Function)
                                if f.args == (T,)})


def generate_ode(model: EquationModel, reduced: PantelidesResult, selection: DummySelection,
                 symbols: dict[int, sp.Symbol], explicit: list[tuple[sp.Symbol, sp.Expr]],
                 aliases: list[tuple[str, sp.Expr, str]]) -> GeneratedOde:
    """Stage 8: closed expressions of the state derivatives and of every other variable
    (the explicit assignments substituted in order), lambdified with the parameters
    bound."""
    closed: dict[sp.Symbol, sp.Expr] = {}
    for variable, expression in explicit:
        closed[variable] = expression.xreplace(closed)
    states = [symbols[j] for j in selection.states]
    missing = [str(s) for s in states if model.variables.get(str(s)) is None]
    if missing:
        raise UserInputError(f"model {model.name}: the states {', '.join(missing)} need start "
                             "values")
    derivatives = {str(s): closed[symbols[reduced.variable_association[j]]]
                   for s, j in zip(states, selection.states)}
    observed = {str(v): e for v, e in closed.items()}
    for alias, value, _ in aliases:
        observed[alias] = symbolic_equation(value, reduced.variables, symbols).xreplace(closed)
    parameters = [sp.Symbol(k) for k in model.parameters]
    values = [model.parameters[k] for k in model.parameters]
    arguments = [T, *states, *parameters]
    compiled = sp.lambdify(arguments, [derivatives[str(s)] for s in states], modules="numpy",
                           cse=True, dummify=True)
    observed_names = list(observed)
    compiled_observed = sp.lambdify(arguments, [observed[k] for k in observed_names],
                                    modules="numpy", cse=True, dummify=True)

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        return np.array(compiled(t, *x, *values), dtype=float)

    def observe(t: float, x: np.ndarray) -> dict[str, float]:
        return dict(zip(observed_names, np.broadcast_arrays(
            *compiled_observed(t, *x, *values)))) if observed_names else {}

    return GeneratedOde([str(s) for s in states],
                        np.array([model.variables[str(s)] for s in states], dtype=float),
                        derivatives, observed, rhs, observe)


def simulate(result: PipelineResult, integrator: str = "cvode_bdf", tol: float = 1e-6,
             n_outputs: int = 201, t_end: float | None = None,
             dt: float | None = None, max_steps: int | None = None,
             t_eval: np.ndarray | None = None, events: Sequence[Event] = ()) -> Solution:
    """Stage 9: integrate the generated ODE from the start values with
    youbot_dynamics.integrate.integrators.integrate, with outputs at ``t_eval`` (s; default
    ``n_outputs`` equally spaced over [t0, t_end], the model's t_end by default). ``tol``
    is the one accuracy knob (tolerances_from_tol), ``dt`` the step of a fixed-step
    integrator, ``max_steps`` its step budget, ``events`` state events."""
    ode = result.ode
    if t_eval is None:
        t_eval = np.linspace(result.model.t0,
                             result.model.t_end if t_end is None else t_end, n_outputs)
    rtol, atol = tolerances_from_tol(tol, ode.x0)
    return integrate(ode.rhs, ode.x0, t_eval, integrator, dt=dt, rtol=rtol, atol=atol,
                     state_names=ode.state_names, max_steps=max_steps, events=events)
