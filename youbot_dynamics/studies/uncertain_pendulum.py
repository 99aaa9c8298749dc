"""The uncertainty study (seed 000, item 5): the damped pendulum with uncertain parameters,
L = 0.8 +- 0.2 m, m = 1.0 +- 0.2 kg, d = 0.5 +- 0.2 N m s/rad (independent, one standard
deviation), g = 9.81 m/s^2, phi(0) = 1.57 rad, w(0) = 0:

    phi' = w,   m L^2 w' = -d w - m g L sin(phi).

Two propagations of the same fixed-step RK4 map (h = STEP):

- linear: the ``uncertainties`` package (Measurements.jl's counterpart) carries every
  number as a value with its first-order derivatives to L, m and d through the RK4
  arithmetic, so sigma(phi(t)) is the exact linearisation of the discrete map;
- Monte Carlo: N Gaussian parameter samples, those with L <= 0, m <= 0 or d < 0 drawn
  again (a negative damping, 2.5 sigma away, would feed the swing until it turns over and
  spins, which no physical pendulum does), integrated side by side as arrays.

Where the two standard deviations part (FAILURE_RATIO, FAILURE_FLOOR), linearisation has
failed. Measured (N = 1000, seed 0): they agree to the first swing's end and part at
t = 0.85 s; then the samples dephase (the period depends on L) and the linear sigma
oscillates with the nominal swing, up to 2.0x the Monte Carlo's near t = 5 s, down to
0.35x at t = 10 s (0.049 rad against 0.142 rad). Relative to each other they differ from
the start (0.74x at t = 0.05 s: g / L is far from linear over L = 0.8 +- 25 %), but
there the spread itself is a few mrad.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from youbot_dynamics.errors import UserInputError

GRAVITY = 9.81
#: name -> (nominal value, standard deviation), SI.
PARAMETERS = {"L": (0.8, 0.2), "m": (1.0, 0.2), "d": (0.5, 0.2)}
PHI0, W0 = 1.57, 0.0
T_END = 10.0
#: RK4 step (s) and output interval (s).
STEP, OUTPUT_EVERY = 0.01, 0.05
#: Linearisation counts as failed where |sigma_linear - sigma_MonteCarlo| exceeds both
#: FAILURE_RATIO sigma_MonteCarlo (its own sampling error is about 1/sqrt(2 N), 2.2 % at
#: N = 1000) and FAILURE_FLOOR (rad; tiny early spreads differ relatively but not visibly).
FAILURE_RATIO, FAILURE_FLOOR = 0.2, 0.02


def pendulum_rhs(phi, w, length, mass, damping, sin: Callable):
    """(phi', w') for plain floats, arrays or uncertain numbers (``sin`` to match)."""
    return w, -damping * w / (mass * length * length) - GRAVITY / length * sin(phi)


def rk4(phi, w, parameters, sin: Callable, t_end: float, step: float, every: int,
        after_step: Callable | None = None):
    """Fixed-step RK4 from (phi, w); returns the (phi, w) pairs every ``every`` steps,
    the initial one first. ``after_step(phi, w)`` is called after every step."""
    n_steps = int(round(t_end / step))
    out = [(phi, w)]
    for n in range(1, n_steps + 1):
        k1 = pendulum_rhs(phi, w, *parameters, sin)
        k2 = pendulum_rhs(phi + 0.5 * step * k1[0], w + 0.5 * step * k1[1], *parameters, sin)
        k3 = pendulum_rhs(phi + 0.5 * step * k2[0], w + 0.5 * step * k2[1], *parameters, sin)
        k4 = pendulum_rhs(phi + step * k3[0], w + step * k3[1], *parameters, sin)
        phi = phi + step / 6.0 * (k1[0] + 2.0 * (k2[0] + k3[0]) + k4[0])
        w = w + step / 6.0 * (k1[1] + 2.0 * (k2[1] + k3[1]) + k4[1])
        if after_step is not None:
            after_step(phi, w)
        if n % every == 0:
            out.append((phi, w))
    return out


@dataclass
class Propagation:
    """Mean and standard deviation of phi (rad) at the times t (s)."""

    method: str
    t: np.ndarray
    mean: np.ndarray
    sigma: np.ndarray
    wall_time: float


def output_times(t_end: float) -> tuple[np.ndarray, int]:
    """Output times and the steps between them."""
    every = int(round(OUTPUT_EVERY / STEP))
    return np.arange(int(round(t_end / STEP)) // every + 1) * OUTPUT_EVERY, every


def flatten(*numbers) -> None:
    """Make the ``uncertainties`` numbers expand their derivatives now: their lazily built
    linear combinations share sub-expressions, and expanding many steps at once walks every
    path through them (exponential in the number of steps)."""
    for number in numbers:
        number.derivatives


def linear_propagation(t_end: float = T_END, parameters=PARAMETERS) -> Propagation:
    """sigma(phi) by the ``uncertainties`` package through the RK4 arithmetic."""
    import time

    from uncertainties import ufloat, umath
    start = time.perf_counter()
    uncertain = [ufloat(value, sigma, tag=name) for name, (value, sigma) in parameters.items()]
    times, every = output_times(t_end)
    states = rk4(PHI0, W0, uncertain, umath.sin, t_end, STEP, every, flatten)
    phi = [state[0] for state in states]
    mean = np.array([getattr(p, "nominal_value", p) for p in phi])
    sigma = np.array([getattr(p, "std_dev", 0.0) for p in phi])
    return Propagation("linear", times, mean, sigma, time.perf_counter() - start)


def parameter_samples(n: int, seed: int = 0, parameters=PARAMETERS) -> np.ndarray:
    """(n, 3) Gaussian samples of (L, m, d); rows with L <= 0, m <= 0 or d < 0 drawn
    again."""
    if n < 2:
        raise UserInputError(f"the Monte Carlo needs at least 2 samples, got {n}")
    rng = np.random.default_rng(seed)
    means = np.array([value for value, _ in parameters.values()])
    sigmas = np.array([sigma for _, sigma in parameters.values()])
    samples = rng.normal(means, sigmas, size=(n, 3))
    while True:
        bad = (samples[:, 0] <= 0) | (samples[:, 1] <= 0) | (samples[:, 2] < 0)
        if not bad.any():
            return samples
        samples[bad] = rng.normal(means, sigmas, size=(int(bad.sum()), 3))


def sample_traces(samples: np.ndarray, t_end: float) -> np.ndarray:
    """phi (rad) of each parameter sample (rows L, m, d) at the output times, ((outputs,
    n)): the samples integrated side by side as arrays."""
    n = len(samples)
    _, every = output_times(t_end)
    states = rk4(np.full(n, PHI0), np.full(n, W0), tuple(samples.T), np.sin, t_end, STEP,
                 every)
    return np.array([state[0] for state in states])


#: Samples per case when the Monte Carlo runs on Dask (the split does not change phi).
SAMPLES_PER_CASE = 250


def monte_carlo(n: int = 1000, t_end: float = T_END, seed: int = 0,
                parameters=PARAMETERS, *, workers: int | None = 0,
                scheduler: str | None = None) -> tuple[Propagation, np.ndarray]:
    """Sample mean and standard deviation (ddof 1) of phi over n parameter samples, and
    phi of every sample at the output times ((outputs, n)). The samples run in blocks of
    SAMPLES_PER_CASE as cases of youbot_dynamics.accuracy.sweeps.map_cases (serial with
    ``workers=0``, the default; a local Dask cluster or the one at ``scheduler``)."""
    import time

    from youbot_dynamics.accuracy.sweeps import map_cases
    start = time.perf_counter()
    samples = parameter_samples(n, seed, parameters)
    times, _ = output_times(t_end)
    blocks = np.array_split(samples, max(1, -(-n // SAMPLES_PER_CASE)))
    phi = np.hstack(map_cases(sample_traces, [(block, t_end) for block in blocks],
                              workers=workers, scheduler=scheduler, desc="Monte Carlo",
                              progress=False))
    return (Propagation("monte_carlo", times, phi.mean(axis=1), phi.std(axis=1, ddof=1),
                        time.perf_counter() - start), phi)


def comparison(linear: Propagation, sampled: Propagation) -> dict:
    """Figures of the study: both sigmas and 2-sigma band widths at the end, the range of
    sigma_linear / sigma_MonteCarlo, and the first time (s) where they part by more than
    FAILURE_RATIO and FAILURE_FLOOR (None if never)."""
    ratio = np.divide(linear.sigma, sampled.sigma, out=np.ones_like(linear.sigma),
                      where=sampled.sigma > 0)
    gap = np.abs(linear.sigma - sampled.sigma)
    failed = np.flatnonzero((gap > FAILURE_RATIO * sampled.sigma) & (gap > FAILURE_FLOOR))
    return {"t_end": float(linear.t[-1]),
            "sigma_linear_end": float(linear.sigma[-1]),
            "sigma_monte_carlo_end": float(sampled.sigma[-1]),
            "band_width_linear_end": float(2.0 * linear.sigma[-1]),
            "band_width_monte_carlo_end": float(2.0 * sampled.sigma[-1]),
            "mean_difference_end": float(linear.mean[-1] - sampled.mean[-1]),
            "min_ratio": float(np.min(ratio)), "max_ratio": float(np.max(ratio)),
            "linearisation_fails_at": float(linear.t[failed[0]]) if failed.size else None,
            "wall_time_linear": linear.wall_time,
            "wall_time_monte_carlo": sampled.wall_time}


PENDULUM_TITLE = "Damped pendulum, L = 0.8 +- 0.2, m = 1 +- 0.2, d = 0.5 +- 0.2"


def plot_uncertainty(linear: Propagation, sampled: Propagation, phi_samples: np.ndarray,
                     path: str, title: str = PENDULUM_TITLE, quantity: str = "phi (rad)") -> None:
    """PNG: the quantity (default the pendulum's phi) with the +-sigma bands of both
    propagations and 30 sample traces; below, the two sigmas over time."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, (top, bottom) = plt.subplots(2, 1, figsize=(9, 8), sharex=True)
    top.plot(sampled.t, phi_samples[:, :30], color="grey", linewidth=0.3, alpha=0.6)
    for result, color in ((linear, "tab:blue"), (sampled, "tab:orange")):
        top.plot(result.t, result.mean, color=color, label=f"{result.method} mean")
        top.fill_between(result.t, result.mean - result.sigma, result.mean + result.sigma,
                         color=color, alpha=0.25, label=f"{result.method} +-1 sigma")
        bottom.plot(result.t, result.sigma, color=color, label=result.method)
    top.set_ylabel(quantity)
    top.set_title(f"{title}; {phi_samples.shape[1]} samples", fontsize=10)
    bottom.set_ylabel(f"sigma of {quantity}")
    bottom.set_xlabel("t (s)")
    for axis in (top, bottom):
        axis.grid(True, alpha=0.3)
        axis.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
