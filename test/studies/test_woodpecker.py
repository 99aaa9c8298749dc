"""The woodpecker toy: equations as benchmarks.md section 2 writes them, impacts, the
contact-force sign along the run, and the seed's 22 beak hits over 2 s."""
from __future__ import annotations

import numpy as np
import pytest

from youbot_dynamics.studies.woodpecker import (BEAK, BLOCK_II, BLOCK_III, SEED_BEAK_HITS,
                                                SEED_INITIAL_STATE, Woodpecker,
                                                WoodpeckerParameters)

P = WoodpeckerParameters()
WOODPECKER = Woodpecker(P)


@pytest.fixture(scope="module")
def dense_run():
    return WOODPECKER.simulate(2.0, "dop853", rtol=1e-8, atol=1e-10, n_out=8000)


def benchmark_rows(mode: str, x: np.ndarray):
    """Unknowns (z'', phiS'', phiB'', lambda1, lambda2): the rows exactly as written in
    benchmarks.md (M q'' = right-hand side, plus the index-1 constraints)."""
    phiS, phiB = x[1], x[2]
    M = np.array([[P.mS + P.mB, P.mB * P.lS, P.mB * P.lG],
                  [P.mB * P.lS, P.JS + P.mB * P.lS ** 2, P.mB * P.lS * P.lG],
                  [P.mB * P.lG, P.mB * P.lS * P.lG, P.JB + P.mB * P.lG ** 2]])
    rhs = np.array([-(P.mS + P.mB) * P.g, P.cp * (phiB - phiS) - P.mB * P.lS * P.g,
                    P.cp * (phiS - phiB) - P.mB * P.lG * P.g])
    K = np.zeros((5, 5))
    K[:3, :3] = M
    # moving the lambda terms to the left: row1 + lambda2; row2 +- hS lambda1 + rS lambda2
    K[0, 4] = 1.0
    K[1, 3] = P.hS if mode == "II" else -P.hS
    K[1, 4] = P.rS
    K[3, 1] = 1.0                 # phiS'' = 0
    K[4, 0], K[4, 1] = 1.0, P.rS  # z'' + rS phiS'' = 0
    return np.linalg.solve(K, np.concatenate([rhs, [0.0, 0.0]]))


@pytest.mark.parametrize("mode", ["II", "III"])
def test_blocked_modes_solve_the_benchmark_equations(mode):
    x = np.array([0.01, 0.1, -0.3, 0.0, 0.0, 2.0])
    expected = benchmark_rows(mode, x)
    A, b, _, _ = WOODPECKER.affine_modes[mode]
    np.testing.assert_allclose((A @ x + b)[3:], expected[:3], rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(WOODPECKER.constraint_forces(mode, x), expected[3:],
                               rtol=1e-12)


def test_seed_initial_state_is_a_compressive_contact():
    """The seed's resting state II has lambda1 < 0 (seed: -0.628993 from a static guess
    with phiB'' = 0; the index-1 form, with the bird accelerating, gives -0.6911)."""
    lambda1, _ = WOODPECKER.constraint_forces("II", np.array(SEED_INITIAL_STATE))
    assert lambda1 == pytest.approx(-0.69113, abs=1e-5)
    # and the free acceleration would push the sleeve through its lower stop
    A, b, _, _ = WOODPECKER.affine_modes["I"]
    assert (A @ np.array(SEED_INITIAL_STATE) + b)[4] < 0


def test_blocking_is_a_plastic_impact_keeping_the_bird_momentum(dense_run):
    M = WOODPECKER.mass_matrix
    blocks = [s for s in dense_run.switches if s.kind in (BLOCK_II, BLOCK_III)]
    assert len(blocks) >= 2 * SEED_BEAK_HITS
    for switch in blocks:
        before, after = switch.state_before[3:], switch.state_after[3:]
        # the seed's angular momentum expression for phiB' after the impact
        momentum = P.mB * P.lG * before[0] + P.mB * P.lS * P.lG * before[1] \
            + (P.JB + P.mB * P.lG ** 2) * before[2]
        assert after[2] == pytest.approx(momentum / (P.JB + P.mB * P.lG ** 2), rel=1e-13)
        # independently: M (v+ - v-) = G^T Lambda, G v+ = 0
        G = WOODPECKER.constraint_jacobian(switch.mode_after)
        K = np.block([[M, -G.T], [G, np.zeros((2, 2))]])
        v_plus = np.linalg.solve(K, np.concatenate([M @ before, [0.0, 0.0]]))[:3]
        np.testing.assert_allclose(after, v_plus, atol=1e-12 * np.abs(before).max())
        np.testing.assert_array_equal(switch.state_after[:3], switch.state_before[:3])
        assert abs(switch.state_before[1]) == pytest.approx(WOODPECKER.stop_angle(), rel=1e-9)


def test_beak_hits_reverse_the_bird_at_the_bar(dense_run):
    for switch in (s for s in dense_run.switches if s.kind == BEAK):
        assert switch.state_before[2] == pytest.approx(WOODPECKER.beak_angle(), abs=1e-12)
        assert switch.state_before[5] > 0
        assert switch.state_after[5] == -switch.state_before[5]
        assert switch.mode_before == switch.mode_after == "III"


def test_contact_force_never_keeps_the_wrong_sign(dense_run):
    """In a blocked mode, once lambda1 is compressive (< 0) it stays so until the mode is
    left: a tensile lambda1 lasts at most one event tolerance. The one exception is the
    seed's own: right after a blocking impact lambda1 starts tensile (it is affine in phiB
    alone) and the seed's rules hold the contact until it changes sign."""
    t, modes = dense_run.t, np.array(dense_run.mode)
    switch_at = {s.time: s for s in dense_run.switches}
    lam1 = np.array([WOODPECKER.constraint_forces(m, x)[0] for m, x in zip(modes, dense_run.x)])
    tolerance = 1e-9  # N, against |lambda1| up to 0.69 N
    blocked = modes != "I"
    edges = np.flatnonzero(np.diff(np.concatenate([[0], blocked.astype(int), [0]])))
    tensile_entries = []
    for start, stop in zip(edges[::2], edges[1::2]):
        segment = lam1[start:stop]
        compressive = np.flatnonzero(segment <= tolerance)
        assert compressive.size, f"blocked at t={t[start]:.6f} s without contact force"
        first = compressive[0]
        if first > 0:  # tensile at entry: only right after a blocking impact
            assert switch_at[t[start]].kind in (BLOCK_II, BLOCK_III)
            tensile_entries.append(t[start + first] - t[start])
        later = segment[first:]
        assert np.all(later <= tolerance), \
            f"tensile lambda1={later.max():.3g} N in {modes[start]} at t={t[start]:.6f} s"
    assert max(tensile_entries) < 3e-3


@pytest.mark.parametrize("integrator", ["dop853", "cvode_bdf", "ida"])
def test_hit_count_is_the_seeds_and_stable_under_tolerance(integrator):
    counts = {rtol: WOODPECKER.simulate(2.0, integrator, rtol=rtol, atol=rtol * 1e-2).count(BEAK)
              for rtol in (1e-6, 1e-8)}
    assert counts == {1e-6: SEED_BEAK_HITS, 1e-8: SEED_BEAK_HITS}


def test_command_line_reports_the_hits_and_rejects_a_fixed_step_run_without_dt(capsys):
    import json

    from youbot_dynamics.cli import main
    assert main(["study", "woodpecker", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["beak_hits"] == SEED_BEAK_HITS
    assert sum(s["kind"] == BEAK for s in report["switches"]) == SEED_BEAK_HITS
    assert report["stats"]["events"] >= len(report["switches"])
    assert main(["study", "woodpecker", "--integrator", "rk4"]) == 2
    assert "--dt" in capsys.readouterr().err


@pytest.mark.parametrize("rtol", ["1e-4", "1e-6", "1e-8"])
def test_command_line_ida_gives_the_seeds_hits_at_every_tolerance(rtol, capsys):
    """`woodpecker --integrator ida` (which once handed Brent's method an interval without
    a sign change on the interpolant) at the acceptance tolerances."""
    import json

    from youbot_dynamics.cli import main
    assert main(["study", "woodpecker", "--integrator", "ida", "--rtol", rtol, "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["beak_hits"] == SEED_BEAK_HITS
