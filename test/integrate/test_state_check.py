"""StateCheck.step (integrate/drive.py): its compiled pass for float64 states against numpy's
reading of the same checks (every entry finite, |x_i| <= bound_i), and the errors it names."""
from __future__ import annotations

import numpy as np
import pytest

from youbot_dynamics.integrate.drive import StateCheck, finite_within
from youbot_dynamics.integrate.errors import DivergenceError

NAMES = tuple(f"x{i}" for i in range(6))


def numpy_passes(x: np.ndarray, bounds: np.ndarray | None) -> bool:
    return bool(np.all(np.isfinite(x)) and (bounds is None or not np.any(np.abs(x) > bounds)))


def test_compiled_pass_agrees_with_numpy():
    rng, bounds = np.random.default_rng(4), np.array([1.0, 2.0, np.inf, 0.5, 3.0, np.nan])
    specials = [np.nan, np.inf, -np.inf, 1e308, -0.0, 2.0, 0.5000001]
    passed = failed = 0
    for _ in range(3000):
        x = rng.normal(0.0, 1.0, 6)
        x[rng.integers(6)] = specials[rng.integers(len(specials))]
        for b in (bounds, None):
            expected = numpy_passes(x, b)
            assert finite_within(x, np.empty(0) if b is None else b) == expected
            passed, failed = passed + expected, failed + (not expected)
    assert passed > 1000 and failed > 1000  # both outcomes exercised


@pytest.mark.parametrize("bounds", [None, 10.0, [10.0, 10.0, 10.0, 10.0, 10.0, 1.0]])
def test_step_passes_and_names_what_fails(bounds):
    check = StateCheck("rk4", NAMES, bounds, None)
    # without bounds: x.sum() overflows, yet all finite passes
    x = np.array([0.5, -2.0, 3.0, 1e308 if bounds is None else 9.0, 1e308 if bounds is None else -9.0, 0.25])
    frozen = x.copy()
    frozen.setflags(write=False)
    for state in (x, x[::-1].copy()[::-1], frozen, np.repeat(x, 2)[::2]):
        check.step(1.0, state, 0.01)
    if bounds is None:
        return
    with pytest.raises(DivergenceError, match="non-finite state") as error:
        check.step(1.0, np.where(np.arange(6) == 2, np.nan, 0.0), 0.01)
    assert list(error.value.components) == ["x2"]
    with pytest.raises(DivergenceError, match="outside its bounds") as error:
        check.step(1.0, np.array([0.0, 0.0, 0.0, 0.0, 0.0, 20.0]), 0.01)
    assert list(error.value.components) == ["x5"]
    with pytest.raises(DivergenceError, match="outside its bounds"):  # numpy's path for float32
        check.step(1.0, np.array([0.0, 0.0, 0.0, 0.0, 0.0, 20.0], dtype=np.float32), 0.01)
