"""The equal-accuracy helpers of bench/bench_contact_mujoco.py (no MuJoCo needed): the wall
time at a target error on log-log lines with a known answer, and the two error measures
against closed forms."""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))

from bench_contact_mujoco import G, Run, rising_apex, slip, wall_at_error  # noqa: E402


def first_order(method: str, steps: list[float], c: float = 2.0, k: float = 1e-3) -> list[Run]:
    """A method with error c h and wall time k / h: at error e the wall time is k c / e."""
    return [Run("x", method, f"h={h:g}", c * h, k / h) for h in steps]


def test_wall_at_error_interpolates_on_the_log_log_line():
    runs = first_order("a", [1e-2, 1e-3, 1e-4])
    # target 5e-4 lies between h = 1e-3 (error 2e-3) and 1e-4 (2e-4): wall k c / e = 4 s
    assert wall_at_error(runs, 5e-4) == pytest.approx(4.0, rel=1e-12)
    # the cheapest run already meets it: its own wall time, nothing to interpolate against
    assert wall_at_error(runs, 0.1) == pytest.approx(0.1, rel=1e-12)
    assert wall_at_error(runs, 1e-5) is None


def test_wall_at_error_takes_the_cheapest_method_and_skips_sign_changes():
    cheap = first_order("cheap", [1e-2, 1e-3, 1e-4], k=1e-4)
    # the run meeting 1e-3 follows a miss of the other sign: its wall time, not interpolated
    crossing = [Run("x", "crossing", "1", -5e-3, 1e-3), Run("x", "crossing", "2", 5e-4, 2e-3)]
    assert wall_at_error(first_order("dear", [1e-2, 1e-3, 1e-4]) + cheap, 5e-4) == pytest.approx(0.4, rel=1e-12)
    assert wall_at_error(crossing, 1e-3) == 2e-3
    assert wall_at_error(cheap + crossing, 1e-3) == 2e-3  # cheap would need k c / e = 0.2 s
    # a diverged run (infinite error, no wall time) never meets a target nor bounds one
    diverged = Run("x", "cheap", "h=0.05", math.inf, math.nan)
    assert wall_at_error([diverged], 1.0) is None
    assert wall_at_error([diverged, *cheap], 5e-4) == pytest.approx(0.4, rel=1e-12)


def test_rising_apex_of_a_sampled_throw():
    t = np.linspace(0.0, 0.5, 37)
    v0 = 3.0  # m/s upwards from z = 0.1 m: apex 0.1 + v0^2 / 2g, whichever rising sample
    z, vz = 0.1 + v0 * t - G * t ** 2 / 2, v0 - G * t
    assert rising_apex(z, vz) == pytest.approx(0.1 + v0 ** 2 / (2 * G), rel=1e-12)


def test_slip_is_measured_from_the_window_start():
    t = np.arange(1, 101) / 100.0
    z = -0.003 * t  # sliding down at 3 mm/s: 0.75 s x 3 mm/s from 0.25 s to 1 s
    assert slip(t, z) == pytest.approx(0.00225, rel=1e-12)
