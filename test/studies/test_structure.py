"""Structural analysis against the seed's worked examples (benchmarks.md section 6)."""
from __future__ import annotations

import itertools
import random

import pytest
import sympy as sp

from youbot_dynamics.errors import UserInputError
from youbot_dynamics.studies.structure import (LOWPASS_INCIDENCE, block_lower_triangular,
                                               cartesian_pendulum_equations, incidence,
                                               maximum_matching, pantelides, structure_report)

LOWPASS = [{j - 1 for j in vs} for vs in LOWPASS_INCIDENCE]
UNKNOWNS = [0, 1, 2, 3, 5, 6]          # variable 5 (index 4) is the known state


def test_lowpass_matching_is_perfect_and_valid():
    matching = maximum_matching(LOWPASS, UNKNOWNS)
    assert sorted(matching.values()) == list(range(6))
    assert all(j in LOWPASS[i] and j != 4 for j, i in matching.items())


@pytest.mark.parametrize("source", ["networkx", "seed"])
def test_lowpass_blocks_are_the_seeds(source):
    # The seed's assign = [2, 6, 3, 1, 0, 5, 4] (variable -> equation, 1-based, 0 known).
    seed = {j: i - 1 for j, i in enumerate([2, 6, 3, 1, 0, 5, 4]) if i}
    matching = seed if source == "seed" else maximum_matching(LOWPASS, UNKNOWNS)
    blocks = block_lower_triangular(LOWPASS, matching)
    assert [[i + 1 for i in b] for b in blocks] == [[6], [1, 2, 3, 4], [5]]


def test_lowpass_report_gives_a_perfect_matching_and_the_seeds_blocks():
    # Matchings are not unique (the seed's [2, 6, 3, 1, 0, 5, 4] is one of several);
    # the blocks are.
    report = structure_report("lowpass")
    assign = report["assign"]
    assert assign[4] == 0 and sorted(assign[:4] + assign[5:]) == [1, 2, 3, 4, 5, 6]
    assert all(j + 1 in LOWPASS_INCIDENCE[i - 1] for j, i in enumerate(assign) if i)
    assert report["blocks"] == [[6], [1, 2, 3, 4], [5]]


def test_blt_respects_dependencies_on_random_systems():
    rng = random.Random(3)
    for _ in range(30):
        n = rng.randint(3, 9)
        perm = list(range(n))
        rng.shuffle(perm)
        eq_vars = [{perm[i]} | {rng.randrange(n) for _ in range(rng.randint(0, 3))}
                   for i in range(n)]
        matching = maximum_matching(eq_vars)
        assert len(matching) == n
        blocks = block_lower_triangular(eq_vars, matching)
        position = {i: k for k, block in enumerate(blocks) for i in block}
        assert sorted(position) == list(range(n))
        for i, variables in enumerate(eq_vars):
            for j in variables:           # solved in the same block or an earlier one
                assert position[matching[j]] <= position[i]
        for block in blocks:              # each block is irreducible: brute force
            if len(block) > 1:
                for size in range(1, len(block)):
                    for subset in itertools.combinations(block, size):
                        needed = {matching[j] for i in subset for j in eq_vars[i]}
                        assert not needed <= set(subset)


def test_pendulum_pantelides_matches_seed():
    t = sp.Symbol("t")
    equations, names = cartesian_pendulum_equations(t)
    result = pantelides(equations, t, names, ("x", "y", "u", "v", "lambda"))
    assert result.vmap() == {"x": "x'", "y": "y'", "u": "u'", "v": "v'", "x'": "x''",
                             "y'": "y''"}
    assert result.eqmap() == {"f5": "f6", "f6": "f7", "f1": "f8", "f2": "f9"}
    assert result.assignment_names() == {"x'": "f1", "y'": "f2", "u'": "f8", "v'": "f4",
                                         "lambda": "f3", "x''": "f7", "y''": "f9"}
    assert result.differentiations == {"f1": 1, "f2": 1, "f5": 2}
    assert (len(result.equations), len(result.variables)) == (9, 11)
    assert result.structural_index == 3
    x, y = sp.Function("x")(t), sp.Function("y")(t)
    assert sp.simplify(result.equations[5] - (2 * x * x.diff(t) + 2 * y * y.diff(t))) == 0
    assert sp.simplify(result.equations[6] - (2 * x * x.diff(t, 2) + 2 * x.diff(t)**2
                                              + 2 * y * y.diff(t, 2)
                                              + 2 * y.diff(t)**2)) == 0


def test_index_one_and_ode_systems_need_no_differentiation():
    t = sp.Symbol("t")
    x, z = sp.Function("x")(t), sp.Function("z")(t)
    index1 = pantelides([x.diff(t) + x - z, z - x**2], t)
    assert index1.differentiations == {} and index1.structural_index == 1
    ode = pantelides([x.diff(t) + x], t)
    assert ode.structural_index == 0


def test_structurally_singular_system_is_an_error():
    t = sp.Symbol("t")
    x, z = sp.Function("x")(t), sp.Function("z")(t)
    with pytest.raises(UserInputError, match="structurally singular"):
        pantelides([x.diff(t) - z, x + 1, x - 2], t, max_steps=5)


def test_incidence_ignores_parameters_and_separates_orders():
    t, k = sp.symbols("t k")
    x = sp.Function("x")(t)
    variables, eq_vars = incidence([k * x.diff(t, 2) + x], t)
    assert variables == [("x", 0), ("x", 1), ("x", 2)]
    assert eq_vars == [{0, 2}]


def test_squeezer_structural_index_three():
    report = structure_report("squeezer")
    assert report["structural_index"] == 3
    differentiated = report["differentiations"]
    assert all(differentiated[f"f{i}"] == 2 for i in range(15, 21))   # g, twice
    assert all(differentiated[f"f{i}"] == 1 for i in range(1, 8))     # q' = v, once
    assert not any(f"f{i}" in differentiated for i in range(8, 15))   # M v' = ...
    assert (report["n_equations"], report["n_variables"]) == (39, 41)


@pytest.mark.parametrize("example", ["lowpass", "pendulum", "squeezer"])
def test_blt_view_is_block_lower_triangular_with_the_matching_on_its_diagonal(example):
    """Every entry of the permuted matrix lies on or below its row's diagonal block, the
    diagonal is the matching, and it is the same incidence, rows and columns reordered."""
    report = structure_report(example)
    view = report["blt"]
    rows = [[k for k, cell in enumerate(row) if cell == "x"] for row in view["incidence"]]
    end, block_end = 0, []
    for size in view["block_sizes"]:
        end += size
        block_end += [end] * size
    assert len(rows) == end == len(view["rows"])
    assert all(max(columns) < block_end[r] for r, columns in enumerate(rows))
    assert all(r in columns for r, columns in enumerate(rows))
    assert sorted(view["columns"]) == sorted(set(view["columns"]))
    if example == "lowpass":  # the given incidence, permuted
        original = {f"f{i + 1}": {str(j) for j in vs} for i, vs in enumerate(LOWPASS_INCIDENCE)}
        permuted = {name: {view["columns"][k] for k in columns}
                    for name, columns in zip(view["rows"], rows)}
        assert permuted == original
