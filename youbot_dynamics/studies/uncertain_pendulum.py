"""The uncertainty study (document 000, section 3): the damped pendulum with uncertain parameters,
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

Where the two standard deviations part (accuracy/propagation.py's FAILURE_RATIO and
FAILURE_FLOOR), linearisation has failed. Measured (N = 1000, random seed 0): they agree to the first swing's end and part at
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

from youbot_dynamics.accuracy.propagation import (FAILURE_FLOOR, FAILURE_RATIO, Propagation,
                                                  comparison)
from youbot_dynamics.errors import UserInputError

GRAVITY = 9.81
#: name -> (nominal value, standard deviation), SI.
PARAMETERS = {"L": (0.8, 0.2), "m": (1.0, 0.2), "d": (0.5, 0.2)}
PHI0, W0 = 1.57, 0.0
T_END = 10.0
#: RK4 step (s) and output interval (s).
STEP, OUTPUT_EVERY = 0.01, 0.05


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


@dataclass(frozen=True)
class UncertaintyConfig:
    """The study's settings: Monte Carlo ``samples`` and their random ``seed``, the
    simulated ``duration`` (s), where the samples run (``workers``: processes of a local
    Dask cluster, 0 serial; ``scheduler``: a cluster's address)."""

    samples: int = 1000
    seed: int = 0
    duration: float = T_END
    workers: int | None = None
    scheduler: str | None = None


@dataclass
class UncertaintyResult:
    """Both propagations of phi (rad), the Monte Carlo's traces ((outputs, samples)) and
    the comparison's figures (accuracy.propagation.comparison)."""

    config: UncertaintyConfig
    linear: Propagation
    sampled: Propagation
    phi: np.ndarray
    figures: dict


def run(config: UncertaintyConfig) -> UncertaintyResult:
    """Linear propagation against the Monte Carlo over [0, duration]."""
    if config.samples < 2:
        raise UserInputError(f"--samples must be at least 2, got {config.samples}")
    linear = linear_propagation(config.duration)
    sampled, phi = monte_carlo(config.samples, config.duration, config.seed,
                               workers=config.workers, scheduler=config.scheduler)
    return UncertaintyResult(config, linear, sampled, phi, comparison(linear, sampled))


def as_json(result: UncertaintyResult) -> dict:
    """The comparison's figures with the samples and their random seed."""
    return {**result.figures, "samples": result.config.samples, "seed": result.config.seed}


def text(result: UncertaintyResult) -> str:
    """The study's figures as lines of text."""
    figures, config = result.figures, result.config
    fails = figures["linearisation_fails_at"]
    return "\n".join([
        f"Damped pendulum, L = 0.8 +- 0.2 m, m = 1 +- 0.2 kg, d = 0.5 +- 0.2 N m s/rad, "
        f"phi0 = 1.57 rad; RK4 h = 0.01 s; linear propagation (uncertainties) against "
        f"{config.samples} Monte Carlo samples (seed {config.seed})",
        f"at t = {figures['t_end']:g} s: sigma(phi) linear {figures['sigma_linear_end']:.4g} "
        f"rad, Monte Carlo {figures['sigma_monte_carlo_end']:.4g} rad (2-sigma bands "
        f"{figures['band_width_linear_end']:.4g} and {figures['band_width_monte_carlo_end']:.4g}"
        f" rad wide); means differ by {figures['mean_difference_end']:.3g} rad",
        f"sigma_linear / sigma_MC ranges over [{figures['min_ratio']:.3g}, "
        f"{figures['max_ratio']:.3g}]; linearisation fails (beyond +-{FAILURE_RATIO:.0%} "
        f"and {FAILURE_FLOOR:g} rad) "
        + ("nowhere" if fails is None else f"first at t = {fails:g} s"),
        f"wall time: linear {figures['wall_time_linear']:.3g} s, Monte Carlo "
        f"{figures['wall_time_monte_carlo']:.3g} s"])
