"""Two propagations of parameter uncertainty compared: a linear one (first-order
sensitivities) against a Monte Carlo over the same output times.

:class:`Propagation` holds the mean and standard deviation of one output over time;
:func:`comparison` gives the figures both users print (studies/uncertain_pendulum.py: the
damped pendulum of equations; accuracy/scene_uncertainty.py: a scene's ``value ± sigma``
parameters), and :func:`plot_uncertainty` draws the two bands and the sigmas. Where the
two standard deviations part by more than FAILURE_RATIO of the Monte Carlo's and
FAILURE_FLOOR (in the output's unit), linearisation has failed.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Linearisation counts as failed where |sigma_linear - sigma_MonteCarlo| exceeds both
#: FAILURE_RATIO sigma_MonteCarlo (its own sampling error is about 1/sqrt(2 N), 2.2 % at
#: N = 1000) and FAILURE_FLOOR (the output's unit, rad for the pendulum; tiny early spreads
#: differ relatively but not visibly).
FAILURE_RATIO, FAILURE_FLOOR = 0.2, 0.02


@dataclass
class Propagation:
    """Mean and standard deviation of the output (rad for the pendulum's phi) at the
    times t (s); ``method`` 'linear' or 'monte_carlo'; ``wall_time`` in s."""

    method: str
    t: np.ndarray
    mean: np.ndarray
    sigma: np.ndarray
    wall_time: float


def comparison(linear: Propagation, sampled: Propagation) -> dict:
    """Figures of the comparison: both sigmas and 2-sigma band widths at the end, the range
    of sigma_linear / sigma_MonteCarlo, and the first time (s) where they part by more than
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


def plot_uncertainty(linear: Propagation, sampled: Propagation, samples: np.ndarray,
                     path: str, title: str, quantity: str) -> None:
    """PNG at ``path``: the quantity (label with its unit, e.g. 'phi (rad)') with the
    +-sigma bands of both propagations and 30 of the sample traces ((outputs, n)); below,
    the two sigmas over time (s)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, (top, bottom) = plt.subplots(2, 1, figsize=(9, 8), sharex=True)
    top.plot(sampled.t, samples[:, :30], color="grey", linewidth=0.3, alpha=0.6)
    for result, color in ((linear, "tab:blue"), (sampled, "tab:orange")):
        top.plot(result.t, result.mean, color=color, label=f"{result.method} mean")
        top.fill_between(result.t, result.mean - result.sigma, result.mean + result.sigma,
                         color=color, alpha=0.25, label=f"{result.method} +-1 sigma")
        bottom.plot(result.t, result.sigma, color=color, label=result.method)
    top.set_ylabel(quantity)
    top.set_title(f"{title}; {samples.shape[1]} samples", fontsize=10)
    bottom.set_ylabel(f"sigma of {quantity}")
    bottom.set_xlabel("t (s)")
    for axis in (top, bottom):
        axis.grid(True, alpha=0.3)
        axis.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
