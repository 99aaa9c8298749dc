"""The matched-accuracy helpers of bench/bench_contact_mujoco.py (no MuJoCo needed): each
side's cheapest setting that holds a target, the robust choice (every finer step holds it
too), the stability line, and the two error measures against closed forms."""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))

from bench_contact_mujoco import G, Run, cheapest, rising_apex, robust_choice, slip, stability  # noqa: E402
from timing import Timing  # noqa: E402


def runs(family: str, errors: dict[float, float], k: float = 1e-3) -> list[Run]:
    """A family whose cost is k / step (s) and whose errors are given per step."""
    return [Run("x", family, step, error, Timing(k / step, k / step)) for step, error in errors.items()]


#: not monotone in the step, as MuJoCo's apex error: 2 ms holds 1 %, 1 ms does not
BUMPY = runs("bumpy", {5e-3: 12.0, 2e-3: -0.2, 1e-3: 5.7, 5e-4: 2.4})
#: monotone: holds 1 % from 2.5 ms down
STEADY = runs("steady", {5e-3: 1.4, 2.5e-3: 0.9, 1e-3: 0.3, 5e-4: 0.2}, k=2e-3)


def test_cheapest_takes_the_least_cpu_time_that_holds_the_target():
    # bumpy at 2 ms costs 0.5 s, steady at 2.5 ms 0.8 s: bumpy's lucky step wins
    assert cheapest(BUMPY + STEADY, 1.0) is BUMPY[1]
    assert cheapest(STEADY, 1.0) is STEADY[1]
    assert cheapest(BUMPY, 0.1) is None


def test_the_robust_choice_needs_every_finer_step_to_hold():
    assert robust_choice(BUMPY + STEADY, 1.0) is STEADY[1]
    assert robust_choice(BUMPY, 1.0) is None
    assert robust_choice(BUMPY, 10.0) is BUMPY[1]  # 12 % at 5 ms misses: 2 ms and finer hold 10 %
    # holding only at the finest step swept is no evidence: nothing finer was tried
    assert robust_choice(runs("last", {1e-3: 3.0, 5e-4: 0.5}), 1.0) is None


def test_diverged_runs_never_hold_a_target():
    diverged = Run("x", "steady", 1e-2, math.inf, Timing(math.nan, math.nan))
    assert cheapest([diverged], 1e9) is None
    assert robust_choice([diverged, *STEADY], 1.0) is STEADY[1]


def test_stability_names_the_neighbouring_steps():
    line = stability(BUMPY, BUMPY[1], 1.0)
    assert "dt=0.002: -0.2" in line and "dt=0.001: +5.7" in line and "dt=0.005: +12" in line
    assert line.endswith("(0 of 2 hold)")


def test_rising_apex_of_a_sampled_throw():
    t = np.linspace(0.0, 0.5, 37)
    v0 = 3.0  # m/s upwards from z = 0.1 m: apex 0.1 + v0^2 / 2g, whichever rising sample
    z, vz = 0.1 + v0 * t - G * t ** 2 / 2, v0 - G * t
    assert rising_apex(z, vz) == pytest.approx(0.1 + v0 ** 2 / (2 * G), rel=1e-12)


def test_slip_is_measured_from_the_window_start():
    t = np.arange(1, 101) / 100.0
    z = -0.003 * t  # sliding down at 3 mm/s: 0.75 s x 3 mm/s from 0.25 s to 1 s
    assert slip(t, z) == pytest.approx(0.00225, rel=1e-12)
