"""Structural analysis of equation systems: the bipartite incidence graph, a maximum
matching, block lower triangular (BLT) sorting and Pantelides' index reduction.

An equation system is a list of residuals (sympy expressions = 0) in unknown functions of
time x(t) and their derivatives; symbols that are not functions of t are parameters. A
*variable* is one function at one derivative order (x, x', x'', ...). Numbering: equations
and variables are 0-based in the code; everything printed (and document 000's lists in
benchmarks.md section 6) counts from 1, equations named f1, f2, ... in their given order.

- :func:`incidence` / :func:`incidence_graph`: which variables each equation contains, and
  that as a networkx bipartite graph.
- :func:`maximum_matching`: Hopcroft-Karp (networkx) between equations and the variables
  to be solved for.
- :func:`block_lower_triangular`: the strongly connected components (networkx) of the
  graph "equation a must be solved before equation b" (b contains the variable matched to
  a), in a topological order: blocks of equations that must be solved together.
- :func:`pantelides`: Pantelides' algorithm (1988) with the variable association list A
  (A[j] = k: variable k is the derivative of variable j) and equation association list B
  (B[i] = l: equation l was made by differentiating equation i); the structural index and
  how often each equation was differentiated.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Iterable, Sequence

import networkx as nx
import sympy as sp
from sympy.core.function import AppliedUndef

from youbot_dynamics.errors import UserInputError

#: A variable: (name of the function of t, derivative order).
Variable = tuple[str, int]


def variable_name(variable: Variable) -> str:
    """x, x', x'', x^(3), ... for (x, 0), (x, 1), ..."""
    name, order = variable
    return name + ("'" * order if order <= 3 else f"^({order})")


def equation_variables(expression: sp.Expr, t: sp.Symbol) -> set[Variable]:
    """The variables (function of t, derivative order) that occur in a residual."""
    found: set[Variable] = set()
    walk = sp.preorder_traversal(expression)
    for node in walk:
        if isinstance(node, sp.Derivative) and isinstance(node.expr, AppliedUndef):
            if any(symbol != t for symbol, _ in node.variable_count):
                raise UserInputError(f"derivative {node} is not with respect to {t}")
            found.add((node.expr.func.__name__, sum(c for _, c in node.variable_count)))
            walk.skip()
        elif isinstance(node, AppliedUndef):
            if node.args != (t,):
                raise UserInputError(f"unknown {node} must be a function of {t} alone")
            found.add((node.func.__name__, 0))
            walk.skip()
    return found


def incidence(equations: Sequence[sp.Expr], t: sp.Symbol,
              function_order: Sequence[str] = ()) -> tuple[list[Variable], list[set[int]]]:
    """All variables (functions in ``function_order``, the rest by name; each at every
    order from 0 up to the highest that occurs) and, per equation, the indices of the
    variables it contains."""
    per_equation = [equation_variables(sp.sympify(e), t) for e in equations]
    highest: dict[str, int] = {}
    for found in per_equation:
        for name, order in found:
            highest[name] = max(order, highest.get(name, 0))
    rank = {name: k for k, name in enumerate(function_order)}
    ordered = sorted(highest, key=lambda name: (rank.get(name, len(rank)), name))
    variables = [(name, order) for name in ordered for order in range(highest[name] + 1)]
    index = {variable: j for j, variable in enumerate(variables)}
    return variables, [{index[v] for v in found} for found in per_equation]


def incidence_graph(equation_vars: Sequence[Iterable[int]]) -> nx.Graph:
    """Bipartite graph: nodes ("e", i) for equations (bipartite=0) and ("v", j) for
    variables (bipartite=1); an edge where equation i contains variable j."""
    graph = nx.Graph()
    for i, variables in enumerate(equation_vars):
        graph.add_node(("e", i), bipartite=0)
        for j in variables:
            graph.add_node(("v", j), bipartite=1)
            graph.add_edge(("e", i), ("v", j))
    return graph


def maximum_matching(equation_vars: Sequence[Iterable[int]],
                     unknowns: Iterable[int] | None = None) -> dict[int, int]:
    """A maximum matching variable -> equation (Hopcroft-Karp), using only the variables
    in ``unknowns`` (all if None). Perfect when every equation is matched."""
    allowed = None if unknowns is None else set(unknowns)
    restricted = [sorted(j for j in vs if allowed is None or j in allowed)
                  for vs in equation_vars]
    # Integer nodes (equation i, variable m + j): networkx keeps the two sides in sets,
    # and sets of ints iterate in the same order in every process; ("e", i) tuples hash
    # their strings, so the matching changed with PYTHONHASHSEED.
    m = len(restricted)
    graph = nx.Graph()
    graph.add_nodes_from(range(m))
    graph.add_edges_from((i, m + j) for i, vs in enumerate(restricted) for j in vs)
    matching = nx.bipartite.hopcroft_karp_matching(graph, top_nodes=range(m))
    return {node - m: partner for node, partner in matching.items() if node >= m}


def augmenting_path_matching(equation_vars: Sequence[Sequence[int]], unknowns: Iterable[int],
                             last_first: bool = False) -> dict[int, int]:
    """A maximum matching variable -> equation by Pantelides' AUGMENTPATH (depth first):
    equations in order, each first taking a free variable, else re-routing an assigned one;
    each equation's variables scanned first to last, or last to first if ``last_first``.
    The order decides which of several perfect matchings comes out."""
    allowed = set(unknowns)
    assign: dict[int, int] = {}

    def candidates(i: int) -> list[int]:
        variables = [j for j in equation_vars[i] if j in allowed]
        return variables[::-1] if last_first else variables
    for i in range(len(equation_vars)):
        augmenting_path(i, candidates, assign, [], [])
    return assign


def augmenting_path(i: int, candidates: Callable[[int], Sequence[int]], assign: dict[int, int],
                    colored_eqs: list[int], colored_vars: list[int]) -> bool:
    """Pantelides' AUGMENTPATH from equation i: a free variable of ``candidates(i)`` (in that
    order), else one re-routed along a path, ``assign`` (variable -> equation) updated;
    the equations and variables the search visited are appended to ``colored_eqs`` and
    ``colored_vars``. True if the path was found."""
    colored_eqs.append(i)
    options = candidates(i)
    for j in options:
        if j not in assign:
            assign[j] = i
            return True
    for j in options:
        if j not in colored_vars:
            colored_vars.append(j)
            if augmenting_path(assign[j], candidates, assign, colored_eqs, colored_vars):
                assign[j] = i
                return True
    return False


def is_perfect_matching(equation_vars: Sequence[Iterable[int]], assign: Sequence[int]) -> bool:
    """Whether an ``assign`` list (variable j -> 1-based equation, 0 = none) matches every
    equation once, each to a variable it contains."""
    pairs = [(j, i - 1) for j, i in enumerate(assign) if i]
    return (sorted(i for _, i in pairs) == list(range(len(equation_vars)))
            and all(j in equation_vars[i] for j, i in pairs))


def block_lower_triangular(equation_vars: Sequence[Iterable[int]],
                           assignment: dict[int, int]) -> list[list[int]]:
    """Blocks of equations in solution order: the strongly connected components of the
    dependency graph (an edge a -> b when equation b contains the variable matched to
    equation a), topologically sorted, lowest equation first among independent blocks.
    Equations whose variables are all known form blocks of their own."""
    graph = nx.DiGraph()
    graph.add_nodes_from(range(len(equation_vars)))
    for b, variables in enumerate(equation_vars):
        for j in variables:
            a = assignment.get(j)
            if a is not None and a != b:
                graph.add_edge(a, b)
    condensed = nx.condensation(graph)
    members = condensed.graph["mapping"]
    blocks: dict[int, list[int]] = {}
    for equation, component in members.items():
        blocks.setdefault(component, []).append(equation)
    order = nx.lexicographical_topological_sort(condensed, key=lambda c: min(blocks[c]))
    return [sorted(blocks[c]) for c in order]


@dataclass
class PantelidesResult:
    """The reduced system: all equations (given ones first, then each differentiated one
    as it was made) and variables, the association lists (None where there is none), the
    variables each equation contains, the final assignment variable -> equation, and a
    log of the reduction steps."""

    equations: list[sp.Expr]
    equation_names: list[str]
    variables: list[Variable]
    equation_vars: list[set[int]]
    variable_association: list[int | None]
    equation_association: list[int | None]
    assignment: dict[int, int]
    steps: list[str] = field(default_factory=list)

    @property
    def differentiations(self) -> dict[str, int]:
        """How often each given equation was differentiated (only those that were)."""
        counts, given = {}, set(self.given_names)
        for i, name in enumerate(self.equation_names):
            count, k = 0, self.equation_association[i]
            while k is not None:
                count, k = count + 1, self.equation_association[k]
            if count and name in given:
                counts[name] = count
        return counts

    @property
    def given_names(self) -> list[str]:
        """Names of the equations as given (not made by differentiation)."""
        made = {k for k in self.equation_association if k is not None}
        return [name for i, name in enumerate(self.equation_names) if i not in made]

    @property
    def structural_index(self) -> int:
        """max number of differentiations of an equation, plus one if some variable
        appears only undifferentiated (an algebraic variable, like lambda); Pryce's
        structural index, equal to the differentiation index for these systems."""
        differentiated = max(self.differentiations.values(), default=0)
        algebraic = any(order == 0 and self.variable_association[j] is None
                        for j, (_, order) in enumerate(self.variables))
        return differentiated + (1 if algebraic else 0)

    @property
    def active_equations(self) -> list[int]:
        """Equations of the reduced system (those not differentiated further)."""
        return [i for i, b in enumerate(self.equation_association) if b is None]

    def vmap(self) -> dict[str, str]:
        """Variable association by name: variable -> its derivative (e.g. x -> x')."""
        return {variable_name(self.variables[j]): variable_name(self.variables[k])
                for j, k in enumerate(self.variable_association) if k is not None}

    def eqmap(self) -> dict[str, str]:
        """Equation association by name: equation -> the equation made by differentiating it."""
        return {self.equation_names[i]: self.equation_names[k]
                for i, k in enumerate(self.equation_association) if k is not None}

    def assignment_names(self) -> dict[str, str]:
        """The final assignment by name: variable -> the equation it is solved from."""
        return {variable_name(self.variables[j]): self.equation_names[i]
                for j, i in sorted(self.assignment.items())}


def pantelides(equations: Sequence[sp.Expr], t: sp.Symbol,
               names: Sequence[str] | None = None, function_order: Sequence[str] = (),
               max_steps: int = 100) -> PantelidesResult:
    """Pantelides' algorithm on residuals in functions of t (see the module docstring).

    For each given equation in turn: look for an augmenting path over the highest
    derivatives (variables with A[j] None); if none, differentiate every equation and
    every variable coloured in the failed search (sympy ``diff``), set
    assign[A[j]] = B[assign[j]] for the coloured variables and retry with the derivative
    of the equation. ``function_order`` orders the variables (see :func:`incidence`),
    which decides among equally good matchings.
    """
    equations = [sp.sympify(e) for e in equations]
    eq_names = list(names) if names is not None else [f"f{i + 1}" for i in range(len(equations))]
    variables, eq_vars = incidence(equations, t, function_order)
    index = {v: j for j, v in enumerate(variables)}
    A: list[int | None] = [index.get((name, order + 1)) for name, order in variables]
    B: list[int | None] = [None] * len(equations)
    assign: dict[int, int] = {}
    steps: list[str] = []

    def highest_derivatives(i: int) -> list[int]:
        return sorted(j for j in eq_vars[i] if A[j] is None)

    def add_variable(variable: Variable) -> int:
        index[variable] = len(variables)
        variables.append(variable)
        A.append(None)
        return index[variable]

    for k in range(len(equations)):
        i = k
        for _ in range(max_steps):
            colored_eqs: list[int] = []
            colored_vars: list[int] = []
            if augmenting_path(i, highest_derivatives, assign, colored_eqs, colored_vars):
                break
            for j in colored_vars:
                name, order = variables[j]
                derivative_of_j = (name, order + 1)
                A[j] = index[derivative_of_j] if derivative_of_j in index else add_variable(derivative_of_j)
            made = []
            for l in colored_eqs:
                derivative = sp.expand(equations[l].diff(t))
                found = equation_variables(derivative, t)
                for variable in sorted(found - set(index)):
                    previous = index.get((variable[0], variable[1] - 1))
                    new = add_variable(variable)
                    if previous is not None:
                        A[previous] = new
                B[l] = len(equations)
                equations.append(derivative)
                eq_names.append(f"f{len(equations)}")
                eq_vars.append({index[v] for v in found})
                B.append(None)
                made.append(f"{eq_names[l]} -> {eq_names[-1]}")
            for j in colored_vars:
                assign[A[j]] = B[assign[j]]
            steps.append(
                f"{eq_names[i]}: no augmenting path; differentiate equations "
                f"{', '.join(made)}; variables "
                + (", ".join(f"{variable_name(variables[j])} -> "
                             f"{variable_name(variables[A[j]])}" for j in colored_vars)
                   or "none"))
            i = B[i]
        else:
            raise UserInputError(f"Pantelides: equation {eq_names[k]} still unmatched after "
                                 f"{max_steps} differentiations; the system is structurally "
                                 "singular")
    return PantelidesResult(equations, eq_names, variables, eq_vars, A, B, assign, steps)


#: Document 000's low-pass filter as a bipartite graph: equation i lists its variables
#: (1-based, as in benchmarks.md section 6); variable 5 (the capacitor voltage, a state) is
#: known. Its ModiaBase.matching result and BLT blocks as it prints them.
LOWPASS_INCIDENCE = ((1, 2, 4), (1, 7), (3, 4), (3, 7), (6, 7), (2,))
LOWPASS_KNOWN = (5,)
LOWPASS_DOCUMENT_ASSIGN = (2, 6, 3, 1, 0, 5, 4)
LOWPASS_DOCUMENT_BLOCKS = ((6,), (2, 4, 3, 1), (5,))


PENDULUM_FUNCTIONS = ("x", "y", "u", "v", "lambda")


def cartesian_pendulum_equations(t: sp.Symbol) -> tuple[list[sp.Expr], list[str]]:
    """Document 000's pendulum in Cartesian coordinates (m = 1, L = l^2): residuals
    x' - u, y' - v, u' - lambda x, v' - lambda y + g, x^2 + y^2 - L (f1..f5), in the
    unknown functions PENDULUM_FUNCTIONS of t."""
    x, y, u, v, lam = (sp.Function(name)(t) for name in PENDULUM_FUNCTIONS)
    length_squared, gravity = sp.symbols("L g", positive=True)
    equations = [x.diff(t) - u, y.diff(t) - v, u.diff(t) - lam * x,
                 v.diff(t) - lam * y + gravity, x**2 + y**2 - length_squared]
    return equations, [f"f{i + 1}" for i in range(5)]


STRUCTURE_EXAMPLES: tuple[str, ...] = ("lowpass", "pendulum", "squeezer")


def incidence_rows(equation_vars: Sequence[Iterable[int]], n_variables: int) -> list[str]:
    """The incidence matrix as text rows: 'x' where equation i contains variable j."""
    return ["".join("x" if j in set(vs) else "." for j in range(n_variables))
            for vs in equation_vars]


def blt_permutation(equation_vars: Sequence[Iterable[int]], assignment: dict[int, int],
                    blocks: Sequence[Sequence[int]], n_variables: int
                    ) -> tuple[list[int], list[int]]:
    """Row and column order of the BLT-permuted incidence matrix: the equations block by
    block, each column the variable matched to its row's equation, unmatched (known)
    variables last; with this order the matrix is block lower triangular."""
    rows = [i for block in blocks for i in block]
    matched_to = {i: j for j, i in assignment.items()}
    columns = [matched_to[i] for i in rows if i in matched_to]
    return rows, columns + [j for j in range(n_variables) if j not in set(columns)]


def blt_view(equation_vars: Sequence[Iterable[int]], assignment: dict[int, int],
             blocks: Sequence[Sequence[int]], equation_names: Sequence[str],
             variable_names: Sequence[str]) -> dict:
    """The BLT-permuted incidence matrix as plain data: row (equation) and column
    (variable) names in that order, its text rows and the block sizes."""
    rows, columns = blt_permutation(equation_vars, assignment, blocks, len(variable_names))
    position = {j: k for k, j in enumerate(columns)}
    permuted = [{position[j] for j in equation_vars[i]} for i in rows]
    return {"rows": [equation_names[i] for i in rows],
            "columns": [variable_names[j] for j in columns],
            "incidence": incidence_rows(permuted, len(columns)),
            "block_sizes": [len(block) for block in blocks]}


def structure_report(example: str) -> dict:
    """The structural analysis of one of STRUCTURE_EXAMPLES as plain data (1-based numbers
    and names as printed): incidence matrix, matching, BLT blocks and, for the equation
    systems, Pantelides' reduction steps, vmap, eqmap, final assignment and structural
    index."""
    if example == "lowpass":
        return lowpass_report()
    if example not in STRUCTURE_EXAMPLES:
        raise UserInputError(f"unknown structure example {example!r}; valid: "
                             + ", ".join(STRUCTURE_EXAMPLES))
    return pantelides_report(example)


def assign_list(matching: dict[int, int], n_variables: int) -> list[int]:
    """A matching variable -> equation as ModiaBase's assign list (1-based, 0 = none)."""
    return [matching[j] + 1 if j in matching else 0 for j in range(n_variables)]


def document_assign_report(equation_vars: list[set[int]], unknowns: list[int],
                           n_variables: int) -> dict:
    """Document 000's low-pass assign list checked (a perfect matching? its blocks) and the
    lists AUGMENTPATH gives in either variable order."""
    document = {j: i - 1 for j, i in enumerate(LOWPASS_DOCUMENT_ASSIGN) if i}
    orders = {"first to last": False, "last to first": True}
    return {
        "document_assign": list(LOWPASS_DOCUMENT_ASSIGN),
        "document_assign_is_perfect_matching": is_perfect_matching(equation_vars,
                                                                   LOWPASS_DOCUMENT_ASSIGN),
        "document_assign_blocks": [[i + 1 for i in block]
                                   for block in block_lower_triangular(equation_vars, document)],
        "augmenting_path_assign": {
            order: assign_list(augmenting_path_matching(equation_vars, unknowns, last_first),
                               n_variables) for order, last_first in orders.items()},
    }


def lowpass_report() -> dict:
    """The low-pass filter's incidence (document 000 section 3): our matching as ModiaBase's
    ``assign`` list (variable -> equation, 0 = known), the BLT blocks, and the document's
    assign list checked: a perfect matching too, with the same blocks. The loop f1-f4 in
    variables 1, 3, 4, 7 is one 8-cycle of the bipartite graph, which has exactly two
    perfect matchings; AUGMENTPATH scanning each equation's variables first to last gives
    ours, last to first the document's."""
    example = "lowpass"
    equation_vars = [{j - 1 for j in vs} for vs in LOWPASS_INCIDENCE]
    n_variables = max(max(vs) for vs in LOWPASS_INCIDENCE)
    unknowns = [j for j in range(n_variables) if j + 1 not in LOWPASS_KNOWN]
    matching = maximum_matching(equation_vars, unknowns)
    blocks = block_lower_triangular(equation_vars, matching)
    names = [f"f{i + 1}" for i in range(len(equation_vars))]
    return {
        "example": example,
        "variables": [str(j + 1) for j in range(n_variables)],
        "known": list(LOWPASS_KNOWN),
        "equations": [f"f{i + 1}" for i in range(len(equation_vars))],
        "incidence": incidence_rows(equation_vars, n_variables),
        "assign": assign_list(matching, n_variables),
        "perfect_matching": len(matching) == len(equation_vars),
        **document_assign_report(equation_vars, unknowns, n_variables),
        "blocks": [[i + 1 for i in block] for block in blocks],
        "blt": blt_view(equation_vars, matching, blocks, names,
                        [str(j + 1) for j in range(n_variables)]),
        "steps": ["perfect matching: no equation needs differentiating (index 0 or 1)"]
        if len(matching) == len(equation_vars) else ["no perfect matching"],
    }


def pantelides_report(example: str) -> dict:
    """The Cartesian pendulum's or the squeezer's equations: the matching of the highest
    derivatives, Pantelides' steps, vmap, eqmap, the final assignment, the BLT blocks of
    the reduced system and the structural index."""
    t = sp.Symbol("t")
    if example == "pendulum":
        equations, names = cartesian_pendulum_equations(t)
        functions = PENDULUM_FUNCTIONS
    else:
        from youbot_dynamics.studies.squeezer import SQUEEZER_FUNCTIONS, squeezer_equations
        equations, names = squeezer_equations(t)
        functions = SQUEEZER_FUNCTIONS
    variables, equation_vars = incidence(equations, t, functions)
    highest = [j for j, (name, order) in enumerate(variables)
               if (name, order + 1) not in variables]
    initial = maximum_matching(equation_vars, highest)
    result = pantelides(equations, t, names, functions)
    return {
        "example": example,
        "variables": [variable_name(v) for v in variables],
        "equations": names,
        "incidence": incidence_rows(equation_vars, len(variables)),
        "initial_matching": {variable_name(variables[j]): names[i]
                             for j, i in sorted(initial.items())},
        "unmatched_equations": [names[i] for i in range(len(names))
                                if i not in initial.values()],
        "steps": result.steps,
        "vmap": result.vmap(),
        "eqmap": result.eqmap(),
        "assignment": result.assignment_names(),
        "differentiations": result.differentiations,
        "n_equations": len(result.equations),
        "n_variables": len(result.variables),
        **reduced_blocks(result),
        "structural_index": result.structural_index,
    }


def reduced_blocks(result: PantelidesResult) -> dict:
    """The BLT blocks of Pantelides' reduced system (its active equations in the variables
    they solve for, by equation name) and their permuted incidence matrix."""
    active = result.active_equations
    solved = {j: active.index(i) for j, i in result.assignment.items()
              if result.variable_association[j] is None}
    solved_vars = [{j for j in result.equation_vars[i] if j in solved} for i in active]
    blocks = block_lower_triangular(solved_vars, solved)
    unknowns = sorted(solved)
    column = {j: k for k, j in enumerate(unknowns)}
    return {"blocks": [[result.equation_names[active[i]] for i in block] for block in blocks],
            "blt": blt_view([{column[j] for j in vs} for vs in solved_vars],
                            {column[j]: i for j, i in solved.items()}, blocks,
                            [result.equation_names[i] for i in active],
                            [variable_name(result.variables[j]) for j in unknowns])}


def structure_text(report: dict) -> str:
    """A structure report (:func:`structure_report`) as the lines ``study structure``
    prints: variables, incidence matrix, matching, reduction steps, maps, BLT blocks."""
    lines = [f"Structural analysis: {report['example']} (equations and variables numbered "
             f"from 1)",
             "variables: " + ", ".join(f"{j + 1}:{name}" for j, name in
                                       enumerate(report["variables"]))]
    if "known" in report:
        lines.append(f"known: {report['known']}")
    lines.append("incidence matrix (rows equations, columns variables):")
    lines += [f"  {name:>4s} {row}" for name, row in zip(report["equations"], report["incidence"])]
    lines += matching_lines(report)
    lines.append("reduction steps:")
    lines += [f"  {step}" for step in report["steps"]]
    if "vmap" in report:
        lines += pantelides_lines(report)
    lines.append("blocks (BLT order): " + "  ".join(
        "[" + ", ".join(str(e) for e in block) + "]" for block in report["blocks"]))
    return "\n".join(lines)


def matching_lines(report: dict) -> list[str]:
    """The matching as ModiaBase's assign list with the document's beside it, or the
    highest derivatives' matching and the equations it leaves unmatched."""
    if "assign" in report:
        orders = report["augmenting_path_assign"]
        return [f"matching (variable -> equation, 0 = known): assign = {report['assign']}",
                f"document 000's assign = {report['document_assign']}: perfect matching "
                f"{report['document_assign_is_perfect_matching']}, blocks "
                f"{report['document_assign_blocks']}",
                "both are perfect matchings of the loop f1-f4 (an 8-cycle has two); "
                + "; ".join(f"AUGMENTPATH scanning variables {order}: {found}"
                            for order, found in orders.items())]
    return ["matching of the highest derivatives: " + ", ".join(
                f"{v} -> {e}" for v, e in report["initial_matching"].items()),
            f"unmatched equations: {', '.join(report['unmatched_equations']) or 'none'}"]


def pantelides_lines(report: dict) -> list[str]:
    """vmap, eqmap, the assignment, the differentiations and the structural index."""
    lines = [f"{key}: " + ", ".join(f"{a} -> {b}" for a, b in report[key].items())
             for key in ("vmap", "eqmap", "assignment")]
    lines.append("differentiated: " + ", ".join(f"{name} x{count}" for name, count in
                                                report["differentiations"].items()))
    lines.append(f"{report['n_equations']} equations in {report['n_variables']} variables; "
                 f"structural index {report['structural_index']}")
    return lines


def variable_symbol(variable: Variable) -> sp.Symbol:
    """The plain symbol standing for a variable once derivatives are replaced: named as
    printed (x, x', lambda, ...)."""
    return sp.Symbol(variable_name(variable))


def symbolic_equation(expression: sp.Expr, variables: Sequence[Variable],
                      symbols: dict[int, sp.Symbol] | Sequence[sp.Symbol],
                      t: sp.Symbol = sp.Symbol("t")) -> sp.Expr:
    """A residual in functions of t with every variable (function at a derivative order,
    ``variables[j]``) replaced by ``symbols[j]``: an algebraic expression."""
    replacements = {}
    for j, (name, order) in enumerate(variables):
        function = sp.Function(name)(t)
        node = sp.Derivative(function, (t, order)) if order else function
        replacements[node] = symbols[j]
    return sp.sympify(expression).xreplace(replacements)
